"""Fixtures of the secured client tests: they need a cyclonedds binding whose libddsc has the DDS
Security plugins (``.venv-secure``, made by scripts/setup.sh); under the pip wheel of ``.venv`` they
are skipped. The server side and the process helpers are the service tests' (real processes,
unique domains, torn down even on failure)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from surfeledit.security import security_available

from service.conftest import REPO, SecuredServer

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


@pytest.fixture
def secured_server(request: pytest.FixtureRequest, tmp_path: Path, security_dir: Path) -> SecuredServer:
    """A surfeledit-server with --security (the demo's server identity) on a fresh domain."""
    return SecuredServer.started(request, tmp_path, security_dir / "server" / "security.conf")
