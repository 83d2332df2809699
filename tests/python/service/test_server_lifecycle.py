"""The server process: clean shutdown on SIGINT/SIGTERM with sessions open, many sessions at once."""

from __future__ import annotations

import signal
import time
from pathlib import Path

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
