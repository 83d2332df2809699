"""The compact encoding's normal decoder (surfeledit/compact.py) against unit normals encoded here with the
octahedral map (Meyer et al. 2010; PROTOCOL.md "Updates, compact"): every decoded normal is a unit vector within
OCTAHEDRAL_MAX_ANGLE of the normal encoded, over random directions, the axes, and both sides of the fold."""

from __future__ import annotations

import numpy as np

from surfeledit.compact import OCTAHEDRAL_MAX_ANGLE, octahedral_decode


def encode(n: np.ndarray) -> np.ndarray:
    """(N, 2) int16 octahedral coordinates (times 32767, rounded) of unit normals n (N, 3)."""
    p = n / np.abs(n).sum(axis=1, keepdims=True)
    xy = p[:, :2].copy()
    lower = p[:, 2] < 0.0
    sign = np.where(xy[lower] < 0.0, -1.0, 1.0)
    xy[lower] = (1.0 - np.abs(p[lower][:, [1, 0]])) * sign
    return np.round(xy * 32767.0).astype(np.int16)


def test_decoded_normals_are_unit_and_within_the_stated_angle() -> None:
    rng = np.random.default_rng(2)
    random = rng.normal(size=(100_000, 3))
    axes = np.vstack([np.eye(3), -np.eye(3)])
    # Near the fold (z ~ 0) and near the lower pole, where the folded coordinates are largest.
    fold = np.column_stack([rng.normal(size=(2000, 2)), rng.normal(scale=1e-6, size=2000)])
    pole = np.column_stack([rng.normal(scale=1e-3, size=(2000, 2)), -np.ones(2000)])
    normals = np.vstack([random, axes, fold, pole])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    got = octahedral_decode(encode(normals).ravel())
    assert got.shape == normals.shape
    assert np.abs(np.linalg.norm(got, axis=1) - 1.0).max() < 1e-15 * 8
    angle = np.arccos(np.clip((got * normals).sum(axis=1), -1.0, 1.0))
    assert angle.max() <= OCTAHEDRAL_MAX_ANGLE, f"largest angle {angle.max():.3g} rad"
    # The lower half is unfolded: z keeps its sign wherever it is clearly nonzero.
    clear = np.abs(normals[:, 2]) > 1e-4
    assert np.array_equal(np.sign(got[clear, 2]), np.sign(normals[clear, 2]))
