"""Collision detection over DDS with a real server: configure, remove, and a scripted scenario whose
colliding ids must equal the in-process EditSession's (issue 3)."""

from __future__ import annotations

from typing import Any, Dict, List

import numpy as np
import pytest

import surfeledit
from surfeledit import core
from surfeledit.errors import ConflictError, InvalidArgumentError, NotFoundError

ALGORITHMS = ["simple", "improved", "temporal", "robust"]
STEPS = 10
PUSH = (0.0, 0.0, -0.06)  # per step: the sphere (bottom at z 0.5) ends 0.1 below the slab top (z 0.15)


def default_scene() -> Any:
    """The default scene at spacing 0.05: part 0 the slab (zero region), part 1 the sphere (one region)."""
    return core.make_default_scene().sample(spacing=0.05)


def load(session: surfeledit.Session, s: Any) -> None:
    session.load_points(s.positions, s.normals, s.radii)
    part = np.asarray(s.part)
    session.set_regions(zero=np.flatnonzero(part == 0), one=np.flatnonzero(part == 1))


def synced_watcher(sess: surfeledit.Session, zero: np.ndarray, one: np.ndarray) -> surfeledit.Watcher:
    """A watcher the server's update writer has surely matched: Update is volatile, and the watcher only
    knows that its reader matched the writer, not the reverse. Re-sets the (same) regions until their
    update arrives; this changes nothing but the version."""
    w = sess.watch()
    for _ in range(20):
        sess.set_regions(zero=zero, one=one)
        ev = w.get(timeout=0.5)
        if ev is not None:
            while w.get(timeout=0.2) is not None:  # drain the other probes' updates
                pass
            return w
    w.close()
    pytest.fail("the server's update writer never matched the watcher")


def in_process_session(s: Any) -> Any:
    if not hasattr(core, "EditSession") or not hasattr(core.EditSession, "configure"):
        pytest.skip("surfeledit.core.EditSession.configure (in-process collision detection) is not built yet")
    es = core.EditSession("in-process")
    es.load_points(s.positions, s.normals, s.radii)
    part = np.asarray(s.part)
    es.set_regions(zero=np.flatnonzero(part == 0), one=np.flatnonzero(part == 1))
    return es


def test_configure_switches_algorithms_without_losing_the_model(client: surfeledit.Client) -> None:
    s = default_scene()
    with client.open_session("cfg") as sess:
        load(sess, s)
        sess.deform(translation=PUSH)
        before = sess.info()
        version = sess.version
        assert before.settings, "session info lists the settings"
        assert sess.settings()["algorithm"] == "robust"
        for algorithm in ALGORITHMS + ["none", "robust"]:
            info = sess.configure(algorithm=algorithm)
            assert {st.name: st for st in info.settings}["algorithm"].text == algorithm
            assert int(info.state_hash) == int(before.state_hash)
            assert int(info.surfels) == int(before.surfels)
            assert sess.settings()["algorithm"] == algorithm
            assert sess.version == version
        # Several settings at once, each kind by its Python type.
        sess.configure(algorithm="temporal", boundary_n=8, boundary_i=3, step_bound=False, threshold=0.001)
        got = sess.settings()
        assert got["algorithm"] == "temporal"
        assert got["boundary_n"] == 8 and got["boundary_i"] == 3
        assert got["step_bound"] is False
        assert got["threshold"] == pytest.approx(0.001)
        assert int(sess.info().state_hash) == int(before.state_hash)
        # The model still deforms and detects after the switches.
        step = sess.deform(translation=PUSH)
        assert step.detected


@pytest.mark.parametrize("settings, field", [
    ({"no_such_setting": 1}, "no_such_setting"),
    ({"boundary_n": -1}, "boundary_n"),
    ({"algorithm": "bogus"}, "algorithm"),
    ({"boundary_n": "ten"}, "boundary_n"),
    ({"boundary_n": 2.5}, "boundary_n"),
    ({"step_bound": 1}, "step_bound"),
    # A valid setting with a bad one: neither is applied.
    ({"algorithm": "simple", "boundary_n": -1}, "boundary_n"),
    ({"boundary_n": 4, "algorithm": "bogus"}, "algorithm"),
])
def test_bad_settings_are_typed_errors_and_change_nothing(client: surfeledit.Client, settings: Dict[str, Any],
                                                         field: str) -> None:
    s = default_scene()
    with client.open_session("bad") as sess:
        load(sess, s)
        before_settings = sess.settings()
        before = sess.info()
        version = sess.version
        with pytest.raises(InvalidArgumentError) as e:
            sess.configure(**settings)
        assert e.value.field == field
        assert "must be a bool" not in e.value.message  # the server's verdict, not a client-side check
        assert field in str(e.value)
        assert sess.settings() == before_settings
        after = sess.info()
        assert int(after.state_hash) == int(before.state_hash)
        assert sess.version == version


