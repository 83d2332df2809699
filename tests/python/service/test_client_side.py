"""Client-side pieces that need no server: error mapping, argument checks, cache merge, reassembly."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import surfeledit
from surfeledit import errors, proto
from surfeledit.results import Changes, State, merge
from surfeledit.session import Session
from surfeledit.watcher import Watcher


@pytest.mark.parametrize("status, cls", [(1, errors.InvalidArgumentError), (2, errors.NotFoundError),
                                         (3, errors.ConflictError), (4, errors.TooLargeError),
                                         (5, errors.ServerIOError), (6, errors.InternalServerError)])
def test_status_mapping(status: int, cls: type) -> None:
    e = errors.error_for_status(status, "bad thing", "deform.axis")
    assert type(e) is cls and e.status == status == getattr(proto.Status, list(proto.Status)[status].name).value
    assert e.field == "deform.axis" and e.message == "bad thing"
    assert isinstance(e, errors.SurfelEditError)
    assert isinstance(e, ValueError) == (status == 1)


class _NoServer:
    """Stands in for a Client: any request is a test failure (checks must happen before sending)."""

    closed = False

    def attach(self, child: Any) -> None:
        pass

    def detach(self, child: Any) -> None:
        pass

    def request(self, *a: Any, **k: Any) -> Any:
        raise AssertionError("a request was sent")

    max_chunk_surfels = 10


def make_session() -> Session:
    return Session(_NoServer(), "s", proto.Reply())  # type: ignore[arg-type]


@pytest.mark.parametrize("positions, normals, radii, field", [
    (np.zeros((4, 2)), np.zeros((4, 3)), None, "positions"),
    (np.zeros(12), np.zeros((4, 3)), None, "positions"),
    (np.zeros((4, 3)), np.zeros((3, 3)), None, "normals"),
    (np.zeros((4, 3)), np.zeros((4, 3)), np.zeros((4, 1)), "radii"),
    (np.zeros((4, 3)), np.zeros((4, 3)), np.zeros(5), "radii"),
    ([["a", "b", "c"]], [[0, 0, 1]], None, "positions"),
])
def test_load_points_shape_checks(positions: Any, normals: Any, radii: Any, field: str) -> None:
    with pytest.raises(errors.InvalidArgumentError) as info:
        make_session().load_points(positions, normals, radii)
    assert info.value.field == field
    assert isinstance(info.value, ValueError)


def test_selector_and_deform_checks() -> None:
    s = make_session()
    with pytest.raises(errors.InvalidArgumentError, match="shape"):
        s.set_regions(zero=[1], one_sphere=((0.0, 0.0), 1.0))
    with pytest.raises(errors.InvalidArgumentError, match="integer"):
        s.set_regions(zero=[1.5], one=[2])
    with pytest.raises(errors.InvalidArgumentError, match="negative"):
        s.set_regions(zero=[-1], one=[2])
    with pytest.raises(errors.InvalidArgumentError):
        s.deform(axis=(0.0, 1.0, 0.0, 0.0))
    for selector, field in [(dict(one_sphere=((0.0, 0.0, 1.0), "x")), "one_sphere.radius"),
                            (dict(one_sphere=(0.0, 0.0, 1.0)), "one_sphere"),  # not a (center, radius) pair
                            (dict(zero_box=(0.0, 0.0, 1.0)), "zero_box")]:
        with pytest.raises(errors.InvalidArgumentError) as info:
            s.set_regions(zero=[1], **selector)
        assert info.value.field == field


def test_merge_changes_into_cache() -> None:
    ids = np.array([0, 2, 4, 6], np.uint64)
    cache = State(1, ids, np.arange(12.0).reshape(4, 3), np.ones((4, 3)), np.full(4, 0.1))
    ch = Changes(version=3, full=False, ids=np.array([3, 4], np.uint64),
                 positions=np.array([[9.0, 9, 9], [8, 8, 8]]), normals=np.zeros((2, 3)),
                 radii=np.array([0.3, 0.4]), removed=np.array([2], np.uint64))
    out = merge(cache, ch)
    assert out.version == 3
    assert out.ids.tolist() == [0, 3, 4, 6]
    assert out.positions.tolist() == [[0, 1, 2], [9, 9, 9], [8, 8, 8], [9, 10, 11]]
    assert out.radii.tolist() == [0.1, 0.3, 0.4, 0.1]
    assert cache.positions[2].tolist() == [6, 7, 8]  # the cache itself is not modified


def test_watcher_reassembles_parts() -> None:
    w = Watcher.__new__(Watcher)
    w._pending, w._ready = {}, []
    for part in (1, 0):  # out of order
        w._add(proto.Update(session="s", version=5, cause="deform", parts=2, part=part, step=3,
                            ids=[2 * part, 2 * part + 1], positions=[float(part)] * 6,
                            normals=[0.0, 0.0, 1.0] * 2, radii=[0.1, 0.2]))
    assert len(w._ready) == 1
    ev = w._ready[0]
    assert ev.ids.tolist() == [0, 1, 2, 3] and ev.positions.shape == (4, 3)
    assert ev.positions[:, 0].tolist() == [0, 0, 1, 1] and ev.step == 3 and ev.version == 5


def test_remote_and_in_process_sessions_satisfy_one_protocol() -> None:
    from surfeledit.session_api import EditingSession
    assert isinstance(make_session(), EditingSession)
    try:
        from surfeledit.local import LocalSession
        local = LocalSession("protocol", threads=1)
    except ImportError:
        pytest.skip("surfeledit.core (the in-process session) is not built")
    assert isinstance(local, EditingSession)
    local.load_points(np.eye(3) + 1.0, np.eye(3))
    local.set_regions(zero=[0], one=[2])
    step = local.deform(translation=(0.0, 0.0, 0.1))
    assert isinstance(step, surfeledit.StepResult) and step.version == local.version
    assert isinstance(local.state(), State) and local.changes_since(local.version).ids.size == 0


@pytest.mark.parametrize("call, field", [
    (lambda s: s.set_regions(zero=[0.5], one=[2]), "zero"),
    (lambda s: s.set_regions(zero=[0], one=[True]), "one"),
    (lambda s: s.set_regions(zero=[-1], one=[2]), "zero"),
    (lambda s: s.set_regions(zero=[[0]], one=[2]), "zero"),
    (lambda s: s.deform(translation=(0.0, 0.0)), "translation"),
    (lambda s: s.deform(axis=(0.0, 1.0, 0.0, 0.0), angle=0.1), "axis"),
    (lambda s: s.deform(center="abc", angle=0.1), "center"),
    (lambda s: s.remove([1.0]), "ids"),
    (lambda s: s.deform(angle="abc"), "angle"),
    (lambda s: s.changes_since(-1), "version"),
    (lambda s: s.changes_since(2**70), "version"),
    (lambda s: s.blend(iterations=1.5), "iterations"),
    (lambda s: s.blend(iterations=2**40), "iterations"),
    (lambda s: s.blend(dt="x"), "dt"),
    (lambda s: s.fill_holes("x"), "max_diameter"),
    (lambda s: s.intersection_curves("x"), "refine_angle"),
])
def test_in_process_session_checks_arguments_as_the_remote_one(call: Any, field: str) -> None:
    # One script, two backends (surfeledit.scenario): the same bad argument is the same typed error naming the same
    # field, before anything reaches the core or the wire (a float id would otherwise be truncated to another id, a
    # negative version fail to encode).
    try:
        from surfeledit.local import LocalSession
    except ImportError:
        pytest.skip("surfeledit.core (the in-process session) is not built")
    local = LocalSession("checks", threads=1)
    local.load_points(np.eye(3) + 1.0, np.eye(3))
    before = local.version
    for session in (make_session(), local):
        with pytest.raises(errors.InvalidArgumentError) as info:
            call(session)
        assert info.value.field == field, (type(session).__name__, info.value)
    assert local.version == before


@pytest.mark.parametrize("domain", [-1, 233, "x", 2**40])
def test_a_domain_outside_the_servers_range_is_refused_before_dds(domain: Any) -> None:
    # -1 would be Cyclone's "configured default" domain and > 232 has no port mapping (a bare DDSException).
    with pytest.raises(errors.InvalidArgumentError) as info:
        surfeledit.connect(domain=domain, spawn=False, timeout=0.1)
    assert info.value.field == "domain"
