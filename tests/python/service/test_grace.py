"""Leases and the grace period with clients in their own processes, killed with SIGKILL (issue 11 §4):
the lease detaches a killed client (presence "expired" seen by another client, its upload dropped); a
session whose last client was detached is kept for the grace period, a restarted client with the same
client id finds it (and its role) and continues; after the grace period the session is gone."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable, Dict, Iterator, List

import numpy as np
import pytest

import surfeledit


from .collab_peer import watch
from .conftest import ServerProcess, connect_to
from .test_presence import presence_until

PEER = Path(__file__).with_name("collab_peer.py")
LEASE_MS = 1000


@pytest.fixture
def peers() -> Iterator[Callable[..., subprocess.Popen]]:
    started: List[subprocess.Popen] = []

    def run(mode: str, srv: ServerProcess, **args: object) -> subprocess.Popen:
        p = subprocess.Popen([sys.executable, str(PEER), mode, str(srv.domain), json.dumps(args)],
                             stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             start_new_session=True)
        started.append(p)
        return p

    yield run
    for p in started:
        if p.poll() is None:
            p.kill()
        p.wait()


def line(p: subprocess.Popen) -> Dict:
    out = p.stdout.readline() if p.stdout else ""
    assert out, f"peer {p.pid} ended: {p.stderr.read() if p.stderr else ''}"
    return json.loads(out)


def kill(p: subprocess.Popen) -> None:
    p.send_signal(signal.SIGKILL)
    p.wait()


def test_a_killed_client_expires_with_a_presence_update_and_its_upload_dropped(
        start_server: Callable[..., ServerProcess], peers: Callable[..., subprocess.Popen]) -> None:
    srv = start_server("--client-lease-ms", str(LEASE_MS))
    owner_client = connect_to(srv)
    try:
        owner = owner_client.open_session("crew")
        watcher = watch(owner)
        victim = "victim-" + owner_client.client_id
        p = peers("hold", srv, session="crew", token=owner.invite("editor"), client_id=victim, upload=4000)
        assert line(p)["ready"]
        presence_until(watcher, "join", victim)
        assert owner_client.info().upload_bytes == 4000 * 7 * 8
        assert {q.client_id: q.state for q in owner.peers()}[victim] == "attached"
        kill(p)
        killed = time.monotonic()
        ev = presence_until(watcher, "expired", victim, timeout=10.0)
        waited = time.monotonic() - killed
        assert waited < surfeledit._protocol.CLIENT_LIVELINESS_S + LEASE_MS / 1000 + 3.0
        states = {q.client_id: q.state for q in ev.peers}
        assert states == {owner_client.client_id: "attached", victim: "away"}
        assert owner_client.info().upload_bytes == 0
        assert owner.info().clients == 1
        assert {q.client_id: q.state for q in owner.peers()}[victim] == "away"
        # The owner goes on undisturbed; expiry changed no version.
        assert ev.version == owner.version
        watcher.close()
    finally:
        owner_client.close()


def test_a_restarted_client_resumes_within_the_grace_period_and_not_after(
        start_server: Callable[..., ServerProcess], peers: Callable[..., subprocess.Popen]) -> None:
    grace_ms = 4000
    srv = start_server("--client-lease-ms", str(LEASE_MS), "--session-grace-ms", str(grace_ms))
    observer = connect_to(srv)
    try:
        assert observer.info().session_grace_s == grace_ms / 1000
        # A session only the peer is in: the observer is no member, it reads the update stream only.
        me = "restartable-" + observer.client_id
        watcher = surfeledit.Watcher(observer, "solo")
        assert watcher.wait_greeted(20.0)
        p = peers("hold", srv, session="solo", client_id=me, points=500)
        held = line(p)
        presence_until(watcher, "join", me)
        kill(p)
        ev = presence_until(watcher, "expired", me)
        expired_at = time.monotonic()
        assert [(q.client_id, q.state, q.role) for q in ev.peers] == [(me, "away", "owner")]
        assert ev.version == held["version"]

        # Restarted with the same id within the grace period: the session, its model and the role are there.
        r = peers("resume", srv, session="solo", client_id=me, seconds=20.0)
        joined = line(r)
        assert joined == {"joined": True, "version": held["version"], "surfels": 500, "role": "owner"}
        changed = line(r)["changed"]
        assert changed == held["version"] + 1
        assert r.wait(timeout=20) == 0
        assert time.monotonic() - expired_at < grace_ms / 1000
        presence_until(watcher, "join", me)
        load, update = watcher.get(timeout=10.0), watcher.get(timeout=10.0)  # both processes' changes, in order
        assert load is not None and (load.cause, load.version, load.author) == ("load", held["version"], me)
        assert update is not None and (update.cause, update.version, update.author) == ("remove", changed, me)
        np.testing.assert_array_equal(update.removed, np.array([0], np.uint64))
        presence_until(watcher, "expired", me)  # the resumed process exited without closing: leased out again
        expired_at = time.monotonic()

        # Nobody comes back: the session is dropped once the grace period ends ("close" update) ...
        closed = watcher.get(timeout=grace_ms / 1000 + 5.0)
        assert closed is not None and closed.cause == "close" and closed.author == ""
        waited = time.monotonic() - expired_at
        assert waited > grace_ms / 1000 - 0.5, f"dropped {waited:.1f} s after the lease, before its grace period"
        # ... and a restarted client does not find it any more (nor its membership).
        late = peers("resume", srv, session="solo", client_id=me, seconds=20.0)
        assert line(late) == {"joined": False, "error": "NotFoundError", "field": "session"}
        watcher.close()
    finally:
        observer.close()
