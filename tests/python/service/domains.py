"""DDS domains that no two processes use at once: tests, the fuzzer and benchmarks take one here.

Each domain id has a lock file (``surfeledit-dds-domains/<id>.lock`` in the system temp dir); taking the
domain is an exclusive ``fcntl.flock`` on it, held until :func:`release` or until the process exits
(the kernel drops the lock then, even after a crash). A domain whose lock another process (a
pytest-xdist worker, a second pytest run, a benchmark) holds is skipped: the next id is tried. The
search starts at an offset that varies with the pid, so that processes rarely contend for the same ids.
Locks are per open file, so two takes in one process get different domains too.
"""

from __future__ import annotations

import fcntl
import os
import tempfile
from pathlib import Path
from typing import Dict, List

__all__ = ["FIRST", "LAST", "LOCK_DIR", "take", "release", "release_all", "held"]

#: The domain ids handed out (Cyclone DDS accepts 0..232; 0 is the default domain of anything else).
FIRST, LAST = 1, 230
LOCK_DIR = Path(tempfile.gettempdir()) / "surfeledit-dds-domains"

_held: Dict[int, int] = {}  # domain -> file descriptor holding its lock


def _try_lock(domain: int) -> bool:
    LOCK_DIR.mkdir(parents=True, exist_ok=True)
    fd = os.open(LOCK_DIR / f"{domain}.lock", os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:  # another process (or another take of this one) holds it
        os.close(fd)
        return False
    _held[domain] = fd
    return True


def take() -> int:
    """A domain in FIRST..LAST that this process now holds exclusively; raises RuntimeError if all are held."""
    count = LAST - FIRST + 1
    start = (os.getpid() * 37) % count
    for i in range(count):
        domain = FIRST + (start + i) % count
        if domain not in _held and _try_lock(domain):
            return domain
    raise RuntimeError(f"every DDS domain {FIRST}..{LAST} is held by some process (locks in {LOCK_DIR})")


def release(domain: int) -> None:
    """Gives ``domain`` back (no-op when this process does not hold it)."""
    fd = _held.pop(domain, None)
    if fd is not None:
        os.close(fd)  # closing the only descriptor of the open file drops its lock


def release_all() -> None:
    """Gives back every domain this process holds."""
    for domain in list(_held):
        release(domain)


def held() -> List[int]:
    """The domains this process holds, in the order taken."""
    return list(_held)
