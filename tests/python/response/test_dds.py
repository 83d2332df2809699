"""Responses and the edit history over DDS with a real server (one per test, own domain): every response
equals the in-process result, undo / redo / history round-trip, a watcher stays exact through undo and
redo, and bad arguments are typed errors that change nothing (issue 9 §1, §2, §4)."""

from __future__ import annotations

from typing import Dict, List, Tuple

import numpy as np
import pytest

import surfeledit
from surfeledit import ConflictError, InvalidArgumentError, LocalSession, State
from surfeledit.results import Changes, merge
from surfeledit.scenes import SceneSetup

from .conftest import approach

STEPS = [dict(translation=(0, 0, -3.0)), dict(translation=(0, 0, -3.0), angle=0.2, axis=(1, 0, 0)),
         dict(translation=(0, 0, -5.0))]  # in spacings


def steps(h: float):
    for st in STEPS:
        yield {**st, "translation": tuple(h * np.asarray(st["translation"]))}


def load(session, a: SceneSetup) -> None:
    session.load_points(a.positions, a.normals, a.radii)
    session.set_regions(zero=a.zero, one=a.one)


@pytest.mark.parametrize("response", ["report", "cancel", "backoff", "merge"])
def test_responses_equal_in_process(client: surfeledit.Client, response: str) -> None:
    a = approach(spacing=0.05)
    local = LocalSession("local")
    load(local, a)
    local.configure(response=response)
    with client.open_session("r") as sess:
        load(sess, a)
        sess.configure(response=response)
        for st in steps(a.spacing):
            want, got = local.deform(**st), sess.deform(**st)
            assert got.response == want.response
            assert np.array_equal(got.colliding, want.colliding)
            assert np.array_equal(got.depths, want.depths)
            assert got.backoff == want.backoff
            assert np.array_equal(got.features, want.features)
            assert got.version == want.version
        assert np.array_equal(sess.state().positions, local.state().positions)
        assert sess.info().state_hash == local.core.state_hash


def load_and_watch(sess: surfeledit.Session, a: SceneSetup) -> surfeledit.Watcher:
    """Loads `a` and returns a watcher that has heard the session: updates are volatile, so the regions
    are re-set until one arrives (see test_collision_dds); what it heard is drained."""
    load(sess, a)
    w = sess.watch()
    for _ in range(20):
        sess.set_regions(zero=a.zero, one=a.one)
        if w.get(timeout=0.5) is not None:
            break
    while w.get(timeout=0.2) is not None:
        pass
    return w


def apply_updates(w: surfeledit.Watcher, cache: State, n: int) -> Tuple[State, List[str]]:
    """Waits for the next `n` updates of `w`, applies each to `cache` (the client's own merge) and
    returns the result and the updates' causes in arrival order."""
    causes: List[str] = []
    while len(causes) < n:
        ev = w.get(timeout=5.0)
        assert ev is not None, f"only {causes} arrived"
        causes.append(ev.cause)
        cache = merge(cache, Changes(ev.version, ev.full, ev.ids, ev.positions, ev.normals, ev.radii,
                                     ev.removed, ev.clips))
    return cache, causes


def test_undo_redo_history_and_watcher(client: surfeledit.Client) -> None:
    a = approach(spacing=0.05)
    with client.open_session("h") as sess:
        w = load_and_watch(sess, a)
        base = sess.state()
        known: Dict[int, np.ndarray] = {int(i): p for i, p in zip(base.ids, base.positions)}
        before = sess.state().positions.copy()
        hash_before = sess.info().state_hash
        r = sess.deform(translation=(0, 0, -5 * a.spacing))
        assert r.colliding.size > 0
        sess.remove([int(a.one[1])])
        v = sess.undo()
        assert v == sess.version
        sess.undo()
        assert np.array_equal(sess.state().positions, before)
        assert sess.info().state_hash == hash_before
        v = sess.redo()
        hist = sess.history()
        assert [h.op for h in hist][-2:] == ["deform", "remove"]
        assert hist[-1].undone and not hist[-2].undone
        assert all(h.client == client.client_id for h in hist)
        # The watcher saw deform, remove, undo, undo, redo; applying them gives the server's state.
        causes = []
        while len(causes) < 5:
            ev = w.get(timeout=5.0)
            assert ev is not None, f"only {causes} arrived"
            causes.append(ev.cause)
            for i in ev.removed:
                known.pop(int(i), None)
            for i, p in zip(ev.ids, ev.positions):
                known[int(i)] = p
        assert causes == ["deform", "remove", "undo", "undo", "redo"]
        assert ev.detected and np.array_equal(ev.colliding, r.colliding)
        st = sess.state()
        assert sorted(known) == [int(i) for i in st.ids]
        assert np.array_equal(np.array([known[int(i)] for i in st.ids]), st.positions)
        w.close()


def test_bad_arguments_are_typed_and_change_nothing(client: surfeledit.Client) -> None:
    a = approach(spacing=0.05)
    with client.open_session("bad") as sess:
        with pytest.raises(ConflictError):
            sess.undo()
        load(sess, a)
        info, version = sess.info(), sess.version
        for bad in ({"response": "unknown"}, {"response": "melt"}, {"backoff_epsilon": -1e-3}):
            with pytest.raises(InvalidArgumentError) as e:
                sess.configure(**bad)
            assert e.value.field == next(iter(bad))
        after = sess.info()
        assert after.state_hash == info.state_hash and sess.version == version
        assert sess.settings()["response"] == "report"
        with pytest.raises(ConflictError):
            sess.redo()
