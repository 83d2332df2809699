"""Two and four clients in separate processes edit one session at once (issue 11 §2, §6): one total order,
no lost or duplicated op, authors as acknowledged, every client's view and a watcher's replay of the update
stream equal to GET_STATE at the end, bit for bit."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Dict, List

import numpy as np
import pytest

import surfeledit

from surfeledit.demo import sphere_sectors

from .collab_peer import apply, digest, fresh_state, same, watch
from .conftest import ServerProcess, generated_scene

PEER = Path(__file__).with_name("collab_peer.py")
STEPS = 25          # deform steps per client
SECONDS = 30.0      # bound on each client's editing time


def start_peers(srv: ServerProcess, n: int, session: str, token: str, tools: List[List[int]]) -> List[subprocess.Popen]:
    return [subprocess.Popen([sys.executable, str(PEER), "edit", str(srv.domain), json.dumps(
        dict(session=session, token=token, steps=STEPS, seconds=SECONDS, seed=100 + k, one=tools[k]))],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
        for k in range(n)]


def read(p: subprocess.Popen) -> Dict:
    line = p.stdout.readline() if p.stdout else ""
    if not line:
        p.kill()
        raise AssertionError(f"peer {p.pid} ended: {p.stderr.read() if p.stderr else ''}")
    return json.loads(line)


def send(p: subprocess.Popen, line: str) -> None:
    assert p.stdin is not None
    p.stdin.write(line + "\n")
    p.stdin.flush()


@pytest.mark.parametrize("n", [2, 4])
def test_clients_in_separate_processes_edit_one_session(n: int, client: surfeledit.Client,
                                                        server: ServerProcess) -> None:
    pos, nrm, rad, part = generated_scene(0.1)
    owner = client.open_session("together")
    watcher = watch(owner)
    owner.load_points(pos, nrm, rad)
    ids = owner.state().ids
    token = owner.invite("editor")
    # Disjoint tools (issue 11 §1): each client moves one sector of the sphere, the rest is rigid to it.
    peers = start_peers(server, n, "together", token, sphere_sectors(pos, part, ids, n))
    try:
        ready = [read(p) for p in peers]
        assert all(r["ready"] for r in ready)
        start = fresh_state(owner)  # after every client set its regions
        names = [r["client_id"] for r in ready]
        # Every peer's join reaches the stream; the owner's own join may too (it can be published after the
        # watcher subscribed), so it is allowed, not required.
        allowed = set(names) | {client.client_id}
        joined = set()
        deadline = time.monotonic() + 10.0
        while not set(names) <= joined and time.monotonic() < deadline:
            joined |= {ev.client for ev in watcher.presence(timeout=1.0) if ev.what == "join"}
        assert set(names) <= joined <= allowed, f"joins seen {sorted(joined)}, peers {sorted(names)}"
        # Joins do not enter the model updates: nothing after the start before the first step.
        assert all(e.version <= start.version and e.cause in ("load", "regions") for e in watcher.poll())
        for p in peers:
            send(p, "go")
        done = [read(p) for p in peers]
        acked: Dict[int, str] = {}
        for d in done:
            v = d["versions"]
            assert len(v) == STEPS, f"{d['client_id']} made {len(v)} steps in {d['seconds']:.1f} s"
            assert all(a < b for a, b in zip(v, v[1:])), f"versions not strictly increasing: {v}"
            for version in v:
                assert version not in acked, f"version {version} acknowledged to two clients"
                acked[version] = d["client_id"]
        # One total order: the acknowledged versions are exactly the versions after the start, each once.
        assert sorted(acked) == list(range(start.version + 1, start.version + 1 + n * STEPS))

        truth = fresh_state(owner)
        assert truth.version == start.version + n * STEPS
        history = [h for h in owner.history() if h.version > start.version]
        assert [h.version for h in history] == sorted(acked), "lost or duplicated op in the history"
        assert all(h.op == "deform" and h.client == acked[h.version] and not h.undone for h in history)

        # Every client's view (its watcher's replay, its incremental state()) equals GET_STATE.
        for p in peers:
            send(p, "final")
        finals = [read(p) for p in peers]
        for f in finals:
            assert f["version"] == truth.version, f
            assert f["view_equal"] and f["state_equal"], f
            assert f["digest"] == digest(truth)
            # Updates before the start: the other clients' set_regions.
            assert all(acked[int(v)] == a for v, a in f["authors"].items() if int(v) > start.version)

        # This process's watcher: every model update, in version order, authors as acknowledged.
        events = []
        while not events or events[-1].version < truth.version:
            ev = watcher.get(timeout=10.0)
            assert ev is not None, f"updates stopped at {[e.version for e in events][-3:]}"
            events.append(ev)
        versions = [e.version for e in events]
        assert versions == sorted(acked), "the update stream skipped or repeated a version"
        assert all(e.cause == "deform" and e.author == acked[e.version] for e in events)
        view = start
        for e in events:
            view = apply(view, e)
        assert same(view, truth), "the update stream does not reconstruct the final state"
        assert not np.array_equal(truth.positions, start.positions)
        # Every editor is listed with its last step.
        listed = {peer.client_id: peer for peer in owner.peers()}
        for name in names:
            assert listed[name].role == "editor" and listed[name].last_op == "deform"
            assert listed[name].last_version == max(v for v, a in acked.items() if a == name)
    finally:
        for p in peers:
            if p.poll() is None:
                try:
                    send(p, "quit")
                    p.wait(timeout=10)
                except (OSError, subprocess.TimeoutExpired):
                    p.kill()
                    p.wait()
        watcher.close()
