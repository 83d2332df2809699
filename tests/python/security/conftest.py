"""Fixtures of the secured client tests: they need a cyclonedds binding whose libddsc has the DDS
Security plugins (``.venv-secure``, made by scripts/setup.sh); under the pip wheel of ``.venv`` they
are skipped. The server side and the process helpers are the service tests' (real processes,
unique domains, torn down even on failure)."""

from __future__ import annotations

import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Sequence

import pytest

from surfeledit.security import security_available

from service.conftest import REPO, ManagedProcess, free_domain, server_executable  # noqa: F401
from surfeledit.server_process import server_args

def pytest_report_header(config: pytest.Config) -> str:
    return ("secured client tests: on (this binding's libddsc has the DDS Security plugins)" if security_available()
            else "secured client tests: skipped (no DDS Security plugins in this cyclonedds binding; use .venv-secure)")


@pytest.fixture(scope="session")
def security_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A demo setup (scripts/make_security.py): server; alice, bob, carol and dave permitted (each
    writes requests in "surfeledit.req.<user>" and reads replies only in its own partitions); mallory with a valid identity but no surfeledit permission; eve
    with permissions signed by her own CA."""
    if shutil.which("openssl") is None:
        pytest.skip("openssl not installed (Debian package openssl)")
    out = tmp_path_factory.mktemp("security")
    subprocess.run([sys.executable, str(REPO / "scripts" / "make_security.py"), str(out),
                    "--clients", "alice,bob,carol,dave", "--denied", "mallory", "--rogue", "eve"],
                   check=True, capture_output=True, text=True, timeout=120)
    return out


class SecuredServer(ManagedProcess):
    def __init__(self, domain: int, log: Path, security: Path, extra: Sequence[str] = ()) -> None:
        self.domain = domain
        super().__init__([server_executable()] + server_args(domain, None) + ["--security", str(security)]
                         + list(extra), log)

    def wait_ready(self, timeout: float = 30.0) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if not self.alive:
                pytest.fail(f"surfeledit-server exited with {self.proc.returncode}:\n{self.log_tail()}")
            if "ready on domain" in self.log_tail(100_000):
                return
            time.sleep(0.05)
        pytest.fail(f"surfeledit-server not ready within {timeout} s:\n{self.log_tail()}")


@pytest.fixture
def secured_server(request: pytest.FixtureRequest, tmp_path: Path, security_dir: Path) -> SecuredServer:
    """A surfeledit-server with --security (the demo's server identity) on a fresh domain."""
    srv = SecuredServer(free_domain(), tmp_path / "server.log", security_dir / "server" / "security.conf")
    request.addfinalizer(srv.stop)
    srv.wait_ready()
    return srv
