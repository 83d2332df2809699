"""Blend, boolean and hole filling end to end (issue 10): over DDS with a real server every result equals the
in-process one; bad arguments are typed errors that change nothing; undo restores the state exactly; a
watcher applying the updates reaches the server's state. Geometry against exact truth is tested in the core
(tests/core/particles/test_blend.cpp, tests/core/test_boolean.cpp, tests/core/test_holes.cpp)."""

from __future__ import annotations

import numpy as np
import pytest

import surfeledit
from surfeledit import ConflictError, InvalidArgumentError, LocalSession, NotFoundError

from response.conftest import approach
from response.test_dds import apply_updates, load, load_and_watch, steps
from response.test_merge import same_merge, same_state

from .conftest import holed_sphere, two_spheres


def pushed_and_merged(session, a) -> surfeledit.MergeResult:
    load(session, a)
    for st in steps(a.spacing):
        session.deform(**st)
    return session.merge()


def same_blend(got: surfeledit.BlendResult, want: surfeledit.BlendResult) -> None:
    assert got.particles == want.particles and got.substeps == want.substeps
    for field in ("moved", "inserted", "removed", "energy"):
        assert np.array_equal(getattr(got, field), getattr(want, field)), field


def same_fill(got: surfeledit.FillResult, want: surfeledit.FillResult) -> None:
    assert got.skipped == want.skipped and np.array_equal(got.inserted, want.inserted)
    assert len(got.holes) == len(want.holes)
    for g, w in zip(got.holes, want.holes):
        assert np.array_equal(g.boundary, w.boundary) and np.array_equal(g.inserted, w.inserted)
        assert g.diameter == w.diameter


def test_blend_over_dds_equals_in_process(client: surfeledit.Client) -> None:
    a = approach(spacing=0.05)
    local = LocalSession("local")
    pushed_and_merged(local, a)
    with client.open_session("b") as sess:
        pushed_and_merged(sess, a)
        for kwargs in ({"iterations": 10}, {"iterations": 5, "adaptive": True, "only_grow": True},
                       {"iterations": 3, "repulsion": "spring", "weight": "gaussian", "neighbourhood": "grid"},
                       {"iterations": 4, "projection": "tangent"}):
            want, got = local.blend(**kwargs), sess.blend(**kwargs)
            same_blend(got, want)
            assert got.version == want.version == sess.version
            assert got.particles > 0 and got.energy.shape == (kwargs["iterations"],)
            same_state(sess.state(), local.state())
        assert sess.info().state_hash == local.core.state_hash
        assert [h.op for h in sess.history()][-4:] == ["blend"] * 4


@pytest.mark.parametrize("op", ["union", "intersection", "difference"])
def test_boolean_over_dds_equals_in_process(client: surfeledit.Client, op: str) -> None:
    (pa, na, ra), (pb, nb, rb) = two_spheres()
    local = LocalSession("local")
    local.load_points(pa, na, ra)
    with client.open_session("bool") as sess:
        sess.load_points(pa, na, ra)
        want, got = local.boolean(op, pb, nb, rb), sess.boolean(op, pb, nb, rb)
        same_merge(got, want)
        assert got.features.size > 0 and got.version == want.version == sess.version
        same_state(sess.state(), local.state())
        # The boolean's features are the blend's default.
        same_blend(sess.blend(iterations=4), local.blend(iterations=4))
        same_state(sess.state(), local.state())


def test_fill_holes_over_dds_equals_in_process(client: surfeledit.Client) -> None:
    p, n, r = holed_sphere()
    local = LocalSession("local")
    local.load_points(p, n, r)
    with client.open_session("holes") as sess:
        sess.load_points(p, n, r)
        want, got = local.fill_holes(0.6), sess.fill_holes(0.6)
        same_fill(got, want)
        assert len(got.holes) == 1 and got.inserted.size > 0
        assert got.holes[0].diameter == pytest.approx(0.3, rel=0.25)
        same_state(sess.state(), local.state())
        # The override: the same boundary given explicitly, after an undo, fills the same way.
        for s in (sess, local):
            s.undo()
        same_fill(sess.fill_holes(0.6, boundary=got.holes[0].boundary),
                  local.fill_holes(0.6, boundary=want.holes[0].boundary))
        same_state(sess.state(), local.state())
        # Without the final MLS projection the filling stays on the fitted quadric: other positions.
        mls = sess.state()
        for s in (sess, local):
            s.undo()
        same_fill(sess.fill_holes(0.6, projection="tangent"), local.fill_holes(0.6, projection="tangent"))
        tangent = sess.state()
        same_state(tangent, local.state())
        assert mls.positions.shape != tangent.positions.shape or not np.array_equal(mls.positions, tangent.positions)


