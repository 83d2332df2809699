"""What the service benchmarks share: starting a server process and connecting to it."""

from __future__ import annotations

import contextlib
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Iterator, Optional

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


@contextlib.contextmanager
def served_client(exe: Path, log_prefix: str) -> Iterator[surfeledit.Client]:
    """A client of surfeledit-server `exe` started on a free DDS domain (its output in a temporary log); the client
    is closed, the server stopped and the log removed on leaving, whatever happens."""
    from service.conftest import free_domain  # the benches put tests/python on sys.path

    domain = free_domain()
    log = Path(tempfile.mkstemp(prefix=log_prefix, suffix=".log")[1])
    srv = start_server(exe, domain, None, log)
    try:
        client = connect_when_up(domain)
        try:
            yield client
        finally:
            client.close()
    finally:
        srv.terminate()
        srv.wait(timeout=30)
        log.unlink(missing_ok=True)
