"""The merge response end to end (issue 9 §3): over DDS with a real server every merge, merged step and
curve equals the in-process result; a watcher applying the updates (clip lines included) reaches the
server's state; bad arguments are typed errors that change nothing; undo / redo of merges in random
sequences restore snapshots taken before each op; steps and detection go on after a merge."""

from __future__ import annotations

import random
from typing import Dict, List

import numpy as np
import pytest

import surfeledit
from surfeledit import ConflictError, InvalidArgumentError, LocalSession, State

from .conftest import approach
from .test_dds import apply_updates, load, load_and_watch, steps


def same_state(a: State, b: State) -> None:
    assert np.array_equal(a.ids, b.ids)
    assert np.array_equal(a.positions, b.positions)
    assert np.array_equal(a.normals, b.normals)
    assert np.array_equal(a.radii, b.radii)
    assert (a.clips is None) == (b.clips is None)
    if a.clips is not None:
        assert np.array_equal(a.clips, b.clips)


def same_merge(got: surfeledit.MergeResult, want: surfeledit.MergeResult) -> None:
    for field in ("removed", "features", "moved", "inserted"):
        assert np.array_equal(getattr(got, field), getattr(want, field)), field
    assert len(got.curves) == len(want.curves)
    for g, w in zip(got.curves, want.curves):
        assert g.closed == w.closed and np.array_equal(g.points, w.points)


def pushed(session, a) -> None:
    load(session, a)
    for st in steps(a.spacing):
        session.deform(**st)


def test_merge_over_dds_equals_in_process(client: surfeledit.Client) -> None:
    a = approach(spacing=0.05)
    local = LocalSession("local")
    pushed(local, a)
    with client.open_session("m") as sess:
        pushed(sess, a)
        want, got = local.merge(), sess.merge()
        same_merge(got, want)
        assert got.removed.size > 0 and got.features.size > 0 and got.curves
        assert got.version == want.version == sess.version
        same_state(sess.state(), local.state())
        assert sess.state().clips is not None
        assert sess.info().state_hash == local.core.state_hash
        for angle in (0.5, 0.1):
            w_curves, g_curves = local.intersection_curves(refine_angle=angle), sess.intersection_curves(angle)
            assert [c.points.tolist() for c in g_curves] == [c.points.tolist() for c in w_curves]
        assert all(c.points.shape[1] == 3 and c.points.shape[0] >= 3 for c in g_curves)
        # Undo over the wire: back to the state before, without clip lines.
        local.undo()
        sess.undo()
        same_state(sess.state(), local.state())
        assert sess.state().clips is None
        assert [h.op for h in sess.history()][-1] == "merge"


def test_response_merge_over_dds_and_later_steps(client: surfeledit.Client) -> None:
    a = approach(spacing=0.05)
    local = LocalSession("local")
    load(local, a)
    local.configure(response="merge")
    with client.open_session("rm") as sess:
        load(sess, a)
        sess.configure(response="merge")
        responses = []
        for st in list(steps(a.spacing)) + [dict(translation=(0, 0, 2 * a.spacing)),
                                            dict(translation=(0, 0, -4 * a.spacing))]:
            want, got = local.deform(**st), sess.deform(**st)
            assert got.response == want.response
            assert np.array_equal(got.colliding, want.colliding)
            assert np.array_equal(got.features, want.features)
            assert np.array_equal(got.inserted, want.inserted)
            assert got.version == want.version
            responses.append(got.response)
        assert "merged" in responses
        # The detector re-initialised from each merged model and goes on detecting.
        assert responses[-1] in ("merged", "none")
        same_state(sess.state(), local.state())
        assert sess.info().state_hash == local.core.state_hash


def test_watcher_applies_clips(client: surfeledit.Client) -> None:
    a = approach(spacing=0.05)
    with client.open_session("w") as sess:
        w = load_and_watch(sess, a)
        cache = sess.state()
        for st in steps(a.spacing):
            sess.deform(**st)
        sess.merge()
        sess.undo()
        sess.redo()
        cache, causes = apply_updates(w, cache, 6)
        assert causes == ["deform", "deform", "deform", "merge", "undo", "redo"]
        same_state(cache, sess.state())
        assert cache.clips is not None
        w.close()


@pytest.mark.parametrize("where", ["local", "dds"])
def test_bad_arguments_are_typed_and_change_nothing(client: surfeledit.Client, where: str) -> None:
    a = approach(spacing=0.05)
    ctx = LocalSession("bad") if where == "local" else client.open_session("bad")
    with ctx as sess:
        sess.load_points(a.positions, a.normals, a.radii)
        before, version = sess.state(), sess.version
        with pytest.raises(ConflictError):
            sess.merge()  # no regions
        with pytest.raises(ConflictError):
            sess.intersection_curves()  # no merge yet
        with pytest.raises(InvalidArgumentError):
            sess.configure(response="melt")
        assert sess.version == version
        same_state(sess.state(), before)
        pushed(sess, a)
        sess.merge()
        after, version = sess.state(), sess.version
        with pytest.raises(InvalidArgumentError):
            sess.intersection_curves(refine_angle=-1.0)
        # Nothing colliding after a merge: an empty merge, nothing changes.
        empty = sess.merge()
        assert empty.removed.size == 0 and sess.version == version
        same_state(sess.state(), after)


def test_undo_redo_of_merges_in_random_sequences() -> None:
    a = approach(spacing=0.05)
    sess = LocalSession("random")
    load(sess, a)
    rng = random.Random(5)
    before: List[State] = []  # the state before each applied op (a stack, as the history)
    undone: List[State] = []  # the state after each undone op (the redo tail)
    counts: Dict[str, int] = {"merge": 0, "undo": 0, "redo": 0}
    for _ in range(40):
        what = rng.randrange(10)
        if what < 4:
            before.append(sess.state())
            sess.deform(translation=(0, 0, -a.spacing * rng.choice([1.0, 2.0, 3.0])))
            undone.clear()
        elif what < 6:
            b, v = sess.state(), sess.version
            sess.merge(crease=rng.random() < 0.7)
            if sess.version == v:
                continue
            before.append(b)
            undone.clear()
            counts["merge"] += 1
        elif what < 9 and before:
            now = sess.state()
            sess.undo()
            same_state(sess.state(), before.pop())
            undone.append(now)
            counts["undo"] += 1
        elif undone:
            now = sess.state()
            sess.redo()
            same_state(sess.state(), undone.pop())
            before.append(now)
            counts["redo"] += 1
    assert counts["merge"] > 0 and counts["undo"] > 0
