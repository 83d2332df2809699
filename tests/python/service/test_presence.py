"""Peers, presence on the update stream, authors and expect_version against a real server (issue 11 §2)."""

from __future__ import annotations

import time
from typing import Callable, List, Tuple

import numpy as np
import pytest

import surfeledit
from surfeledit import errors
from surfeledit._protocol import proto


from .collab_peer import watch
from .conftest import generated_scene


def loaded(client: surfeledit.Client, name: str) -> Tuple[surfeledit.Session, np.ndarray, np.ndarray]:
    """An opened session with the demo scene (spacing 0.1); returns it, the ids and the parts."""
    pos, nrm, rad, part = generated_scene(0.1)
    s = client.open_session(name)
    s.load_points(pos, nrm, rad)
    return s, s.state().ids, part


def presence_until(watcher: surfeledit.Watcher, what: str, client: str,
                   timeout: float = 10.0) -> surfeledit.PresenceEvent:
    """The next presence event ``what`` about ``client`` after the one the last call returned (events
    received meanwhile are kept for later calls)."""
    log = watcher.__dict__.setdefault("_test_presence", {"events": [], "cursor": 0})
    deadline = time.monotonic() + timeout
    while True:
        for i in range(log["cursor"], len(log["events"])):
            ev = log["events"][i]
            if ev.what == what and ev.client == client:
                log["cursor"] = i + 1
                return ev
        if time.monotonic() >= deadline:
            seen = [(e.what, e.client) for e in log["events"]]
            raise AssertionError(f"no presence {what!r} of {client} within {timeout} s; seen {seen}")
        log["events"].extend(watcher.presence(timeout=0.5))


def test_peers_list_roles_last_ops_and_tool_sizes(client: surfeledit.Client,
                                                  make_client: Callable[[], surfeledit.Client]) -> None:
    owner, ids, part = loaded(client, "peers")
    watcher = watch(owner)
    watched_from = owner.version  # an update published before the watcher matched may still arrive
    editor_client, viewer_client = make_client(), make_client()
    editor = editor_client.join_session("peers", token=owner.invite("editor"))
    ev = presence_until(watcher, "join", editor_client.client_id)
    assert {p.client_id for p in ev.peers} == {client.client_id, editor_client.client_id}
    viewer = viewer_client.join_session("peers", token=owner.invite("viewer"))
    presence_until(watcher, "join", viewer_client.client_id)

    # Regions by the editor: the zero region is the slab, the one region the sphere's upper half; the
    # rest of the sphere is the band. Independent truth from the ids sent.
    pos = owner.state().positions
    zero = ids[part == 0]
    one = ids[(part == 1) & (pos[:, 2] > np.median(pos[part == 1, 2]))]
    editor.set_regions(zero=zero, one=one)
    regions_version = editor.version
    ev = presence_until(watcher, "regions", editor_client.client_id)
    by_id = {p.client_id: p for p in ev.peers}
    assert by_id[editor_client.client_id].zero == zero.size and by_id[editor_client.client_id].one == one.size
    step = editor.deform(translation=(0.0, 0.0, -0.01))  # the editor's tool (each client has its own)

    peers = viewer.peers()  # a viewer may ask
    assert [p.client_id for p in peers] == sorted([client.client_id, editor_client.client_id,
                                                   viewer_client.client_id])
    by_id = {p.client_id: p for p in peers}
    o, e, v = by_id[client.client_id], by_id[editor_client.client_id], by_id[viewer_client.client_id]
    assert (o.role, e.role, v.role) == ("owner", "editor", "viewer")
    assert all(p.state == "attached" for p in peers)
    assert o.last_op.startswith("load") and 0 < o.last_version < regions_version
    assert (e.last_op, e.last_version) == ("deform", step.version)
    assert (v.last_op, v.last_version) == ("", 0)
    assert (e.zero, e.one) == (zero.size, one.size)
    assert e.deformable == ids.size - zero.size  # everything outside the zero region may move
    for p in (o, v):
        assert (p.zero, p.one, p.deformable) == (0, 0, 0)  # no tool of their own
    for p in peers:
        assert 0.0 <= p.idle_ms < 60_000
    assert v.idle_ms < o.idle_ms + 1.0  # the viewer asked last

    # The step's update names its author; presence changes stay out of the model updates.
    updates = []
    while not updates or updates[-1].version < step.version:
        u = watcher.get(timeout=10.0)
        assert u is not None
        if u.version > watched_from:
            updates.append(u)
    assert [(u.cause, u.author) for u in updates] == [("regions", editor_client.client_id),
                                                      ("deform", editor_client.client_id)]

    viewer.close()
    ev = presence_until(watcher, "leave", viewer_client.client_id)
    assert viewer_client.client_id not in {p.client_id for p in ev.peers}
    assert [p.client_id for p in owner.peers()] == sorted([client.client_id, editor_client.client_id])
    watcher.close()


