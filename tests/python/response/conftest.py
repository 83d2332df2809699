"""Scenes with exact truth for the response tests, and the real-server fixtures of tests/python/service."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from service.conftest import client, make_client, server  # noqa: F401  (fixtures: a real server per test)
from surfeledit import core, scenes
from surfeledit.scenes import SceneSetup


def approach(spacing: float = 0.03, offset: float = 0.0, scale: float = 1.0, gap: float = 2.0) -> SceneSetup:
    """A rigid plate (zero region) and a ball (one region) `gap` spacings above it, moved by ``offset``
    and scaled by ``scale`` (positions * scale + offset); ``truth_sdf`` is the plate's exact signed
    distance in that frame, ``spacing`` scaled too."""
    half_t, r = 0.075, 0.4
    plate = core.make_box([0.8, 0.8, half_t])
    scene = core.Scene()
    scene.add(plate)
    scene.add(core.make_sphere(r, center=[0.0, 0.0, half_t + r + gap * spacing]))
    s = scene.sample(spacing=spacing, seed=1)
    part = np.asarray(s.part)

    def sdf(q: np.ndarray) -> np.ndarray:
        return np.asarray(plate.sdf((np.asarray(q, np.float64) - offset) / scale)) * scale

    setup = scenes._setup("plate_and_ball", s, np.flatnonzero(part == 0), np.flatnonzero(part == 1), spacing,
                          plate.sdf, scenes.Motion(translation=(0.0, 0.0, -8.0 * spacing)), 1, "")
    return dataclasses.replace(setup, positions=setup.positions * scale + offset, radii=setup.radii * scale,
                               spacing=spacing * scale, truth_sdf=sdf, seam=setup.seam * scale + offset)


@pytest.fixture
def plate_and_ball() -> SceneSetup:
    return approach()
