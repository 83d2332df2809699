"""Every step, the C++ colliding set equals a slow from-scratch reference of the same definition
(oracles.py: scipy cKDTree, numpy, state keyed by id) — with insertion (resampling) and removal
mid-scenario too, and with ids stable."""

import numpy as np
import pytest

from oracles import make_reference, split_parents
from surfeledit import scenario as S

ALGS = ["simple", "improved", "temporal", "robust"]


def _check(sc, alg, settings=None, removals=None, steps=None):
    settings = dict(settings or {}, threads=1)
    ref = make_reference(alg, sc.scene, **settings)
    seen = {"ids": set(int(i) for i in range(sc.scene.size)), "inserted": 0, "steps": 0}
    mismatches = []

    def hook(k, backend, out, state):
        ids_now = set(state.ids.astype(np.int64).tolist())
        inserted = set(out.inserted.astype(np.int64).tolist())
        removed = set(int(i) for i in (removals or {}).get(k, []))
        # ids stable: exactly the previous ids minus the removed plus the inserted, never reused.
        assert ids_now == (seen["ids"] - removed) | inserted, f"step {k}: ids changed unexpectedly"
        assert not (inserted & seen["ids"]), f"step {k}: an inserted id was used before"
        if removed:
            ref.remove(removed)
        parents = split_parents(out.inserted, state)
        got = ref.step(state, parents)
        if not np.array_equal(got, np.sort(out.colliding)):
            a, b = set(got.tolist()), set(out.colliding.tolist())
            mismatches.append((k, len(a - b), len(b - a)))
        seen["ids"] = ids_now
        seen["inserted"] += len(inserted)
        seen["steps"] += 1

    scenario = sc if steps is None else S.Scenario(sc.scene, steps, sc.motion)
    res = S.run(scenario, alg, backend=S.LocalBackend(1), settings=settings, removals=removals, after_step=hook,
                measure=True)
    assert not mismatches, f"{alg}: (step, only in oracle, only in C++): {mismatches}"
    assert seen["steps"] == scenario.steps
    return res, seen


@pytest.mark.parametrize("alg", ALGS)
@pytest.mark.parametrize("name", ["piercing", "cup", "concave"])
def test_equals_oracle_every_step(scenarios, name, alg):
    res, _ = _check(scenarios[name], alg)
    assert max(r.colliding for r in res.records) > 0


@pytest.mark.parametrize("alg", ALGS)
def test_heuristics_off_equal_oracle(scenarios, alg):
    # Other settings reach the same definitions: no boundary marks, no step bound, a threshold W.
    _check(scenarios["cup"], alg, settings=dict(boundary=False, step_bound=False, threshold=0.002), steps=20)
    _check(scenarios["cup"], alg, settings=dict(boundary_n=16, boundary_i=12), steps=20)


@pytest.mark.parametrize("margin", [0.0, 1.0])
@pytest.mark.parametrize("alg", ["temporal", "robust"])
def test_sphere_margins_equal_oracle(scenarios, alg, margin):
    # The thesis's spheres (margin 0, bit for bit |d|^2) and fully shrunk ones reach the same definitions.
    _check(scenarios["piercing"], alg, settings=dict(sphere_margin=margin))


@pytest.mark.parametrize("alg", ALGS)
def test_insertion_and_removal_mid_scenario(scenarios, alg):
    sc = scenarios["cup"]  # the blended handle stretches: splits happen
    d = sc.scene.deformable
    rng = np.random.default_rng(7)
    one = set(sc.scene.one.tolist())
    blend_ids = np.array([i for i in d if i not in one])
    zero = sc.scene.zero
    removals = {
        12: rng.choice(blend_ids, 40, replace=False).tolist() + rng.choice(zero, 60, replace=False).tolist(),
        25: rng.choice(np.array(sorted(one)), 30, replace=False).tolist(),
    }
    res, seen = _check(sc, alg, settings=dict(resample=True, split_threshold=1.05), removals=removals)
    print(f"\n{alg}: {seen['inserted']} surfels inserted, {sum(len(v) for v in removals.values())} removed")
    assert seen["inserted"] > 50, "the scenario did not exercise insertion"


def test_oracle_comparison_can_fail(scenarios):
    """Sensitivity: a reference of a *different* definition (no step bound, no boundary marks) does
    not match the C++ Simple with both heuristics on this scene."""
    sc = scenarios["cup"]
    ref = make_reference("simple", sc.scene, boundary=False, step_bound=False)
    differs = []
    S.run(sc, "simple", backend=S.LocalBackend(1), settings={"threads": 1},
          after_step=lambda k, b, out, st: differs.append(not np.array_equal(ref.step(st), np.sort(out.colliding))))
    assert any(differs)
