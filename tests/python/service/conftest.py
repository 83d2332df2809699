"""Fixtures that run REAL surfeledit-server processes, one per test on its own DDS domain.

The server comes from env ``SURFELEDIT_SERVER`` (scripts/test.sh sets it), falling back to
``<repo>/build/server/app/surfeledit-server``; tests that need it are skipped when it does not exist.
Every started process is stopped by a finalizer (SIGTERM, then SIGKILL) even when the test fails.
"""

from __future__ import annotations

import contextlib
import glob
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable, Iterator, List, Optional, Sequence, Tuple

import numpy as np
import pytest
from cyclonedds.core import DDSException
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic

import surfeledit
from surfeledit._protocol import TOPIC_REQUEST, proto, request_qos
from surfeledit.dds_status import publication_matched
from surfeledit.demo import default_scene
from surfeledit.server_process import server_args

from . import domains

REPO = Path(__file__).resolve().parents[3]


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "large: big data round trips (1M surfels, ~tens of seconds)")


def domain_in_use(domain: int, wait: float = 0.3) -> bool:
    """True if something on ``domain`` already serves the surfeledit or echo topics (a stray server
    would answer our requests too, so tests must not share its domain), or if no participant can join it
    (Cyclone could not bind one of the domain's ports: "address in use", seen once in CI)."""
    try:
        dp = DomainParticipant(domain)
    except DDSException:
        return True
    try:
        endpoints = [DataWriter(dp, Topic(dp, TOPIC_REQUEST, proto.Request), qos=request_qos()),
                     DataWriter(dp, Topic(dp, "echo_in_Request", proto.Request), qos=request_qos())]
        deadline = time.monotonic() + wait
        while time.monotonic() < deadline:
            if any(publication_matched(w) for w in endpoints):  # either cyclonedds binding
                return True
            time.sleep(0.005)
        return False
    finally:
        dp.__del__()  # deletes the participant and its children now


def free_domain() -> int:
    """A DDS domain that this process holds (domains.py: no other process gets it until the test ends)
    and on which nothing answers yet (a stray server that takes no lock would answer our requests too)."""
    for _ in range(20):
        d = domains.take()
        if not domain_in_use(d):
            return d  # a domain in use stays held until the test ends, so the next try takes another
    raise RuntimeError("no free DDS domain found in 20 tries")


@pytest.fixture(autouse=True)
def _domains_for_the_test() -> Iterator[None]:
    """Gives back, at the end of each test, the domains it took (free_domain)."""
    before = set(domains.held())
    yield
    for d in domains.held():
        if d not in before:
            domains.release(d)


def find_executable(env: str, *candidates: str) -> Optional[str]:
    value = os.environ.get(env)
    if value and os.path.isfile(value):
        return value
    for pattern in candidates:
        hits = sorted(glob.glob(str(REPO / pattern), recursive=True))
        for h in hits:
            if os.access(h, os.X_OK):
                return h
    return None


def server_executable() -> str:
    exe = find_executable("SURFELEDIT_SERVER", "build/server/app/surfeledit-server",
                          "build*/server/app/surfeledit-server")
    if exe is None:
        pytest.skip("surfeledit-server not built (set SURFELEDIT_SERVER or build into build/server/app)")
    return exe


class ManagedProcess:
    """A child process with its log file; ``stop()`` is idempotent and always reaps it."""

    def __init__(self, argv: List[str], log: Path) -> None:
        self.argv = argv
        self.log = log
        with open(log, "wb") as out:
            self.proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT,
                                         start_new_session=True)

    @property
    def alive(self) -> bool:
        return self.proc.poll() is None

    def log_tail(self, n: int = 3000) -> str:
        try:
            return self.log.read_text(errors="replace")[-n:]
        except OSError:
            return ""

    def wait_ready(self, timeout: float = 30.0, text: str = "ready on domain") -> None:
        """Until the log holds `text` (a server writes "ready on domain" once it serves, after any journal
        recovery); fails the test if the process exits first or the time runs out."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if not self.alive:
                pytest.fail(f"{Path(self.argv[0]).name} exited with {self.proc.returncode}:\n{self.log_tail()}")
            if text in self.log_tail(100_000):
                return
            time.sleep(0.01)
        pytest.fail(f"{Path(self.argv[0]).name} not ready within {timeout} s:\n{self.log_tail()}")

    def stop(self, grace: float = 5.0) -> Optional[int]:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=grace)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        return self.proc.returncode


class SecuredServer(ManagedProcess):
    """A surfeledit-server with ``--security CONFIG`` (none: a plain one, the control case), no data root."""

    def __init__(self, domain: int, log: Path, security: Optional[Path], extra: Sequence[str] = ()) -> None:
        self.domain = domain
        flags = ["--security", str(security)] if security else []
        super().__init__([server_executable()] + server_args(domain, None) + flags + list(extra), log)

    @classmethod
    def started(cls, request: pytest.FixtureRequest, tmp_path: Path, security: Optional[Path],
                extra: Sequence[str] = ()) -> "SecuredServer":
        """One on a fresh domain, stopped at the test's teardown whatever happens, ready to answer."""
        srv = cls(free_domain(), tmp_path / "server.log", security, extra)
        request.addfinalizer(lambda: domains.release(srv.domain))  # after the stop (finalizers run last first)
        request.addfinalizer(srv.stop)
        srv.wait_ready()
        return srv


