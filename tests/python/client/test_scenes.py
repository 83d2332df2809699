"""surfeledit.scenes helpers against brute force."""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist

from surfeledit.scenes import seam_points


def _brute_seam(positions: np.ndarray, zero: np.ndarray, spacing: float) -> np.ndarray:
    mask = np.zeros(positions.shape[0], bool)
    mask[zero] = True
    d = cdist(positions[mask], positions[~mask]).min(axis=1)
    return positions[mask][d < 1.5 * spacing]


def test_seam_points_equal_brute_force_near_and_far() -> None:
    # A zero plane with a deformable cluster touching part of it and one far away; some zero points sit exactly at
    # 1.5 spacings from a deformable one (excluded: strictly closer counts).
    rng = np.random.default_rng(7)
    spacing = 0.1
    plane = np.stack(np.meshgrid(np.arange(30) * spacing, np.arange(30) * spacing, [0.0]), -1).reshape(-1, 3)
    near = rng.uniform([0.5, 0.5, 0.02], [1.2, 1.2, 0.4], (200, 3))
    far = rng.uniform([50.0, 50.0, 50.0], [51.0, 51.0, 51.0], (200, 3))
    exact = plane[:5] + np.array([0.0, 0.0, 1.5 * spacing])  # at exactly 1.5 spacings above plane[:5]
    positions = np.vstack([plane, near, far, exact])
    zero = np.arange(plane.shape[0])
    got = seam_points(positions, zero, spacing)
    want = _brute_seam(positions, zero, spacing)
    assert got.shape[0] > 0 and got.shape[0] < plane.shape[0]
    np.testing.assert_array_equal(got, want)


def test_seam_points_all_zero_is_empty() -> None:
    positions = np.zeros((4, 3))
    assert seam_points(positions, np.arange(4), 0.1).shape == (0, 3)