def test_unsupported_setting_types_are_refused_by_the_client(client: surfeledit.Client) -> None:
    with client.open_session("client-side") as sess:
        for value in ([1, 2], None, {"a": 1}, b"robust"):
            with pytest.raises(InvalidArgumentError) as e:
                sess.configure(algorithm=value)
            assert e.value.field == "algorithm"
            assert "must be a bool, a number or a string" in e.value.message  # refused before sending
        assert sess.settings()["algorithm"] == "robust"


def test_remove_over_dds(client: surfeledit.Client) -> None:
    s = default_scene()
    part = np.asarray(s.part)
    with client.open_session("rm") as sess:
        load(sess, s)
        ids0 = sess.ids().copy()
        pos0 = sess.positions().copy()
        with synced_watcher(sess, np.flatnonzero(part == 0), np.flatnonzero(part == 1)) as w:
            version0 = sess.version
            hash0 = int(sess.info().state_hash)
            with pytest.raises(NotFoundError) as e:
                sess.remove([3, 10**9])
            assert e.value.field.startswith("remove")
            with pytest.raises(ConflictError):
                sess.remove(np.flatnonzero(part == 1))  # would leave the one region empty
            with pytest.raises(ConflictError):
                sess.remove(np.flatnonzero(part == 0))  # would leave the zero region empty
            with pytest.raises(InvalidArgumentError):
                sess.remove([])
            assert int(sess.info().state_hash) == hash0
            assert sess.version == version0
            assert np.array_equal(sess.ids(), ids0)

            gone = np.array([7, 12, int(np.flatnonzero(part == 1)[0]), 4000], dtype=np.uint64)
            info = sess.remove(gone[::-1])
            assert int(info.surfels) == len(ids0) - len(gone)
            assert sess.version == version0 + 1
            ev = w.get(timeout=10)
            assert ev is not None, "no update for the removal"
            assert ev.cause == "remove"
            assert ev.version == version0 + 1
            assert np.array_equal(ev.removed, np.sort(gone))
            assert ev.ids.size == 0 and not ev.full

        # Ids stay stable: the others keep their id and attributes.
        keep = ~np.isin(ids0, gone)
        assert np.array_equal(sess.ids(), ids0[keep])
        np.testing.assert_array_equal(sess.positions(), pos0[keep])
        ch = sess.changes_since(version0)
        assert np.array_equal(np.sort(ch.removed), np.sort(gone))
        # Removed ids are gone for good.
        with pytest.raises(NotFoundError):
            sess.remove([7])
        # The session still deforms with detection after the removal.
        step = sess.deform(translation=PUSH)
        assert step.detected


