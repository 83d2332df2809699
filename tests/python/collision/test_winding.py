"""The generalized winding number of a surfel set (core.winding_number, docs/algorithms.md §4.6) against
libigl's fast_winding_number (an independent implementation, exact with beta <= 0) and against the
exact inside/outside of the generated solids."""

import math

import numpy as np
import pytest

from surfeledit import core, scenes

igl = pytest.importorskip("igl", reason="libigl is the independent reference of these tests")


@pytest.fixture(scope="module")
def cup():
    return scenes.cup(scale=0.2)


def _zero(sc):
    z = sc.zero
    return sc.positions[z], sc.normals[z]


def _queries(points, n=3000, pad=0.1, seed=3):
    rng = np.random.default_rng(seed)
    return rng.uniform(points.min(0) - pad, points.max(0) + pad, (n, 3))


def test_exact_sum_matches_libigl(cup):
    P, N = _zero(cup)
    A = core.surfel_areas(P)
    Q = _queries(P)
    ours = core.winding_number(P, N, A, Q, beta=0.0)
    ref = igl.fast_winding_number(P, N, A, Q, 2, 0.0)  # beta <= 0: libigl sums every point exactly
    assert np.abs(ours - ref).max() < 1e-9


def test_tree_approximation_converges_to_libigl_exact(cup):
    P, N = _zero(cup)
    A = core.surfel_areas(P)
    Q = _queries(P)
    ref = igl.fast_winding_number(P, N, A, Q, 2, 0.0)
    err = {beta: np.abs(core.winding_number(P, N, A, Q, beta=beta) - ref).max() for beta in (1.5, 2.0, 4.0)}
    print("max |w - w_exact| per beta:", err)
    assert err[2.0] < 0.1          # far below the 1/2 threshold
    assert err[4.0] < err[1.5]     # a larger acceptance ratio is more accurate
    assert err[4.0] < 0.02


def test_density_areas_sum_to_the_surface_area():
    r = 0.5
    s = core.make_sphere(r).sample(spacing=0.02, seed=2)
    A = core.surfel_areas(np.asarray(s.positions))
    assert abs(A.sum() / (4 * math.pi * r * r) - 1.0) < 0.08
    # pi r^2 of the splats overlaps: it would overweight the surface by about pi
    radii = np.asarray(s.radii)
    assert (math.pi * radii ** 2).sum() / (4 * math.pi * r * r) > 2.0


def test_classification_of_the_open_cup_body_is_exact_away_from_the_surface(cup):
    """The zero region of the cup is the body with two holes where the handle was attached; the holes
    are nearly planar, so w > 1/2 is the body's exact inside/outside (§4.6) except within a few
    spacings of the sampled surface."""
    P, N = _zero(cup)
    A = core.surfel_areas(P)
    Q = _queries(P, n=20000)
    # Also points right over and under the two holes (the handle roots at z = 0.2 and 0.8).
    rng = np.random.default_rng(5)
    for zc in (0.2, 0.8):
        roots = np.column_stack([0.5 + rng.uniform(-0.06, 0.06, 2000), rng.uniform(-0.05, 0.05, 2000),
                                 zc + rng.uniform(-0.05, 0.05, 2000)])
        Q = np.vstack([Q, roots])
    sdf = cup.truth_sdf(Q)
    away = np.abs(sdf) > 2.0 * cup.spacing
    w = core.winding_number(P, N, A, Q)
    wrong = (w[away] > 0.5) != (sdf[away] < 0)
    assert away.sum() > 10000
    assert wrong.sum() == 0, f"{wrong.sum()} misclassified, e.g. {Q[away][wrong][:5]}"


def test_bad_input_is_typed():
    from surfeledit.errors import InvalidArgumentError

    P = np.zeros((3, 3))
    with pytest.raises(InvalidArgumentError) as e:
        core.winding_number(P, np.zeros((2, 3)), np.ones(3), P)
    assert e.value.field == "normals"
    with pytest.raises(InvalidArgumentError) as e:
        core.winding_number(P, P, np.ones(2), P)
    assert e.value.field == "areas"
    with pytest.raises(InvalidArgumentError) as e:
        core.winding_number(P, P, np.ones(3), P, beta=-1.0)
    assert e.value.field == "winding_beta"
    with pytest.raises(InvalidArgumentError) as e:
        core.winding_number(P, P, np.full(3, np.nan), P)
    assert e.value.field == "areas"
