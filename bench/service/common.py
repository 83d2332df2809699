"""What the service benchmarks share: starting a server process and connecting to it."""

from __future__ import annotations

import subprocess
import time
from pathlib import Path
from typing import Optional

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


def start_server(exe: Path, domain: int, security: Optional[Path], log: Path) -> subprocess.Popen:
    """surfeledit-server `exe` on DDS `domain` (with `--security CONFIG` when given), its output in `log`;
    returns once it logged that it serves (RuntimeError if it exits first or takes over 60 s)."""
    args = [str(exe), "--domain", str(domain)] + (["--security", str(security)] if security else [])
    with log.open("w") as f:
        srv = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=f, stderr=subprocess.STDOUT)
    deadline = time.monotonic() + 60
    while "ready on domain" not in log.read_text():
        if srv.poll() is not None or time.monotonic() > deadline:
            raise RuntimeError(f"surfeledit-server did not start:\n{log.read_text()[-2000:]}")
        time.sleep(0.05)
    return srv
