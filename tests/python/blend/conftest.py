"""Models for the blend-tool tests (issue 10) and the real-server fixtures of tests/python/service."""

from __future__ import annotations

from typing import Tuple

import numpy as np

from service.conftest import client, make_client, server  # noqa: F401  (fixtures: a real server per test)
from surfeledit import core

Surfels = Tuple[np.ndarray, np.ndarray, np.ndarray]


def sampled(solid, spacing: float, seed: int = 1) -> Surfels:
    s = solid.sample(spacing=spacing, seed=seed)
    return np.asarray(s.positions), np.asarray(s.normals), np.asarray(s.radii)


def two_spheres(spacing: float = 0.05) -> Tuple[Surfels, Surfels]:
    """A (radius 0.5 at the origin) and B (radius 0.4 at (0.5, 0.1, 0)): they overlap."""
    return (sampled(core.make_sphere(0.5), spacing, 1),
            sampled(core.make_sphere(0.4, center=[0.5, 0.1, 0.0]), spacing, 2))


def holed_sphere(spacing: float = 0.04, hole: float = 0.15) -> Surfels:
    """A sphere of radius 0.5 with the samples within `hole` of its north pole cut out."""
    p, n, r = sampled(core.make_sphere(0.5), spacing, 3)
    keep = np.linalg.norm(p - [0.0, 0.0, 0.5], axis=1) > hole
    return p[keep], n[keep], r[keep]