@pytest.mark.parametrize("algorithm", ALGORITHMS)
def test_scripted_scenario_matches_in_process(client: surfeledit.Client, algorithm: str) -> None:
    s = default_scene()
    local = in_process_session(s)
    local.configure(algorithm=algorithm)
    with client.open_session(f"scenario-{algorithm}") as sess:
        load(sess, s)
        sess.configure(algorithm=algorithm)
        remote_settings, local_settings = sess.settings(), local.settings()
        assert remote_settings["algorithm"] == local_settings["algorithm"] == algorithm
        for name in set(remote_settings) & set(local_settings):  # both builds' settings agree
            assert remote_settings[name] == local_settings[name], name
        part = np.asarray(s.part)
        with synced_watcher(sess, np.flatnonzero(part == 0), np.flatnonzero(part == 1)) as w:
            sess.configure(algorithm=algorithm)  # a fresh detector after the probes (as in-process)
            remote_steps: List[surfeledit.StepResult] = []
            for i in range(STEPS):
                r = sess.deform(translation=PUSH)
                want = local.deform(translation=PUSH)
                assert r.detected and bool(want.detected)
                np.testing.assert_array_equal(r.colliding, np.asarray(want.colliding, dtype=np.uint64),
                                              err_msg=f"{algorithm}, step {i + 1}")
                assert r.colliding.dtype == np.uint64 and r.depths.dtype == np.float64
                np.testing.assert_allclose(r.depths, np.asarray(want.depths), rtol=0, atol=1e-12)
                assert r.stats.colliding == r.colliding.size
                assert r.stats.deformable == int(want.stats["deformable"])
                assert r.stats.queries == int(want.stats["queries"])
                assert r.stats.asleep == int(want.stats["asleep"])
                assert r.stats.tested + r.stats.asleep <= r.stats.deformable
                assert np.all(np.diff(r.colliding.astype(np.int64)) > 0)
                assert r.inserted.size == 0
                remote_steps.append(r)
            np.testing.assert_array_equal(np.asarray(local.colliding(), dtype=np.uint64), remote_steps[-1].colliding)
            assert remote_steps[-1].colliding.size > 0, f"{algorithm}: the sphere pushed into the slab never collides"
            assert remote_steps[0].colliding.size == 0, "nothing collides before contact"
            assert np.all(part[remote_steps[-1].colliding.astype(np.int64)] == 1)

            # The update stream carries each step's collision state.
            events = []
            while len(events) < STEPS:
                ev = w.get(timeout=10)
                assert ev is not None, f"only {len(events)} of {STEPS} deform updates arrived"
                events.append(ev)
            for r, ev in zip(remote_steps, events):
                assert ev.cause == "deform" and ev.step == r.seq and ev.version == r.version
                assert ev.detected
                np.testing.assert_array_equal(ev.colliding, r.colliding)
                assert ev.ids.size == r.moved


@pytest.mark.parametrize("algorithm", ["temporal", "robust"])
def test_an_idle_step_reports_its_sleeping_rows(client: surfeledit.Client, algorithm: str) -> None:
    """A tiny translation far from contact: the sphere's rows stay inside their quiet spheres, so most of them are
    not read (stats.asleep), the result is the in-process session's, and nothing collides."""
    s = default_scene()
    local = in_process_session(s)
    local.configure(algorithm=algorithm)
    nudge = (0.0, 0.0, -1e-6)
    with client.open_session(f"idle-{algorithm}") as sess:
        load(sess, s)
        sess.configure(algorithm=algorithm)
        for i in range(3):  # the first step reads every row; the next ones may sleep
            r = sess.deform(translation=nudge)
            want = local.deform(translation=nudge)
            assert r.stats.asleep == int(want.stats["asleep"]), f"step {i + 1}"
            assert r.stats.tested == int(want.stats["tested"]), f"step {i + 1}"
            assert r.colliding.size == 0 == len(want.colliding)
        assert r.stats.asleep > r.stats.deformable // 2, f"{algorithm}: {r.stats}"
        assert r.stats.tested + r.stats.asleep <= r.stats.deformable


def test_inserted_surfels_reach_the_reply_and_the_update(client: surfeledit.Client) -> None:
    """Dynamic resampling: split surfels get new ids, listed in the step and carried by the update."""
    s = default_scene()
    pos, part = np.asarray(s.positions), np.asarray(s.part)
    with client.open_session("resample") as sess:
        sess.load_points(s.positions, s.normals, s.radii)
        sess.set_regions(zero=np.flatnonzero(part == 0), one=np.flatnonzero((part == 1) & (pos[:, 2] > 1.25)))
        n0 = len(pos)
        with synced_watcher(sess, np.flatnonzero(part == 0), np.flatnonzero((part == 1) & (pos[:, 2] > 1.25))) as w:
            sess.configure(resample=True)
            inserted = []
            for _ in range(4):
                r = sess.deform(translation=(0.0, 0.0, 0.15))  # stretches the sphere's middle
                ev = w.get(timeout=10)
                assert ev is not None and ev.cause == "deform"
                assert np.isin(r.inserted, ev.ids).all(), "inserted ids missing from the update"
                inserted.append(r.inserted)
        new = np.concatenate(inserted)
        assert new.size > 0, "stretching by 0.6 split no surfel"
        assert new.min() >= n0  # new ids, never reused
        assert np.isin(new, sess.ids()).all()
        assert int(sess.info().surfels) == n0 + new.size
