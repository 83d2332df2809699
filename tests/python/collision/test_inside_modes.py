"""The inside modes of Temporal and Robust (setting ``inside``, docs/algorithms.md §4.6) against the
exact truth of the generated scenes (analytic signed distances; see surfeledit.scenario): precision and
recall every step, seam band left out, at the CI scales of conftest."""

import pytest

from surfeledit import scenario as S
from surfeledit.errors import InvalidArgumentError

# The bar for the new modes: >= 0.98 at every step with at least 50 true collisions.
FLOOR = 0.98
MIN_TRUTH = 50


@pytest.mark.parametrize("inside", ["winding", "vote"])
@pytest.mark.parametrize("algorithm", ["temporal", "robust"])
@pytest.mark.parametrize("name", ["cup", "concave", "piercing"])
def test_new_modes_are_accurate_on_every_scene(scenarios, name, algorithm, inside):
    res = S.run(scenarios[name], algorithm, backend=S.LocalBackend(1), settings={"threads": 1, "inside": inside})
    judged = [r for r in res.records if r.truth >= MIN_TRUTH]
    assert judged, "no step with enough true collisions: the test would prove nothing"
    for r in judged:
        print(f"{name} {algorithm}/{inside} step {r.step}: truth {r.truth} precision {r.precision:.4f} "
              f"recall {r.recall:.4f}")
        assert r.precision >= FLOOR and r.recall >= FLOOR, f"step {r.step}: {r}"


def test_the_cup_fails_with_the_thesis_test_and_passes_with_the_winding_number(scenarios):
    """The failure this mode exists for (thesis Fig. 6.7): Robust's nearest original surfel near the
    handle's roots is a handle surfel."""
    worst = {}
    for inside in ("nearest", "winding"):
        res = S.run(scenarios["cup"], "robust", backend=S.LocalBackend(1), settings={"threads": 1, "inside": inside})
        s = res.summary()
        worst[inside] = min(s["min_precision_50"], s["min_recall_50"])
    assert worst["nearest"] < 0.9 <= FLOOR <= worst["winding"]


@pytest.mark.parametrize("bad, field", [
    (dict(algorithm="simple", inside="winding"), "inside"),
    (dict(algorithm="improved", inside="vote"), "inside"),
    (dict(algorithm="robust", inside="inner"), "inside"),
    (dict(algorithm="robust", vote_k=0), "vote_k"),
    (dict(algorithm="robust", winding_beta=-1.0), "winding_beta"),
    (dict(algorithm="robust", winding_beta=float("nan")), "winding_beta"),
])
def test_bad_inside_settings_are_typed(scenarios, bad, field):
    b = S.LocalBackend(1)
    b.start(scenarios["concave"].scene)
    b.configure(algorithm="temporal", threads=1)
    before = b.session.settings()
    with pytest.raises(InvalidArgumentError) as e:
        b.configure(**bad)
    assert e.value.field == field, str(e.value)
    assert b.session.settings() == before
    b.close()
