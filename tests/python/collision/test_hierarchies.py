"""Collision detection behind bounding volume hierarchies (issue 4), in-process on the scenario
runner's scenes (scaled as in conftest.py): every configuration gives the colliding set of the same
algorithm without a hierarchy on every step; the extended variant equals Robust where its definition
coincides with Robust's; bad hierarchy settings are typed, name the setting and change nothing; a
background rebuild is adopted without any step waiting for it."""

import numpy as np
import pytest

from surfeledit import scenario as S
from checks import assert_rejected_and_inert

ALGS = ["simple", "temporal", "robust"]
# Zero kinds x deformable none/aabb, every update strategy with a deformable tree, both SAT modes for OBB.
CONFIGS = (
    [dict(zero_hierarchy=z) for z in ("aabb", "obb", "sphere")]
    + [dict(zero_hierarchy=z, deformable_hierarchy="aabb", update=u)
       for z in ("aabb", "obb", "sphere") for u in ("bottom_up", "top_down", "hybrid", "bounded")]
    + [dict(zero_hierarchy="obb", sat="full"), dict(zero_hierarchy="obb", deformable_hierarchy="aabb", sat="full"),
       dict(zero_hierarchy="aabb", deformable_hierarchy="aabb", update="hybrid", hybrid_f=0.75, leaf_max_surfels=8,
            leaf_min_surfels=1, inflation=0.001)]
)


def _run(sc, alg, **settings):
    return S.run(sc, alg, backend=S.LocalBackend(1), settings=dict(threads=1, **settings), measure=False)


def _differing_steps(a, b):
    return [(k + 1, len(set(x.tolist()) ^ set(y.tolist())))
            for k, (x, y) in enumerate(zip(a.colliding, b.colliding)) if not np.array_equal(x, y)]


@pytest.mark.parametrize("alg", ALGS)
@pytest.mark.parametrize("name", ["piercing", "cup", "concave"])
def test_every_configuration_equals_no_hierarchy(scenarios, name, alg):
    sc = scenarios[name]
    ref = _run(sc, alg)
    assert max(len(c) for c in ref.colliding) > 0
    for cfg in CONFIGS:
        got = _run(sc, alg, **cfg)
        assert _differing_steps(ref, got) == [], f"{name} {alg} {cfg}"
        # Nv/Np/Nu are reported, and the broad phase looked at boxes every step.
        assert all(r.queries >= 0 for r in got.records)


@pytest.mark.parametrize("name", ["piercing", "concave"])
def test_extended_equals_robust(scenarios, name):
    # The concave scene: the Simple family tests against the zero region only and cannot see a fold
    # into it in general (by design, not more behind a hierarchy); the extended variant tests against
    # the original model and equals Robust there on every step.
    sc = scenarios[name]
    ref = _run(sc, "robust")
    for cfg in (dict(zero_hierarchy="aabb"), dict(zero_hierarchy="obb", deformable_hierarchy="aabb"),
                dict(zero_hierarchy="sphere", deformable_hierarchy="aabb", update="top_down")):
        got = _run(sc, "robust", extended=True, **cfg)
        assert _differing_steps(ref, got) == [], f"{name} {cfg}"


def test_extended_on_the_cup_differs_from_robust_by_a_few_surfels(scenarios):
    # Measured: the extended test compares each candidate with its inside state at the previous step,
    # Robust with its state at its last test (it skips surfels inside their spheres); on the cup they
    # part on a few steps by 1-3 surfels. Recorded, not hidden.
    sc = scenarios["cup"]
    ref = _run(sc, "robust")
    got = _run(sc, "robust", zero_hierarchy="aabb", deformable_hierarchy="aabb", extended=True)
    diff = _differing_steps(ref, got)
    peak = max(len(c) for c in ref.colliding)
    assert all(d <= 0.02 * peak for _, d in diff), diff


BAD = [
    (dict(zero_hierarchy="kdop"), "zero_hierarchy"),
    (dict(deformable_hierarchy="obb"), "deformable_hierarchy"),
    (dict(zero_hierarchy="none"), "deformable_hierarchy"),  # the deformable tree stays: no zero tree for it
    (dict(zero_hierarchy="aabb", update="sideways"), "update"),
    (dict(zero_hierarchy="aabb", hybrid_f=1.5), "hybrid_f"),
    (dict(zero_hierarchy="obb", sat="half"), "sat"),
    (dict(extended=True), "extended"),
    (dict(zero_hierarchy="aabb", extended=True, algorithm="temporal"), "extended"),
    (dict(zero_hierarchy="aabb", algorithm="improved"), "zero_hierarchy"),
    (dict(zero_hierarchy="aabb", step_bound=False), "zero_hierarchy"),
    (dict(leaf_max_surfels=1, leaf_min_surfels=2), "leaf_max_surfels"),
    (dict(leaf_min_surfels=0), "leaf_min_surfels"),
    (dict(leaf_max_surfels=2.5), "leaf_max_surfels"),
    (dict(max_level=-1), "max_level"),
    (dict(inflation=-0.1), "inflation"),
    (dict(zero_hierarchy=1), "zero_hierarchy"),
]


@pytest.mark.parametrize("bad,field", BAD, ids=[",".join(f"{k}={v}" for k, v in b.items()) for b, _ in BAD])
def test_bad_hierarchy_setting_is_typed_and_changes_nothing(scenarios, bad, field):
    sc = scenarios["concave"]
    b = S.LocalBackend(1)
    b.start(sc.scene)
    b.configure(algorithm="temporal", threads=1, zero_hierarchy="aabb", deformable_hierarchy="aabb")
    params = sc.step_params()
    for _ in range(10):
        b.deform(**params)
    assert_rejected_and_inert(b, bad, field)


def test_session_builds_only_the_trees_it_uses_and_rebuilds_in_the_background(scenarios):
    sc = scenarios["piercing"]
    b = S.LocalBackend(1)
    b.start(sc.scene)
    b.configure(algorithm="robust", threads=1)
    assert not any(k.startswith("bvh_") for k in b.session.report()["structures"])
    assert b.session.hierarchy()["status"] == ""
    b.configure(zero_hierarchy="obb")
    names = set(b.session.report()["structures"])
    assert "bvh_zero_obb" in names and "bvh_deformable_aabb" not in names
    assert b.session.rebuild() is False  # no deformable tree
    b.configure(zero_hierarchy="aabb", deformable_hierarchy="aabb", update="bottom_up")
    rep = b.session.report()
    assert {"bvh_zero_aabb", "bvh_deformable_aabb"} <= set(rep["structures"]) and rep["hierarchy_status"] == "fresh"
    ref = _run(sc, "robust")
    params = sc.step_params()
    outs = [b.deform(**params) for _ in range(5)]
    assert b.session.hierarchy()["status"] == "refit"
    assert all(o.stats["nv"] > 0 for o in outs)
    assert b.session.rebuild() is True
    k = 5
    while b.session.hierarchy()["rebuilds_adopted"] == 0 and k < sc.steps:
        outs.append(b.deform(**params))
        k += 1
    assert b.session.hierarchy()["rebuilds_adopted"] == 1
    while k < sc.steps:
        outs.append(b.deform(**params))
        k += 1
    for step, (o, want) in enumerate(zip(outs, ref.colliding), 1):
        assert np.array_equal(np.sort(o.colliding), want), step
