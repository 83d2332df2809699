#!/usr/bin/env python3
"""How fast dead peers are noticed, and what a client's first request costs (issue 12, leases).

Run (after scripts/setup.sh; needs build/server/app/surfeledit-server):
    .venv/bin/python bench/service/bench_leases.py [--build-dir build] [--runs 5] [--lease-ms 2000]

What is measured (seconds, wall clock, time.monotonic), each --runs times on a fresh DDS domain:
  detach      a client process (the real Python client) joins a session with an editor token, begins an
              upload and sends one chunk, then gets SIGKILL; the owner polls OP_INFO every 50 ms until
              the session reports one client and no upload memory. Expected: about the client's
              liveliness lease (1 s) + --client-lease-ms.
  gone        the server gets SIGKILL; the client's next request raises ServerGoneError after this long
              (expected: up to the server's 1 s liveliness lease).
  first_ms    a fresh client's first OP_INFO round trip once the server's request reader is matched (the
              server makes the client's reply writer, in its partition, and the client's reader must
              discover it) against its next ten (next_ms, median).
Medians and ranges are printed with the machine load (uptime).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Dict, List

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "client_py"))
sys.path.insert(0, str(ROOT / "tests" / "python"))

import surfeledit  # noqa: E402
from surfeledit import errors  # noqa: E402

from service.conftest import free_domain  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import connect_when_up  # noqa: E402

PEER = ROOT / "tests" / "python" / "service" / "peer_process.py"


def start_server(exe: str, domain: int, *options: str) -> subprocess.Popen:
    log = tempfile.NamedTemporaryFile(prefix="bench-leases-", suffix=".log", delete=False)
    return subprocess.Popen([exe, "--domain", str(domain), *options], stdout=log, stderr=subprocess.STDOUT,
                            start_new_session=True)




def one_run(exe: str, lease_ms: int) -> Dict[str, float]:
    domain = free_domain()
    srv = start_server(exe, domain, "--client-lease-ms", str(lease_ms))
    connect_when_up(domain, 20).close()  # the server is up
    owner = surfeledit.Client(domain)
    try:
        if not owner.wait_for_server(10.0):
            raise RuntimeError("server not discovered")
        t0 = time.monotonic()
        owner.info()  # this client's first request: its reply writer is made now
        first_ms = (time.monotonic() - t0) * 1e3
        later = []
        for _ in range(10):
            t0 = time.monotonic()
            owner.info()
            later.append((time.monotonic() - t0) * 1e3)
        s = owner.open_session("bench")
        token = s.invite("editor")
        peer = subprocess.Popen([sys.executable, str(PEER), "upload", str(domain), json.dumps(
            dict(session="bench", token=token, total=100_000, chunks=1, chunk=5000))],
            stdout=subprocess.PIPE, text=True, start_new_session=True)
        assert peer.stdout is not None and json.loads(peer.stdout.readline())["ready"]
        peer.send_signal(signal.SIGKILL)
        killed = time.monotonic()
        peer.wait()
        while True:
            info = owner.info()
            if info.upload_bytes == 0 and s.info().clients == 1:
                break
            if time.monotonic() - killed > 30:
                raise RuntimeError("client not detached within 30 s")
            time.sleep(0.05)
        detach = time.monotonic() - killed
        os.kill(srv.pid, signal.SIGKILL)
        srv.wait()
        killed = time.monotonic()
        try:
            owner.info()
            raise RuntimeError("a request to a killed server returned")
        except errors.ServerGoneError:
            gone = time.monotonic() - killed
        return dict(detach=detach, gone=gone, first_ms=first_ms, next_ms=statistics.median(later))
    finally:
        owner.close()
        if srv.poll() is None:
            srv.kill()
            srv.wait()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build-dir", default=str(ROOT / "build"))
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--lease-ms", type=int, default=2000)
    args = ap.parse_args()
    exe = str(Path(args.build_dir) / "server" / "app" / "surfeledit-server")
    print("load before:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    runs: List[Dict[str, float]] = [one_run(exe, args.lease_ms) for _ in range(args.runs)]
    for key, unit in (("detach", "s"), ("gone", "s"), ("first_ms", "ms"), ("next_ms", "ms")):
        values = [r[key] for r in runs]
        print(f"{key:9s} median {statistics.median(values):8.3f} {unit}  range {min(values):.3f} .. "
              f"{max(values):.3f} {unit}  ({len(values)} runs, lease {args.lease_ms} ms)")
    print("load after:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())


if __name__ == "__main__":
    main()
