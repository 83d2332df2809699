"""The in-process edit session: versions, change tracking, and failed calls leaving it unchanged."""

from __future__ import annotations

import os

import numpy as np
import pytest

from surfeledit import core
from surfeledit.errors import ConflictError, InvalidArgumentError, NotFoundError
from surfeledit.local import LocalSession


@pytest.fixture()
def scene():
    s = core.make_default_scene().sample(spacing=0.06, seed=1)
    es = core.EditSession("t")
    es.load_points(s.positions, s.normals, s.radii)
    return s, es


def test_report_lists_only_what_was_built(scene) -> None:
    s, es = scene
    before = es.report()
    assert set(before["structures"]) == {"model", "versions", "history"}  # issue 9: the history is listed
    es.set_regions(zero=np.flatnonzero(s.part == 0), one=np.flatnonzero(s.part == 1))
    after = es.report()
    assert "deformation_fields" in after["structures"]
    assert after["bytes_per_surfel"] > before["bytes_per_surfel"] > 0
    assert after["surfels"] == len(s.positions)


def test_steps_bump_version_and_move_only_the_deformable_part(scene) -> None:
    s, es = scene
    es.set_regions(zero=np.flatnonzero(s.part == 0), one=np.flatnonzero(s.part == 1))
    v = es.version
    step = es.deform(translation=(0.0, 0.0, -0.05))
    assert es.version == v + 1
    assert step.moved == int((s.part == 1).sum())
    p = es.positions()
    np.testing.assert_array_equal(p[s.part == 0], s.positions[s.part == 0])
    np.testing.assert_allclose(p[s.part == 1], s.positions[s.part == 1] + [0, 0, -0.05], atol=1e-12)


def test_failed_calls_change_nothing(scene) -> None:
    s, es = scene
    zero, one = np.flatnonzero(s.part == 0), np.flatnonzero(s.part == 1)
    h, v = es.state_hash, es.version
    with pytest.raises(ConflictError):
        es.deform(translation=(0, 0, 1))  # no regions yet
    with pytest.raises(NotFoundError):
        es.set_regions(zero=zero, one=np.array([10**9]))
    with pytest.raises(ConflictError):
        es.set_regions(zero=zero, one=zero[:3])  # overlapping
    with pytest.raises(InvalidArgumentError):
        es.set_regions(zero=zero, one=np.array([], dtype=np.int64))
    es.set_regions(zero=zero, one=one)
    h, v = es.state_hash, es.version
    with pytest.raises(InvalidArgumentError):
        es.deform(translation=(0, np.nan, 0))
    with pytest.raises(InvalidArgumentError):
        es.deform(axis=(0, 0, 0), angle=0.3)
    with pytest.raises(InvalidArgumentError):
        es.deform(blend="cubic")
    with pytest.raises(InvalidArgumentError):
        es.load_points(np.zeros((0, 3)), np.zeros((0, 3)))
    with pytest.raises(InvalidArgumentError):
        es.load_points(s.positions, np.zeros_like(s.normals))  # zero normals
    assert (es.state_hash, es.version) == (h, v)


def test_a_sessions_threads_start_its_detection_threads() -> None:
    # One knob keeps an in-process session on one core: its threads are every tool's starting `threads`
    # setting (capped at the hardware threads, the setting's range); bounds are refused with the field named.
    hardware = os.cpu_count() or 1
    for threads in (0, 1, hardware + 2):
        with LocalSession("t", threads=threads) as session:
            assert session.settings()["threads"] == min(threads, hardware)
    for threads in (-1, 257):
        with pytest.raises(InvalidArgumentError) as err:
            core.EditSession("t", threads=threads)
        assert err.value.field == "threads" and str(threads) in str(err.value)


def test_ids_must_be_integers(scene) -> None:
    # A float id would be truncated to another surfel's id; integer arrays of any width (uint64 too) are ids.
    s, es = scene
    zero, one = np.flatnonzero(s.part == 0), np.flatnonzero(s.part == 1)
    v = es.version
    for bad in (zero + 0.5, zero.astype(np.float64), np.ones(zero.size, bool)):
        with pytest.raises(InvalidArgumentError) as err:
            es.set_regions(zero=bad, one=one)
        assert err.value.field == "zero" and "integer" in str(err.value)
    with pytest.raises(InvalidArgumentError):
        es.remove(np.array([1.0]))
    assert es.version == v
    es.set_regions(zero=zero.astype(np.uint64), one=list(one.astype(np.uint32)))
    assert es.version == v + 1
