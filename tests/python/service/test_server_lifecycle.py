"""The server process: clean shutdown on SIGINT/SIGTERM with sessions open, many sessions at once, one server
per domain."""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path
from typing import Optional

import numpy as np
import pytest

from .conftest import ServerProcess, connect_to, free_domain, generated_scene, server_executable


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_clean_exit_on_signal_with_an_open_session(tmp_path: Path, sig: signal.Signals) -> None:
    srv = ServerProcess(server_executable(), free_domain(), tmp_path / "server.log")
    try:
        client = connect_to(srv)
        positions, normals, radii, part = generated_scene()
        session = client.open_session("busy")
        session.load_points(positions, normals, radii)
        session.set_regions(zero=np.flatnonzero(part == 0), one=np.flatnonzero(part == 1))
        session.deform(translation=(0.0, 0.0, -0.01))
        t0 = time.monotonic()
        srv.proc.send_signal(sig)
        code = srv.proc.wait(timeout=10)
        elapsed = time.monotonic() - t0
        print(f"{sig.name}: exit code {code} after {elapsed * 1e3:.0f} ms")
        assert code == 0, srv.log_tail()
        assert elapsed < 5.0
        client.close()
    finally:
        srv.stop()


def test_one_process_serves_independent_sessions(server: ServerProcess) -> None:
    a = connect_to(server)
    b = connect_to(server)
    positions, normals, radii, part = generated_scene()
    zero, one = np.flatnonzero(part == 0), np.flatnonzero(part == 1)
    with a.open_session("left") as left, b.open_session("right") as right:
        for s in (left, right):
            s.load_points(positions, normals, radii)
            s.set_regions(zero=zero, one=one)
        left.deform(translation=(0.0, 0.0, -0.02))
        right.deform(translation=(0.1, 0.0, 0.0))
        right.deform(translation=(0.1, 0.0, 0.0))
        pl, pr = left.positions(), right.positions()
        np.testing.assert_allclose(pl[one], positions[one] + [0.0, 0.0, -0.02], atol=1e-12)
        np.testing.assert_allclose(pr[one], positions[one] + [0.2, 0.0, 0.0], atol=1e-12)
        np.testing.assert_array_equal(pl[zero], positions[zero])
        # Each client lists only its own (private) session.
        assert set(a.info().sessions) == {"left"} and set(b.info().sessions) == {"right"}
    a.close()
    b.close()


def _exit_code(srv: ServerProcess, timeout: float) -> Optional[int]:
    """The process's exit code, or None if it still runs after ``timeout`` seconds."""
    try:
        return srv.proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        return None


def test_a_second_server_on_a_served_domain_gives_way(server: ServerProcess, tmp_path: Path) -> None:
    """PROTOCOL.md "One server per domain": a server started on a domain another server already serves exits
    with code 4 before serving, naming the running server; the running one goes on answering."""
    client = connect_to(server)
    session = client.open_session("kept")
    second = ServerProcess(server_executable(), server.domain, tmp_path / "second.log")
    try:
        code = _exit_code(second, 20.0)
        log = second.log_tail()
        assert code == 4, log
        assert "already has a surfeledit server" in log and f"pid {server.proc.pid}" in log, log
        assert "ready on domain" not in log, log
        assert "kept" in client.info().sessions
        assert server.alive
    finally:
        second.stop()
        session.close()
        client.close()


def test_servers_started_together_leave_exactly_one(tmp_path: Path) -> None:
    """Two servers started at once on one domain, each looking for 3 s: the later one gives way to the earlier,
    which then serves."""
    domain = free_domain()
    probe = ("--domain-probe-ms", "3000")
    a = ServerProcess(server_executable(), domain, tmp_path / "a.log", None, probe)
    b = ServerProcess(server_executable(), domain, tmp_path / "b.log", None, probe)
    try:
        codes = {s: _exit_code(s, 15.0) for s in (a, b)}
        gone = [s for s, c in codes.items() if c is not None]
        assert len(gone) == 1, f"{codes}\n{a.log_tail()}\n{b.log_tail()}"
        loser, winner = gone[0], (b if gone[0] is a else a)
        assert codes[loser] == 4, loser.log_tail()
        assert f"pid {winner.proc.pid}" in loser.log_tail(), loser.log_tail()
        connect_to(winner).close()  # the earlier one serves
        assert winner.alive
    finally:
        a.stop()
        b.stop()


def test_no_probe_starts_beside_a_running_server(server: ServerProcess, tmp_path: Path) -> None:
    """``--domain-probe-ms 0`` turns the check off: the second server stays up (the operator's choice)."""
    connect_to(server).close()
    second = ServerProcess(server_executable(), server.domain, tmp_path / "second.log", None,
                           ("--domain-probe-ms", "0"))
    try:
        second.wait_ready()
        assert _exit_code(second, 1.0) is None, second.log_tail()
    finally:
        second.stop()
