"""No tunnelling (setting ``swept``, docs/algorithms.md §4.7): a ball pushed through a wall 2.5 spacings
thick in 1, 2, 5 and 10 steps. Truth is exact geometry: a ball surfel entered the wall in a step iff
the segment it moved along (a pure translation) meets the wall's box and did not start in it (one that
starts inside was inside at the end of the step before)."""

import numpy as np
import pytest

from surfeledit import scenario as S

SCALE = 0.25  # spacing 0.02: a wall 0.05 thick, ~2k ball surfels


def _segment_meets_box(a, b, half, pad=0.0):
    """(N,) bool: segment a_i -> b_i meets the box |x| <= half + pad (slab test, exact)."""
    lo, hi = -(np.asarray(half) + pad), np.asarray(half) + pad
    t0, t1 = np.zeros(len(a)), np.ones(len(a))
    d = b - a
    for k in range(3):
        with np.errstate(divide="ignore", invalid="ignore"):
            ta, tb = (lo[k] - a[:, k]) / d[:, k], (hi[k] - a[:, k]) / d[:, k]
        flat = d[:, k] == 0
        inside = (a[:, k] >= lo[k]) & (a[:, k] <= hi[k])
        t0 = np.where(flat, np.where(inside, t0, 2.0), np.maximum(t0, np.minimum(ta, tb)))
        t1 = np.where(flat, np.where(inside, t1, -1.0), np.minimum(t1, np.maximum(ta, tb)))
    return t0 <= t1


def _run(steps, algorithm, inside, swept):
    sc = S.make_scenario("thinwall", scale=SCALE, steps=steps)
    scene = sc.scene
    half = np.array([0.8, 0.8, 0.5 * 2.5 * scene.spacing])
    prev = {int(i): scene.positions[i] for i in scene.deformable}
    per_step = []

    def hook(k, _b, out, state):
        ball = ~np.isin(state.ids.astype(np.int64), scene.zero)
        ids, pos = state.ids[ball].astype(np.int64), state.positions[ball]
        a = np.array([prev[int(i)] for i in ids])
        start_inside = np.all(np.abs(a) <= half, axis=1)
        crossed = _segment_meets_box(a, pos, half) & ~start_inside
        near = _segment_meets_box(a, pos, half, pad=scene.spacing)
        reported = np.isin(ids, np.asarray(out.colliding, np.int64))
        per_step.append((int(crossed.sum()), int((crossed & ~reported).sum()), int((reported & ~near).sum())))
        for i, p in zip(ids, pos):
            prev[int(i)] = p

    S.run(sc, algorithm, settings=dict(threads=1, inside=inside, swept=swept), measure=False, after_step=hook)
    return per_step


@pytest.mark.parametrize("inside", ["nearest", "winding", "vote"])
@pytest.mark.parametrize("algorithm", ["temporal", "robust"])
@pytest.mark.parametrize("steps", [1, 2, 5, 10])
def test_every_crossing_surfel_is_reported(steps, algorithm, inside):
    per_step = _run(steps, algorithm, inside, swept=True)
    assert sum(c for c, _, _ in per_step) > 0, "nothing crossed: the test would prove nothing"
    for k, (crossed, missed, spurious) in enumerate(per_step, 1):
        assert missed == 0, f"step {k}: {missed} of {crossed} crossing surfels not reported"
        assert spurious == 0, f"step {k}: {spurious} reported surfels never came within a spacing of the wall"


def test_without_swept_the_single_step_tunnels():
    """The failure the setting fixes: in one step the whole ball passes the wall and nothing is reported."""
    (crossed, missed, _), = _run(1, "temporal", "winding", swept=False)
    assert crossed > 0 and missed == crossed
