"""The watertight bunny with one ear pushed into its head; truth = generalized winding number of
the mesh (libigl, tests only) minus the ear's own rest volume."""

import numpy as np
import pytest

from surfeledit import scenario as S, scenes

pytestmark = pytest.mark.skipif(not scenes.BUNNY_FILE.is_file(),
                                reason=f"{scenes.BUNNY_FILE} is absent (shared test models not mounted; "
                                       "set SURFELEDIT_MODELS to their directory)")


@pytest.fixture(scope="module")
def bunny():
    pytest.importorskip("igl", reason="libigl (scripts/requirements.txt) gives the bunny's truth")
    return S.make_scenario("bunny")


def test_bunny_robust_accuracy_and_oracle(bunny):
    from oracles import make_reference
    ref = make_reference("robust", bunny.scene)
    equal = []
    res = S.run(bunny, "robust", backend=S.LocalBackend(1), settings={"threads": 1},
                after_step=lambda k, b, out, st: equal.append(np.array_equal(ref.step(st), np.sort(out.colliding))))
    for r in res.records:
        print(f"  step {r.step:3d} truth {r.truth:4d} reported {r.colliding:4d} "
              f"precision {r.precision:.4f} recall {r.recall:.4f}")
    assert all(equal)
    assert res.records[0].truth == 0 and max(r.truth for r in res.records) > 30
    # Measured (seed-free: the mesh's vertices): no false positive on any step; recall lags behind
    # the shallow, grazing entry of the ear (0 on the first contact steps, 0.32 on the last), so
    # only "it finds the collision by the end" is asserted.
    assert min(r.precision for r in res.records) >= 0.99
    assert res.records[-1].tp > 0.25 * res.records[-1].truth
