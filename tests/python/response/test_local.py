"""Responses and the edit history in-process (LocalSession), against exact truth: independent copies of
the arrays for cancel and undo / redo, the plate's exact SDF for back-off (issue 9 §1, §2, §4)."""

from __future__ import annotations

from typing import List

import numpy as np
import pytest

from surfeledit import ConflictError, InvalidArgumentError, LocalSession
from surfeledit.scenes import SceneSetup

from .conftest import approach


def open_session(a: SceneSetup, **settings: object) -> LocalSession:
    s = LocalSession("response")
    s.load_points(a.positions, a.normals, a.radii)
    s.set_regions(zero=a.zero, one=a.one)
    if settings:
        s.configure(**settings)
    return s


def snapshot(s: LocalSession) -> tuple:
    """Independent copies of what a user observes (not the state hash alone)."""
    st = s.state()
    return (st.ids.copy(), st.positions.copy(), st.normals.copy(), st.radii.copy(), s.colliding().copy(),
            s.core.state_hash)


def assert_same(a: tuple, b: tuple) -> None:
    for x, y in zip(a[:5], b[:5]):
        assert x.shape == y.shape and np.array_equal(x, y)  # bit for bit (no tolerance)
    assert a[5] == b[5]


def test_cancel_restores_everything_bit_for_bit(plate_and_ball: SceneSetup) -> None:
    s = open_session(plate_and_ball, response="cancel")
    before = snapshot(s)
    version = s.version
    r = s.deform(translation=(0, 0, -8 * plate_and_ball.spacing))
    assert r.response == "cancelled"
    assert r.colliding.size > 0  # what would have collided
    assert_same(snapshot(s), before)
    assert s.version == version
    assert s.history()[-1].op == "configure"  # a cancelled step leaves no entry


@pytest.mark.parametrize("offset,scale", [(0.0, 1.0), (1e6, 1.0), (0.0, 1e-4), (0.0, 1e4)])
@pytest.mark.parametrize("angle", [0.0, 0.3])
def test_backoff_touches_without_penetrating(offset: float, scale: float, angle: float) -> None:
    a = approach(offset=offset, scale=scale)
    h = a.spacing
    s = open_session(a, response="backoff")
    r = s.deform(translation=(0, 0, -8 * h), angle=angle, axis=(1, 0, 0))
    assert r.response == "backed_off"
    d = a.truth_sdf(s.state().positions[a.one])
    assert d.min() >= -0.25 * h, f"inside by {-d.min() / h:.3f} spacings"
    assert d.min() <= 1.0 * h, f"over-retreated: closest {d.min() / h:.3f} spacings"
    assert 1 <= r.backoff.iterations <= 20
    assert 0.0 < r.backoff.kept < 1.0
    # The ball started 2 spacings above the plate: about 2/8 of the step fits.
    assert abs(r.backoff.kept - 0.25) < 0.125
    assert r.backoff.final_depth >= 0.0


def test_bad_response_arguments_change_nothing(plate_and_ball: SceneSetup) -> None:
    s = open_session(plate_and_ball)
    settings, before = s.settings(), snapshot(s)
    for bad in ({"response": "melt"}, {"response": "nope"}, {"backoff_epsilon": -1.0},
                {"backoff_max_iterations": 0}, {"history_mb": -1.0}):
        with pytest.raises(InvalidArgumentError) as e:
            s.configure(**bad)
        assert e.value.field == next(iter(bad))
    assert s.settings() == settings
    assert_same(snapshot(s), before)


def test_nothing_to_undo_or_redo_is_conflict() -> None:
    s = LocalSession("empty")
    with pytest.raises(ConflictError):
        s.undo()
    with pytest.raises(ConflictError):
        s.redo()


def test_random_sequences_against_snapshots() -> None:
    a = approach(spacing=0.05)
    s = open_session(a)
    rng = np.random.default_rng(3)
    before: List[tuple] = []  # before each applied op
    undone: List[tuple] = []  # after each undone op
    for _ in range(80):
        what = rng.integers(10)
        if what < 4:
            b = snapshot(s)
            r = s.deform(translation=(0, 0, -a.spacing * rng.uniform(1, 4)), angle=rng.uniform(-0.2, 0.2),
                         axis=(1, 0, 0))
            if r.response == "cancelled":
                assert_same(snapshot(s), b)
                continue
            before.append(b)
            undone.clear()
        elif what < 5:
            ids = s.state().ids
            victim = int(ids[rng.integers(ids.size)])
            if victim in (int(a.zero[0]), int(a.one[0])):
                continue
            before.append(snapshot(s))
            s.remove([victim])
            undone.clear()
        elif what < 6:
            before.append(snapshot(s))
            s.configure(response=str(rng.choice(["report", "cancel", "backoff"])))
            undone.clear()
        elif what < 9 and before:
            now = snapshot(s)
            s.undo()
            assert_same(snapshot(s), before.pop())
            undone.append(now)
        elif undone:
            now = snapshot(s)
            s.redo()
            assert_same(snapshot(s), undone.pop())
            before.append(now)
    assert [h.op for h in s.history()][:2] == ["load", "set_regions"]
