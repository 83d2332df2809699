"""surfeledit.core.KdTree against scipy's cKDTree (an independent implementation)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from surfeledit import core
from surfeledit.errors import InvalidArgumentError


def _clouds():
    rng = np.random.default_rng(7)
    line = np.zeros((200, 3))
    line[:, 0] = rng.random(200)
    plane = np.c_[rng.random((300, 2)), np.zeros(300)]
    dup = np.repeat(rng.random((30, 3)), 5, axis=0)
    direction = np.array([0.48, -0.6, 0.64])
    return {
        "tilted_line": rng.random((300, 1)) * direction + 1e-9 * rng.standard_normal((300, 3)),
        "tilted_plane": rng.random((400, 1)) * direction + rng.random((400, 1)) * np.array([0.8, 0.6, 0.0]),
        "random": rng.random((5000, 3)),
        "collinear": line,
        "coplanar": plane,
        "duplicates": dup,
        "single": np.array([[0.3, -2.0, 5.0]]),
        "far_from_origin": rng.random((2000, 3)) * 1e-3 + 1e6,
    }


@pytest.mark.parametrize("name", list(_clouds()))
@pytest.mark.parametrize("leaf_size", [1, 10, 50])
@pytest.mark.parametrize("align", [False, True])
def test_knn_matches_scipy(name: str, leaf_size: int, align: bool) -> None:
    pts = _clouds()[name]
    rng = np.random.default_rng(1)
    lo, hi = pts.min(0), pts.max(0)
    queries = lo + (hi - lo + 1e-9) * rng.random((300, 3))
    k = min(8, len(pts))
    tree = core.KdTree(pts, leaf_size=leaf_size, align=align)
    if name.startswith("tilted") and align:
        assert not np.allclose(tree.axes, np.eye(3))  # turned: the answers below come from the turned frame
    idx, dist2 = tree.knn(queries, k)
    ref_d, _ = cKDTree(pts).query(queries, k)
    ref_d = np.asarray(ref_d).reshape(len(queries), k)
    # Ties may pick different points: compare distances, and that indices give those distances.
    scale = max(1.0, float(np.abs(pts).max()))
    np.testing.assert_allclose(np.sqrt(dist2), ref_d, rtol=1e-9, atol=1e-12 * scale)
    recomputed = np.linalg.norm(pts[idx] - queries[:, None, :], axis=2)
    np.testing.assert_allclose(recomputed, np.sqrt(dist2), rtol=1e-9, atol=1e-12 * scale)


def test_knn_pads_when_k_exceeds_points() -> None:
    pts = np.random.default_rng(2).random((3, 3))
    idx, dist2 = core.KdTree(pts).knn(np.zeros((2, 3)), 5)
    assert idx.shape == (2, 5)
    assert (idx[:, 3:] == -1).all() and np.isinf(dist2[:, 3:]).all()
    assert sorted(idx[0, :3]) == [0, 1, 2]


@pytest.mark.parametrize("name", ["random", "duplicates", "coplanar"])
def test_radius_matches_scipy(name: str) -> None:
    pts = _clouds()[name]
    queries = np.random.default_rng(3).random((200, 3))
    r = 0.08
    idx, dist2 = core.KdTree(pts).radius(queries, r)
    ref = cKDTree(pts).query_ball_point(queries, r)
    assert len(idx) == len(queries)
    for mine, d2, theirs, q in zip(idx, dist2, ref, queries):
        assert sorted(mine.tolist()) == sorted(theirs)
        assert np.all(np.diff(d2) >= 0)  # ascending by distance
        np.testing.assert_allclose(d2, ((pts[mine] - q) ** 2).sum(1), rtol=1e-12)


def test_empty_query_set() -> None:
    tree = core.KdTree(np.random.default_rng(4).random((10, 3)))
    idx, dist2 = tree.knn(np.zeros((0, 3)), 3)
    assert idx.shape == (0, 3) and dist2.shape == (0, 3)
    ridx, rd2 = tree.radius(np.zeros((0, 3)), 0.1)
    assert ridx == [] and rd2 == []


def test_bad_input_is_typed() -> None:
    with pytest.raises(InvalidArgumentError) as e:
        core.KdTree(np.zeros((4, 2)))
    assert e.value.field == "points"
    with pytest.raises(InvalidArgumentError):
        core.KdTree(np.array([[0.0, np.nan, 0.0]]))
    with pytest.raises(InvalidArgumentError) as e:
        core.KdTree(np.zeros((4, 3)), leaf_size=0)
    assert e.value.field == "leaf_size"
    with pytest.raises(InvalidArgumentError):
        core.KdTree(np.zeros((4, 3))).knn(np.zeros((1, 3)), 0)


@pytest.mark.parametrize("scale", [1e-4, 1.0, 1e4])
def test_batch_knn_at_million_offset_matches_scipy(scale: float) -> None:
    """A cloud at 1e6 from the origin, queries in random order: the batch (answered internally along a
    space-filling curve) comes back in the caller's order with scipy's distances. Rounding bound: each world
    coordinate is off by <= delta = 1e6 * 2**-52, so a distance is off by <= sqrt(3) * 2 * delta."""
    rng = np.random.default_rng(11)
    offset = np.array([1e6, -1e6, 1e6])
    local = scale * rng.random((70_000, 3))  # above 2**16 points: batches go along the Morton curve
    queries_local = scale * (1.2 * rng.random((3_000, 3)) - 0.1)
    pts, queries = local + offset, queries_local + offset
    tree = core.KdTree(pts, threads=2)
    ref = cKDTree(local)  # scipy on the exact local offsets: the truth
    delta = 1e6 * 2.0**-52
    for k in (1, 10):
        idx, dist2 = tree.knn(queries, k)
        ref_d, _ = ref.query(queries_local, k)
        ref_d = np.asarray(ref_d).reshape(len(queries), k)
        np.testing.assert_allclose(np.sqrt(dist2), ref_d, rtol=0, atol=4 * delta)
        recomputed = np.linalg.norm(local[idx] - queries_local[:, None, :], axis=2)
        np.testing.assert_allclose(recomputed, ref_d, rtol=0, atol=4 * delta)


def test_align_turns_a_tilted_slab_and_matches_scipy() -> None:
    """align=True on a two-sided slab turned against the axes: the tree's axes are orthonormal and one of them is the
    slab's normal, and k = 1 and k = 6 answers are scipy's (the turned frame rounds differently: ~1e-16 of the size).
    The same slab upright keeps the world axes and the same answers as without align."""
    rng = np.random.default_rng(17)
    u, v = np.meshgrid(np.arange(80) * 0.01, np.arange(80) * 0.01)
    face = np.c_[u.ravel(), v.ravel(), 1e-4 * rng.standard_normal(u.size)]
    slab = np.r_[face, face + [0.0, 0.0, 0.08]]
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    c, s = np.cos(0.6), np.sin(0.6)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    turn = np.eye(3) + s * k + (1 - c) * k @ k  # Rodrigues
    tilted = slab @ turn.T + [5.0, -3.0, 2.0]
    queries = tilted[rng.integers(0, len(tilted), 500)] + 0.2 * rng.standard_normal((500, 3))
    tree = core.KdTree(tilted, leaf_size=32, align=True)
    axes = tree.axes
    np.testing.assert_allclose(axes @ axes.T, np.eye(3), atol=1e-14)
    assert np.abs(axes @ (turn @ [0.0, 0.0, 1.0])).max() > np.cos(1e-3)
    ref = cKDTree(tilted)
    for kk in (1, 6):
        idx, dist2 = tree.knn(queries, kk)
        ref_d, _ = ref.query(queries, kk)
        ref_d = np.asarray(ref_d).reshape(len(queries), kk)
        np.testing.assert_allclose(np.sqrt(dist2), ref_d, rtol=1e-12, atol=1e-13)
        recomputed = np.linalg.norm(tilted[idx] - queries[:, None, :], axis=2)
        np.testing.assert_allclose(recomputed, ref_d, rtol=1e-12, atol=1e-13)
    upright = slab + [5.0, -3.0, 2.0]
    plain, turned = core.KdTree(upright, leaf_size=32), core.KdTree(upright, leaf_size=32, align=True)
    np.testing.assert_array_equal(turned.axes, np.eye(3))
    for a, b in zip(plain.knn(queries, 6), turned.knn(queries, 6)):
        np.testing.assert_array_equal(a, b)
