"""What the service benchmarks share: connecting to a server process they started themselves."""

from __future__ import annotations

import time

import surfeledit


def connect_when_up(domain: int, within_s: float = 30.0) -> surfeledit.Client:
    """A client of the server on DDS `domain`, retried until the server answers or `within_s` seconds pass
    (then the last ServerStartError is raised)."""
    deadline = time.monotonic() + within_s
    while True:
        try:
            return surfeledit.connect(domain=domain, spawn=False, timeout=10.0)
        except surfeledit.ServerStartError:
            if time.monotonic() > deadline:
                raise
