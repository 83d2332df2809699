"""DDS Security on (`surfeledit-server --security`, proto/PROTOCOL.md "Security"), against real
server processes and C++ participants (surfeledit-secure-probe links Debian's libddsc, which has the
security plugins; the Python client's wheel does not).

Certificates and signed documents are made once per module by scripts/make_security.py in a temp
dir: server, alice (permitted client), mallory (valid identity, permissions without surfeledit's
topics), eve (valid identity, permissions signed by her own CA); a second setup gives a "stranger"
(a permitted client of other CAs). An "outsider" participant has no security at all. The control test runs the same outsider against a server without security, where
it does get in: the probe can see what security prevents.
"""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
import sys
import time
from pathlib import Path
from types import ModuleType
from typing import Dict, List, Optional

import pytest

from .conftest import REPO, ManagedProcess, SecuredServer, find_executable, server_executable

def probe_executable() -> str:
    exe = find_executable("SURFELEDIT_SECURE_PROBE", "build/tests/surfeledit-secure-probe",
                          "build*/tests/surfeledit-secure-probe")
    if exe is None:
        pytest.skip("surfeledit-secure-probe not built (set SURFELEDIT_SECURE_PROBE)")
    return exe


@pytest.fixture(scope="module")
def security_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    if shutil.which("openssl") is None:
        pytest.skip("openssl not installed (Debian package openssl)")
    out = tmp_path_factory.mktemp("security")
    subprocess.run([sys.executable, str(REPO / "scripts" / "make_security.py"), str(out),
                    "--clients", "alice", "--denied", "mallory", "--rogue", "eve"],
                   check=True, capture_output=True, text=True, timeout=120)
    return out


@pytest.fixture(scope="module")
def stranger_dir(tmp_path_factory: pytest.TempPathFactory, security_dir: Path) -> Path:
    """A second, unrelated setup: its users' identities and permissions are signed by other CAs."""
    out = tmp_path_factory.mktemp("stranger")
    subprocess.run([sys.executable, str(REPO / "scripts" / "make_security.py"), str(out),
                    "--clients", "alice", "--denied", "", "--rogue", ""],
                   check=True, capture_output=True, text=True, timeout=120)
    return out


