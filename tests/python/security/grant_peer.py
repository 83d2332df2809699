"""A secured client in a process of its own (one identity per process) that joins a session without
a token, relying on a role the server granted its user (--grant):

    python grant_peer.py CONF DOMAIN SESSION ZERO

Prints ``key=value`` lines: ``join`` (``ok`` or the error class), then, when joined, ``surfels``
(what it read), ``regions`` (its tool: surfels below ZERO fixed, the rest moving; ``ok`` or the
error class), ``deform`` (``ok:<version>`` or the error class) and ``version`` (after them).
"""

from __future__ import annotations

import sys

import numpy as np

import surfeledit


def main() -> int:
    conf, domain, session, zero = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
    with surfeledit.connect(domain, security=conf, timeout=15) as client:
        try:
            s = client.join_session(session)
        except surfeledit.SurfelEditError as e:
            print(f"join={type(e).__name__}", flush=True)
            return 0
        print("join=ok", flush=True)
        n = len(s.positions())
        print(f"surfels={n}", flush=True)
        try:
            s.set_regions(zero=np.arange(zero), one=np.arange(zero, n))
            print("regions=ok", flush=True)
        except surfeledit.SurfelEditError as e:
            print(f"regions={type(e).__name__}", flush=True)
        try:
            print(f"deform=ok:{s.deform(translation=(0.0, 0.0, -0.01)).version}", flush=True)
        except surfeledit.SurfelEditError as e:
            print(f"deform={type(e).__name__}", flush=True)
        s.info()
        print(f"version={s.version}", flush=True)
        s.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
