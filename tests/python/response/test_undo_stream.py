"""Undo and redo of every op kind reach the update stream (issue 9 §1): a watcher that applies what it
hears stays equal to GET_STATE after each undo and redo of load (down to the empty model before the first
load), set_regions, configure, deform, remove and merge. Real server, own DDS domain."""

from __future__ import annotations

from typing import Dict, Tuple

import numpy as np
import pytest

import surfeledit
from surfeledit import ConflictError

from .conftest import approach
from .test_dds import load_and_watch

Row = Tuple[np.ndarray, np.ndarray, float]


def hear(w: surfeledit.Watcher, mirror: Dict[int, Row], version: int) -> None:
    """Applies updates until the one of `version` arrived."""
    while True:
        ev = w.get(timeout=5.0)
        assert ev is not None, f"no update of version {version} arrived"
        if ev.full:
            mirror.clear()
        for i in ev.removed:
            mirror.pop(int(i), None)
        for k, i in enumerate(ev.ids):
            mirror[int(i)] = (ev.positions[k].copy(), ev.normals[k].copy(), float(ev.radii[k]))
        if ev.version >= version:
            assert ev.version == version
            return


def expect_mirror(sess: surfeledit.Session, mirror: Dict[int, Row], what: str) -> None:
    try:
        st = sess.state()
    except ConflictError:  # no model: the watcher must have emptied its copy
        assert not mirror, f"{what}: the watcher still holds {len(mirror)} surfels of an empty session"
        return
    assert sorted(mirror) == [int(i) for i in st.ids], what
    rows = [mirror[int(i)] for i in st.ids]
    assert np.array_equal(np.array([r[0] for r in rows]).reshape(-1, 3), st.positions), what
    assert np.array_equal(np.array([r[1] for r in rows]).reshape(-1, 3), st.normals), what
    assert np.array_equal(np.array([r[2] for r in rows], dtype=np.float64), st.radii), what


def test_watcher_stays_exact_through_undo_and_redo_of_every_op(client: surfeledit.Client) -> None:
    a = approach(spacing=0.05)
    with client.open_session("stream") as sess:
        w = load_and_watch(sess, a)  # load, then set_regions until the watcher hears
        mirror: Dict[int, Row] = {}
        st = sess.state()
        for k, i in enumerate(st.ids):
            mirror[int(i)] = (st.positions[k], st.normals[k], float(st.radii[k]))
        sess.configure(response="report", algorithm="robust")
        r = sess.deform(translation=(0, 0, -5 * a.spacing))
        assert r.colliding.size > 0
        hear(w, mirror, sess.version)
        sess.remove([int(a.one[3])])
        hear(w, mirror, sess.version)
        m = sess.merge()
        assert m.removed.size > 0
        hear(w, mirror, sess.version)
        expect_mirror(sess, mirror, "after the merge")
        ops = [h.op for h in sess.history()]
        assert ops[0] == "load" and ops[-4:] == ["configure", "deform", "remove", "merge"]
        for op in reversed(ops):
            sess.undo()
            hear(w, mirror, sess.version)
            expect_mirror(sess, mirror, f"undo of {op}")
        assert not mirror  # the first load undone
        with pytest.raises(ConflictError):
            sess.undo()
        for op in ops:
            sess.redo()
            hear(w, mirror, sess.version)
            expect_mirror(sess, mirror, f"redo of {op}")
        w.close()
