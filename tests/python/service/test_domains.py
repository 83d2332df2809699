"""domains.py: two processes (or two takes in one) never hold the same DDS domain; a domain comes back
when its holder releases it or exits. Real processes and real lock files, no DDS."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import List

from . import domains

_HOLDER = """
import sys
sys.path.insert(0, {path!r})
from service import domains
print(" ".join(str(domains.take()) for _ in range({count})), flush=True)
sys.stdin.readline()  # holds them until told to go
"""


def holders(n: int, count: int) -> List[subprocess.Popen]:
    code = _HOLDER.format(path=str(Path(__file__).resolve().parents[1]), count=count)
    return [subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
            for _ in range(n)]


def stop(procs: List[subprocess.Popen]) -> None:
    for p in procs:
        if p.poll() is None:
            p.stdin.close()  # type: ignore[union-attr]
            p.wait(timeout=10)


def test_processes_never_share_a_domain() -> None:
    """4 processes take 5 domains each at the same time, this one 2 more: 22 different ids, each held."""
    procs = holders(4, 5)
    try:
        mine = [domains.take(), domains.take()]
        taken = [int(d) for p in procs for d in p.stdout.readline().split()]  # type: ignore[union-attr]
        assert len(taken) == 20
        everything = taken + mine
        assert len(set(everything)) == len(everything)
        assert all(domains.FIRST <= d <= domains.LAST for d in everything)
        assert mine == domains.held()[-2:]
    finally:
        stop(procs)
        for d in mine:
            domains.release(d)


def test_a_domain_comes_back_when_its_holder_exits_or_releases_it() -> None:
    procs = holders(1, 1)
    try:
        theirs = int(procs[0].stdout.readline())  # type: ignore[union-attr]
        assert not domains._try_lock(theirs)  # held by the other process
    finally:
        stop(procs)
    assert domains._try_lock(theirs)  # it exited: the kernel dropped its lock
    domains.release(theirs)
    assert theirs not in domains.held()
    assert domains._try_lock(theirs)
    domains.release(theirs)