def make_security_module() -> ModuleType:
    """scripts/make_security.py as a module: its permission documents and topic lists, for variants of them."""
    spec = importlib.util.spec_from_file_location("make_security", REPO / "scripts" / "make_security.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def probe_denied_conf(security_dir: Path) -> Path:
    """The server's identity with permissions that are the server's minus reading surfeledit_reply (the
    one-server-per-domain probe), signed by the same permissions CA; its security.conf beside the server's,
    so the relative paths of the CAs and the governance stay valid."""
    ms = make_security_module()
    d = security_dir / "server-probe-denied"
    d.mkdir()
    for name in ("cert.pem", "key.pem", "security.conf"):
        shutil.copy(security_dir / "server" / name, d / name)
    subscribe = [t for t in ms.TOPICS_SERVER_SUBSCRIBES if t != "surfeledit_reply"]
    assert subscribe and len(subscribe) < len(ms.TOPICS_SERVER_SUBSCRIBES)
    domains = (0, 230)  # make_security.py's default --domains, which the security_dir fixture uses
    (d / "permissions.xml").write_text(ms.permissions_xml("server", ms.TOPICS_SERVER_PUBLISHES, subscribe,
                                                          domains, days=1))
    ca = security_dir / "ca"
    ms.sign(d / "permissions.xml", ca / "permissions_ca.pem", ca / "permissions_ca.key")
    return d / "security.conf"


PROBE_FALLBACK_LOG = "cannot look for another server on domain"


def parse(out: str) -> Dict[str, List[str]]:
    values: Dict[str, List[str]] = {}
    for line in out.splitlines():
        key, sep, value = line.partition("=")
        if sep:
            values.setdefault(key, []).append(value)
    return values


def start_probe(args: List[str], log: Path) -> ManagedProcess:
    return ManagedProcess([probe_executable()] + args, log)


def finish(p: ManagedProcess, timeout: float) -> Dict[str, List[str]]:
    try:
        p.proc.wait(timeout=timeout)
    finally:
        p.stop()
    return parse(p.log.read_text(errors="replace"))


def client_args(domain: int, conf: Optional[Path], client_id: str, session: str, steps: int = 3) -> List[str]:
    args = ["client", "--domain", str(domain), "--client-id", client_id, "--session", session,
            "--surfels", "2000", "--steps", str(steps), "--timeout-s", "15"]
    return args + (["--security", str(conf)] if conf else [])


def intruder_args(domain: int, conf: Optional[Path], victim: str, session: str, seconds: float) -> List[str]:
    args = ["intruder", "--domain", str(domain), "--victim", victim, "--session", session, "--seconds", str(seconds)]
    return args + (["--security", str(conf)] if conf else [])


def test_permitted_client_works_end_to_end(request: pytest.FixtureRequest, tmp_path: Path,
                                           security_dir: Path) -> None:
    srv = SecuredServer.started(request, tmp_path, security_dir / "server" / "security.conf")
    p = start_probe(client_args(srv.domain, security_dir / "alice" / "security.conf", "alice.1", "secured"),
                    tmp_path / "alice.log")
    out = finish(p, 60)
    assert p.proc.returncode == 0, p.log_tail()
    for op in ("open", "load_begin", "load_chunk", "load_commit", "set_regions", "configure", "close"):
        assert out[op] == ["0"], (op, p.log_tail())
    assert out["deform"] == ["0"] * 3 and len(out["step_ms"]) == 3
    # The commit's full update and one per step reached alice's update reader.
    assert int(out["updates"][0]) >= 4, p.log_tail()
    assert srv.alive, srv.log_tail()
    assert PROBE_FALLBACK_LOG not in srv.log_tail(100_000)  # its permissions let it probe the domain


def test_server_without_probe_permission_falls_back_and_serves(request: pytest.FixtureRequest, tmp_path: Path,
                                                               security_dir: Path, probe_denied_conf: Path) -> None:
    """A server whose permissions do not let it read surfeledit_reply cannot create the domain probe's reader:
    it logs that it cannot look for another server, starts without the check and serves a permitted client."""
    srv = SecuredServer.started(request, tmp_path, probe_denied_conf)
    log = srv.log_tail(100_000)
    assert f"{PROBE_FALLBACK_LOG} {srv.domain}" in log, log
    assert log.index(PROBE_FALLBACK_LOG) < log.index("ready on domain"), log
    p = start_probe(client_args(srv.domain, security_dir / "alice" / "security.conf", "alice.1", "unprobed", steps=1),
                    tmp_path / "alice.log")
    out = finish(p, 60)
    assert p.proc.returncode == 0, p.log_tail()
    for op in ("open", "load_begin", "load_chunk", "load_commit", "set_regions", "configure", "deform", "close"):
        assert out[op] == ["0"], (op, p.log_tail())
    assert int(out["updates"][0]) >= 2, p.log_tail()  # the commit's full update and the step's
    assert srv.alive, srv.log_tail()


def test_unauthenticated_and_unpermitted_participants_are_shut_out(request: pytest.FixtureRequest, tmp_path: Path,
                                                                   security_dir: Path, stranger_dir: Path) -> None:
    srv = SecuredServer.started(request, tmp_path, security_dir / "server" / "security.conf")
    victim, session = "alice.victim", "taken"  # a client id of alice's (her reply partitions)
    intruders = {
        "outsider": None,  # no security at all
        "stranger": stranger_dir / "alice" / "security.conf",  # a permitted client of another CA pair
        "mallory": security_dir / "mallory" / "security.conf",  # identity ok, no surfeledit permission
        "eve": security_dir / "eve" / "security.conf",  # identity ok, permissions signed by her own CA
    }
    procs = {name: start_probe(intruder_args(srv.domain, conf, victim, session, 8.0), tmp_path / f"{name}.log")
             for name, conf in intruders.items()}
    for p in procs.values():
        request.addfinalizer(p.stop)
    time.sleep(3.0)  # the intruders have been writing as the victim and reading for 3 s
    # Had any intruder request reached the server, the victim's id would be bound to that writer (its
    # requests then get no reply) and the session name taken (OPEN: STATUS_CONFLICT).
    alice = start_probe(client_args(srv.domain, security_dir / "alice" / "security.conf", victim, session),
                        tmp_path / "alice.log")
    out = finish(alice, 60)
    assert alice.proc.returncode == 0 and out["open"] == ["0"], alice.log_tail()
    assert out["deform"] == ["0"] * 3
    for name, p in procs.items():
        got = finish(p, 30)
        assert p.proc.returncode == 0, (name, p.log_tail())
        # Nothing read: no reply of the victim's or its own partition, no update of alice's session.
        assert got["replies_read"] == ["0"] and got["updates_read"] == ["0"], (name, p.log_tail())
        # Nothing written: no server endpoint ever matched its writer or readers.
        assert got["matched_servers"] == ["0"], (name, p.log_tail())
    outsider, mallory, eve = (parse(procs[n].log.read_text()) for n in ("outsider", "mallory", "eve"))
    # The outsider, the stranger and eve did write (to nobody); mallory could not even create the writer.
    stranger = parse(procs["stranger"].log.read_text())
    assert int(outsider["written"][0]) > 0 and int(eve["written"][0]) > 0 and int(stranger["written"][0]) > 0
    assert mallory["writer"] != ["created"], procs["mallory"].log_tail()
    assert srv.alive, srv.log_tail()


def test_control_without_security_the_outsider_gets_in(request: pytest.FixtureRequest, tmp_path: Path) -> None:
    """The same outsider against a server without --security: it binds the victim's id and reads
    replies, so the shut-out test above measures what security prevents."""
    srv = SecuredServer.started(request, tmp_path, None)
    victim, session = "alice.victim", "taken"  # a client id of alice's (her reply partitions)
    outsider = start_probe(intruder_args(srv.domain, None, victim, session, 6.0), tmp_path / "outsider.log")
    request.addfinalizer(outsider.stop)
    time.sleep(3.0)
    alice = start_probe(client_args(srv.domain, None, victim, session) + ["--timeout-s", "3"], tmp_path / "alice.log")
    out = finish(alice, 60)
    got = finish(outsider, 30)
    assert int(got["matched_servers"][0]) > 0 and int(got["replies_read"][0]) > 0, outsider.log_tail()
    # The victim's id is bound to the outsider's writer: its OPEN gets no reply.
    assert alice.proc.returncode == 2 and out["open"] == ["-1"], alice.log_tail()


def test_bad_security_config_is_refused_at_start(tmp_path: Path, security_dir: Path) -> None:
    conf = tmp_path / "bad.conf"
    lines = (security_dir / "server" / "security.conf").read_text().splitlines()
    base = security_dir / "server"
    # Same files by absolute path, minus the permissions: the server names the missing key and exits.
    text = "\n".join(l if l.startswith("#") else l.split("=")[0] + "= " + str((base / l.split("=")[1].strip()).resolve())
                     for l in lines if l and not l.startswith("permissions "))
    conf.write_text(text + "\n")
    r = subprocess.run([server_executable(), "--domain", "0", "--security", str(conf)], capture_output=True,
                       text=True, timeout=30)
    assert r.returncode != 0
    assert "missing key 'permissions'" in r.stdout + r.stderr
