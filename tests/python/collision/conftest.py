"""Shared fixtures: the scaled scenes (fixed seeds) and the oracles' import path."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from surfeledit import scenario as S  # noqa: E402

# Scales chosen so the folder runs well under 3 minutes on 2 cores (~15-30k surfels each).
SCALES = {"piercing": 0.1, "cup": 0.25, "concave": 0.15}


@pytest.fixture(scope="session")
def scenarios():
    return {name: S.make_scenario(name, scale=scale, seed=1) for name, scale in SCALES.items()}
