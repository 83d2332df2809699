"""Memory report (issue 14): every configuration of bench/core/memory_report.py lists exactly the
structures it uses -- one it does not use is absent (not listed, 0 bytes), not empty-but-allocated --
and the history's split by image kind adds up to the history; tool ops hold no model-sized image. Robust
keeps the merge origins in its original model (no `merge_origins` of the session's own)."""

from __future__ import annotations

import pytest

from surfeledit import scenario as S

BASE = {"model", "versions", "deformation_fields", "history"}

# (algorithm, hierarchy settings, the structures the configuration needs beyond BASE)
CONFIGS = [
    ("simple", {}, {"collision_simple", "merge_origins"}),
    ("temporal", {}, {"collision_temporal", "merge_origins"}),
    ("robust", {}, {"collision_robust"}),
    ("robust", {"zero_hierarchy": "aabb"}, {"collision_robust", "bvh_zero_aabb", "bvh_surfel_filter", "bvh_scratch"}),
    ("robust", {"zero_hierarchy": "obb"}, {"collision_robust", "bvh_zero_obb", "bvh_surfel_filter", "bvh_scratch"}),
    ("robust", {"zero_hierarchy": "sphere"}, {"collision_robust", "bvh_zero_sphere", "bvh_surfel_filter", "bvh_scratch"}),
    ("robust", {"zero_hierarchy": "aabb", "deformable_hierarchy": "aabb"},
     {"collision_robust", "bvh_zero_aabb", "bvh_deformable_aabb", "bvh_scratch"}),
]


@pytest.fixture(scope="module")
def piercing():
    return S.make_scenario("piercing", scale=0.05)


@pytest.mark.parametrize("algorithm,extra,needed", CONFIGS, ids=[c[0] + "".join("-" + v for v in c[1].values())
                                                                   for c in CONFIGS])
def test_structures_present_exactly_when_used(piercing, algorithm, extra, needed):
    b = S.LocalBackend(1)
    try:
        b.start(piercing.scene)
        b.configure(algorithm=algorithm, threads=1, **extra)
        rep = b.session.report()
        # Before any step: no step scratch, and the history holds tool images only besides the load.
        assert set(rep["structures"]) == BASE | needed
        assert all(v > 0 for k, v in rep["structures"].items() if k != "history")
        kinds = rep["history_kinds"]
        assert kinds["rows"]["entries"] == 0 and kinds["whole"]["entries"] == 1  # the load, into an empty session
        assert kinds["tool"]["entries"] == 2  # set_regions, configure
        # configure's image: the detector re-derived (a fresh one), the fields kept: nothing per surfel.
        assert kinds["tool"]["bytes"] < rep["surfels"]
        for _ in range(2):
            b.deform(**piercing.step_params())
        rep = b.session.report()
        assert set(rep["structures"]) == BASE | needed | {"step_scratch"}
        kinds = rep["history_kinds"]
        assert kinds["rows"]["entries"] == 2
        assert sum(k["bytes"] for k in kinds.values()) == rep["structures"]["history"]
        assert rep["total_bytes"] == sum(rep["structures"].values())
    finally:
        b.close()


def test_no_detector_no_regions_no_fields(piercing):
    b = S.LocalBackend(1)
    try:
        b.start(piercing.scene)
        b.configure(algorithm="none", threads=1)
        names = set(b.session.report()["structures"])
        assert not any(k.startswith(("collision_", "bvh_")) for k in names)
        b.session.release()
        names = set(b.session.report()["structures"])
        assert names == {"model", "versions", "history"}
    finally:
        b.close()
