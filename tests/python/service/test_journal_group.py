"""Group commit (PROTOCOL.md "Journal"): a group is committed as soon as the server has no more
requests to read, or at its deadline (--journal-group-ms), whichever comes first. A lone client
stepping back to back therefore never waits for the deadline: with a deadline of 200 ms, 20 steps
take far less than 20 x 200 ms. The guarantee (no reply before its op is durable) is checked by
SIGKILL in test_journal_crash.py (both policies) and here by a kill right after the last reply:
the restarted server has every acknowledged step, and the same state hash as an independent
in-process replay of them."""

from __future__ import annotations

import os
import signal
import time
from pathlib import Path

import numpy as np

import surfeledit
from surfeledit.local import LocalSession

from .conftest import free_domain, generated_scene
from .test_journal import _server

GROUP_MS = 200
STEPS = 20


def _step(i: int) -> dict:
    sign = 1.0 if i % 2 == 0 else -1.0
    return {"translation": (0.0, 0.004 * sign, 0.002), "axis": (1.0, 0.0, 0.0), "angle": 0.01 * sign}


def test_a_lone_client_does_not_wait_for_the_group_deadline(tmp_path: Path) -> None:
    domain = free_domain()
    journal = tmp_path / "journal"
    positions, normals, radii, part = generated_scene(0.1)
    ids = np.arange(len(positions), dtype=np.uint64)
    sync = ("--journal-sync", "group", "--journal-group-ms", str(GROUP_MS))
    srv = _server(tmp_path, domain, journal, 0, *sync)
    client = surfeledit.connect(domain=domain, spawn=False, timeout=10.0, reconnect=20.0)
    try:
        s = client.open_session("lone")
        s.load_points(positions, normals, radii)
        s.configure(algorithm="none")
        s.set_regions(zero=ids[part == 0], one=ids[part == 1])
        t0 = time.monotonic()
        versions = [s.deform(**_step(i)).version for i in range(STEPS)]
        elapsed = time.monotonic() - t0
        # Each step waiting for its group's deadline would take >= STEPS x GROUP_MS = 4 s.
        assert elapsed < 0.5 * STEPS * GROUP_MS / 1000, \
            f"{STEPS} steps took {elapsed:.2f} s with a {GROUP_MS} ms group deadline"
        assert versions == list(range(versions[0], versions[0] + STEPS))
        acknowledged = (versions[-1], s.info().state_hash)
        # Acknowledged means durable: SIGKILL now, restart, everything is back.
        os.kill(srv.proc.pid, signal.SIGKILL)
        srv.proc.wait()
        srv = _server(tmp_path, domain, journal, 1, *sync)
        info = s.info()
        assert (s.history()[-1].version, info.state_hash) == acknowledged
        # Independent truth: the same ops applied in process by the core (no server, no journal).
        local = LocalSession("replay", threads=1)
        local.load_points(positions, normals, radii)
        local.configure(algorithm="none")
        local.set_regions(zero=ids[part == 0], one=ids[part == 1])
        for i in range(STEPS):
            local.deform(**_step(i))
        assert int(local.core.state_hash) == int(info.state_hash)
    finally:
        client.close()
        srv.stop()
