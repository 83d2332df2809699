"""Approximate collision detection on the simplified deformable region and the other speed/accuracy
settings of issue 5, in-process on the scenario runner's scaled scenes (conftest.py):
cluster size 1 equals the exact detector on every step; at cluster sizes 18 and 100 precision and
recall against the exact detector are the figures bench/RESULTS.md documents (section 8, scaled
piercing); sphere cluster trees as zero hierarchy equal no hierarchy; knn_eps 0 is exact; bad settings
are typed, name the setting and change nothing; a session builds clusters only when asked for."""

import numpy as np
import pytest

from surfeledit import scenario as S
from checks import assert_rejected_and_inert

METHODS = ["hierarchical", "region_growing"]

# Precision / recall against the exact detector, summed over the 50 steps of piercing at scale 0.1 (one
# thread), as documented in bench/RESULTS.md section 8: (algorithm, method, size, member_margin) -> (P, R).
DOCUMENTED = {
    ("robust", "hierarchical", 18, 0.0): (1.0, 0.9268),
    ("robust", "hierarchical", 100, 0.0): (1.0, 0.8215),
    ("robust", "region_growing", 18, 0.0): (1.0, 0.9010),
    ("robust", "region_growing", 100, 0.0): (1.0, 0.7758),
    ("robust", "hierarchical", 18, 1.0): (1.0, 1.0),
    ("robust", "hierarchical", 100, 1.0): (1.0, 1.0),
    ("temporal", "hierarchical", 18, 0.0): (1.0, 0.9268),
    ("temporal", "region_growing", 100, 0.0): (1.0, 0.7758),
}
MARGIN = 0.02  # absolute, on precision and recall


def _run(sc, alg, **settings):
    return S.run(sc, alg, backend=S.LocalBackend(1), settings=dict(threads=1, **settings), measure=False)


def _differing_steps(a, b):
    return [(k + 1, len(set(x.tolist()) ^ set(y.tolist())))
            for k, (x, y) in enumerate(zip(a.colliding, b.colliding)) if not np.array_equal(x, y)]


def _precision_recall(ref, got):
    tp = fp = fn = 0
    for want, have in zip(ref.colliding, got.colliding):
        w, h = set(want.tolist()), set(have.tolist())
        tp, fp, fn = tp + len(w & h), fp + len(h - w), fn + len(w - h)
    return (tp / (tp + fp) if tp + fp else 1.0), (tp / (tp + fn) if tp + fn else 1.0)


@pytest.fixture(scope="module")
def exact(scenarios):
    """The exact detector's runs, shared by the tests below."""
    cache = {}

    def get(name, alg):
        if (name, alg) not in cache:
            cache[name, alg] = _run(scenarios[name], alg)
        return cache[name, alg]
    return get


@pytest.mark.parametrize("alg", ["simple", "temporal", "robust"])
@pytest.mark.parametrize("name", ["piercing", "cup", "concave"])
def test_cluster_size_one_equals_exact_every_step(scenarios, exact, name, alg):
    ref = exact(name, alg)
    assert max(len(c) for c in ref.colliding) > 0
    for method in METHODS:
        got = _run(scenarios[name], alg, simplify=method, cluster_size=1)
        assert _differing_steps(ref, got) == [], f"{name} {alg} {method}"


@pytest.mark.parametrize("key", sorted(DOCUMENTED), ids=lambda k: "-".join(str(x) for x in k))
def test_precision_recall_at_larger_clusters_as_documented(scenarios, exact, key):
    alg, method, size, margin = key
    got = _run(scenarios["piercing"], alg, simplify=method, cluster_size=size, member_margin=margin)
    p, r = _precision_recall(exact("piercing", alg), got)
    want_p, want_r = DOCUMENTED[key]
    assert abs(p - want_p) <= MARGIN and abs(r - want_r) <= MARGIN, f"{key}: P {p:.4f} R {r:.4f}"


@pytest.mark.parametrize("name", ["piercing", "concave"])
def test_sphere_cluster_trees_as_zero_hierarchy_equal_no_hierarchy(scenarios, exact, name):
    ref = exact(name, "robust")
    for cfg in (dict(zero_hierarchy="sphere_hierarchical"), dict(zero_hierarchy="sphere_incremental"),
                dict(zero_hierarchy="sphere_hierarchical", deformable_hierarchy="aabb", cluster_size=50)):
        got = _run(scenarios[name], "robust", **cfg)
        assert _differing_steps(ref, got) == [], f"{name} {cfg}"


def test_knn_eps_zero_is_exact_and_positive_eps_runs(scenarios, exact):
    sc = scenarios["piercing"]
    ref = exact("piercing", "robust")
    assert _differing_steps(ref, _run(sc, "robust", knn_eps=0.0)) == []
    got = _run(sc, "robust", knn_eps=1.0)
    p, r = _precision_recall(ref, got)
    assert p > 0.5 and r > 0.5  # approximate, but still the same contact


BAD = [
    (dict(simplify="octree"), "simplify"),
    (dict(simplify=True), "simplify"),
    (dict(cluster_size=0), "cluster_size"),
    (dict(cluster_size=2.5), "cluster_size"),
    (dict(max_variation=1.5), "max_variation"),
    (dict(member_margin=-1.0), "member_margin"),
    (dict(knn_eps=-0.1), "knn_eps"),
    (dict(knn_eps="fast"), "knn_eps"),
    (dict(zero_hierarchy="sphere_tree"), "zero_hierarchy"),
    (dict(simplify="hierarchical", algorithm="improved"), "simplify"),
    (dict(simplify="hierarchical", zero_hierarchy="aabb"), "simplify"),
    (dict(simplify="region_growing", zero_hierarchy="sphere_incremental"), "simplify"),
]


@pytest.mark.parametrize("bad,field", BAD, ids=[",".join(f"{k}={v}" for k, v in b.items()) for b, _ in BAD])
def test_bad_settings_are_typed_and_change_nothing(scenarios, bad, field):
    sc = scenarios["concave"]
    b = S.LocalBackend(1)
    b.start(sc.scene)
    b.configure(algorithm="robust", threads=1, simplify="hierarchical", cluster_size=18)
    params = sc.step_params()
    for _ in range(5):
        b.deform(**params)
    assert_rejected_and_inert(b, bad, field)


def test_session_builds_clusters_only_when_asked(scenarios):
    sc = scenarios["piercing"]
    b = S.LocalBackend(1)
    b.start(sc.scene)
    b.configure(algorithm="robust", threads=1)
    names = set(b.session.report()["structures"])
    assert not any(k.startswith("clusters_") or k.startswith("bvh_") for k in names)
    assert b.session.settings()["simplify"] == "none"
    b.configure(simplify="region_growing", cluster_size=18)
    names = set(b.session.report()["structures"])
    assert "clusters_region_growing" in names and "collision_robust" in names
    b.configure(simplify="none", zero_hierarchy="sphere_incremental")
    names = set(b.session.report()["structures"])
    assert "bvh_zero_sphere_incremental" in names and not any(k.startswith("clusters_") for k in names)
    b.configure(algorithm="none", zero_hierarchy="none", simplify="hierarchical")
    names = set(b.session.report()["structures"])
    assert not any(k.startswith(("clusters_", "bvh_", "collision_")) for k in names)