class ServerProcess(ManagedProcess):
    def __init__(self, exe: str, domain: int, log: Path, data_root: Optional[Path] = None,
                 extra: Tuple[str, ...] = ()) -> None:
        self.domain = domain
        self.data_root = data_root
        super().__init__([exe] + server_args(domain, data_root) + list(extra), log)


@pytest.fixture
def server(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[ServerProcess]:
    """A running surfeledit-server on a fresh domain, loading files from ``tmp_path / "data-root"``
    (``--data-root``; the ``data_root`` fixture); killed at teardown whatever happens."""
    exe = server_executable()
    domain = free_domain()
    root = tmp_path / "data-root"
    root.mkdir(exist_ok=True)
    srv = ServerProcess(exe, domain, tmp_path / f"server-{domain}.log", root)
    request.addfinalizer(srv.stop)
    yield srv
    assert srv.alive, f"surfeledit-server died during the test:\n{srv.log_tail()}"


@pytest.fixture
def start_server(tmp_path: Path) -> Iterator[Callable[..., ServerProcess]]:
    """Starts servers on fresh domains with extra command-line options (``start_server("--client-lease-ms",
    "500")``, no data root); every one is stopped at teardown."""
    started: List[ServerProcess] = []

    def start(*options: str) -> ServerProcess:
        domain = free_domain()
        srv = ServerProcess(server_executable(), domain, tmp_path / f"server-{domain}.log", None, options)
        started.append(srv)
        return srv

    yield start
    for srv in started:
        srv.stop()


def connect_to(srv: ServerProcess, timeout: float = 20.0) -> surfeledit.Client:
    """Connects (spawn=False) to ``srv``, retrying while it starts up."""
    deadline = time.monotonic() + timeout
    last: Optional[Exception] = None
    while time.monotonic() < deadline:
        if not srv.alive:
            pytest.fail(f"surfeledit-server exited with {srv.proc.returncode}:\n{srv.log_tail()}")
        try:
            return surfeledit.connect(domain=srv.domain, spawn=False, timeout=10.0)
        except surfeledit.ServerStartError as e:
            last = e
    pytest.fail(f"surfeledit-server on domain {srv.domain} did not answer within {timeout} s ({last}):\n"
                f"{srv.log_tail()}")


@pytest.fixture
def data_root(server: ServerProcess) -> Path:
    """The directory the ``server`` fixture's server may load files from (``--data-root``)."""
    assert server.data_root is not None
    return server.data_root


@pytest.fixture
def make_client(server: ServerProcess) -> Iterator[Callable[[], surfeledit.Client]]:
    """Factory of extra clients of ``server`` (all closed at teardown)."""
    clients: List[surfeledit.Client] = []

    def make() -> surfeledit.Client:
        c = connect_to(server)
        clients.append(c)
        return c

    yield make
    for c in clients:
        c.close()


@pytest.fixture
def client(make_client: Callable[[], surfeledit.Client]) -> surfeledit.Client:
    """A client connected (spawn=False) to this test's server."""
    return make_client()


Scene = Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def generated_scene(spacing: float = 0.05) -> Scene:
    """positions (P, 3), normals (P, 3), radii (P,), part (P,) (0 slab, 1 sphere) of the demo scene."""
    return default_scene(spacing)


@pytest.fixture
def scene() -> Scene:
    return generated_scene()


PEER = Path(__file__).with_name("peer_process.py")


@contextlib.contextmanager
def uploading_peer(domain: int, **job: object) -> Iterator[subprocess.Popen]:
    """A client in its own process (peer_process.py "upload", with ``job``: session, token, total, chunks,
    chunk) that joined and sent its chunks; killed (SIGKILL) and reaped on exit if it still runs."""
    peer = subprocess.Popen([sys.executable, str(PEER), "upload", str(domain), json.dumps(job)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        line = peer.stdout.readline() if peer.stdout else ""
        assert json.loads(line or "{}").get("ready"), peer.stderr.read() if peer.stderr else ""
        yield peer
    finally:
        if peer.poll() is None:
            peer.kill()
        peer.wait()
