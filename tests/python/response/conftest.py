"""Scenes with exact truth for the response tests, and the real-server fixtures of tests/python/service."""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np
import pytest

from service.conftest import client, make_client, server  # noqa: F401  (fixtures: a real server per test)
from surfeledit import core


@dataclasses.dataclass(frozen=True)
class Approach:
    """A rigid plate (zero region) and a ball (one region) `gap` spacings above it, optionally moved by
    ``offset`` and scaled by ``scale`` (positions * scale + offset); ``sdf`` is the plate's exact
    signed distance in the same frame."""

    positions: np.ndarray
    normals: np.ndarray
    radii: np.ndarray
    zero: np.ndarray
    one: np.ndarray
    spacing: float
    sdf: Callable[[np.ndarray], np.ndarray]


def approach(spacing: float = 0.03, offset: float = 0.0, scale: float = 1.0, gap: float = 2.0) -> Approach:
    half_t, r = 0.075, 0.4
    plate = core.make_box([0.8, 0.8, half_t])
    scene = core.Scene()
    scene.add(plate)
    scene.add(core.make_sphere(r, center=[0.0, 0.0, half_t + r + gap * spacing]))
    s = scene.sample(spacing=spacing, seed=1)
    part = np.asarray(s.part)

    def sdf(q: np.ndarray) -> np.ndarray:
        return np.asarray(plate.sdf((np.asarray(q, np.float64) - offset) / scale)) * scale

    return Approach(positions=np.asarray(s.positions) * scale + offset, normals=np.asarray(s.normals),
                    radii=np.asarray(s.radii) * scale, zero=np.flatnonzero(part == 0),
                    one=np.flatnonzero(part == 1), spacing=spacing * scale, sdf=sdf)


@pytest.fixture
def plate_and_ball() -> Approach:
    return approach()