@pytest.mark.parametrize("where", ["local", "dds"])
def test_undo_restores_each_exactly(client: surfeledit.Client, where: str) -> None:
    a = approach(spacing=0.05)
    ctx = LocalSession("undo") if where == "local" else client.open_session("undo")
    with ctx as sess:
        pushed_and_merged(sess, a)
        snapshots = [sess.state()]  # before each op that changed something
        sess.blend(iterations=5, adaptive=True)
        snapshots.append(sess.state())
        (pb, nb, rb) = two_spheres()[1]
        sess.boolean("difference", pb + [0.0, 0.0, 0.3], nb, rb)
        snapshots.append(sess.state())
        filled = sess.fill_holes(0.5, boundary=sess.ids()[:40])
        if filled.inserted.size == 0:
            snapshots.pop()
        for want in reversed(snapshots):
            sess.undo()
            same_state(sess.state(), want)
            assert sess.state().version == sess.version


@pytest.mark.parametrize("where", ["local", "dds"])
def test_bad_arguments_are_typed_and_change_nothing(client: surfeledit.Client, where: str) -> None:
    a = approach(spacing=0.05)
    (pb, nb, rb) = two_spheres()[1]
    ctx = LocalSession("bad") if where == "local" else client.open_session("bad")
    with ctx as sess:
        load(sess, a)
        with pytest.raises(ConflictError):
            sess.blend()  # no merge or boolean yet
        for st in steps(a.spacing):
            sess.deform(**st)
        sess.merge()
        before, version = sess.state(), sess.version
        bad_calls = [
            (InvalidArgumentError, lambda: sess.blend(iterations=-1)),
            (InvalidArgumentError, lambda: sess.blend(dt=0.0)),
            (InvalidArgumentError, lambda: sess.blend(range_factor=float("nan"))),
            (InvalidArgumentError, lambda: sess.blend(repulsion="magnetic")),
            (InvalidArgumentError, lambda: sess.blend(weight="box")),
            (InvalidArgumentError, lambda: sess.blend(neighbourhood="octree")),
            (InvalidArgumentError, lambda: sess.blend(projection="spline")),
            (InvalidArgumentError, lambda: sess.blend(projection="")),
            (InvalidArgumentError, lambda: sess.blend(features=[])),
            (NotFoundError, lambda: sess.blend(features=[10**9])),
            (InvalidArgumentError, lambda: sess.boolean("xor", pb, nb, rb)),
            (InvalidArgumentError, lambda: sess.boolean("union", np.where(np.arange(pb.size).reshape(pb.shape) == 4,
                                                                          np.nan, pb), nb, rb)),
            (InvalidArgumentError, lambda: sess.boolean("union", pb, np.zeros_like(nb), rb)),
            (InvalidArgumentError, lambda: sess.fill_holes(-1.0)),
            (InvalidArgumentError, lambda: sess.fill_holes(0.5, iterations=-3)),
            (InvalidArgumentError, lambda: sess.fill_holes(0.5, projection="MLS")),
            (NotFoundError, lambda: sess.fill_holes(0.5, boundary=[10**9])),
        ]
        for error, call in bad_calls:
            with pytest.raises(error):
                call()
            assert sess.version == version
        same_state(sess.state(), before)


def test_watcher_applies_blend_updates(client: surfeledit.Client) -> None:
    a = approach(spacing=0.05)
    with client.open_session("w") as sess:
        w = load_and_watch(sess, a)
        cache = sess.state()
        for st in steps(a.spacing):
            sess.deform(**st)
        sess.merge()
        sess.blend(iterations=5)
        sess.undo()
        cache, causes = apply_updates(w, cache, 6)
        assert causes[-3:] == ["merge", "blend", "undo"]
        same_state(cache, sess.state())
        w.close()