def test_presence_callback_is_called(client: surfeledit.Client,
                                     make_client: Callable[[], surfeledit.Client]) -> None:
    owner = client.open_session("callback")
    got: List[surfeledit.PresenceEvent] = []
    watcher = owner.watch(on_presence=got.append)
    assert watcher.wait_greeted(20.0)
    other = make_client()
    other.join_session("callback", token=owner.invite("viewer")).close()
    deadline = time.monotonic() + 10.0

    def others() -> List[Tuple[str, str]]:  # the owner's own join may arrive too (published as it opened)
        return [(e.what, e.client) for e in got if e.client == other.client_id]

    while len(others()) < 2 and time.monotonic() < deadline:
        watcher.get(timeout=0.3)  # drains; presence goes to the callback only
    assert others() == [("join", other.client_id), ("leave", other.client_id)]
    assert watcher.presence() == got  # and to presence()
    watcher.close()


def test_expect_version_refuses_a_stale_op_and_changes_nothing(
        client: surfeledit.Client, make_client: Callable[[], surfeledit.Client]) -> None:
    a, ids, part = loaded(client, "optimistic")
    a.set_regions(zero=ids[part == 0], one=ids[part == 1])
    b = make_client().join_session("optimistic", token=a.invite("editor"))
    v = a.version
    step = a.deform(translation=(0.0, 0.0, -0.01), expect_version=v)  # current: accepted
    assert step.version == v + 1
    b.remove(ids[part == 0][:1])  # another client's op comes first (a slab surfel: outside a's lock)
    before = a.info()
    truth = a.state()
    for call in (lambda: a.deform(translation=(0.0, 0.0, -0.01), expect_version=step.version),
                 lambda: a.set_regions(zero=ids[part == 0], one=ids[part == 1][:5], expect_version=step.version),
                 lambda: a.remove(ids[:3], expect_version=step.version),
                 lambda: a.undo(expect_version=step.version),
                 lambda: a.configure(algorithm="simple", expect_version=step.version)):
        with pytest.raises(errors.ConflictError) as exc:
            call()
        assert exc.value.field == "expect_version"
        assert f"it is at version {v + 2}" in exc.value.message  # names the current version
    with pytest.raises(errors.InvalidArgumentError) as exc:
        a.deform(translation=(0.0, 0.0, -0.01), expect_version=v + 5)  # a version the session never reached
    assert exc.value.field == "expect_version"
    after = a.info()
    assert after.state_hash == before.state_hash and a.version == v + 2
    assert {s.name: s for s in after.settings}["algorithm"] == {s.name: s for s in before.settings}["algorithm"]
    now = a.state()
    assert np.array_equal(now.positions, truth.positions) and np.array_equal(now.ids, truth.ids)
    # With the current version it goes through; reading ops ignore it.
    assert a.deform(translation=(0.0, 0.0, -0.01), expect_version=v + 2).version == v + 3
    req = client.new_request(proto.Op.OP_HISTORY, "optimistic")
    req.expect_version = [0]
    assert client.call(req).history
    req = client.new_request(proto.Op.OP_DEFORM, "optimistic", deform=proto.Deform(
        translation=proto.Vec3(x=0.0, y=0.0, z=0.0), axis=proto.Vec3(x=0.0, y=0.0, z=1.0), blend="smooth"))
    req.expect_version = [v + 3, v + 3]
    with pytest.raises(errors.InvalidArgumentError) as exc:
        client.call(req)
    assert exc.value.field == "expect_version"
    a.info()
    assert a.version == v + 3
