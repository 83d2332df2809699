"""Bad settings get a typed InvalidArgumentError and change nothing."""

import numpy as np
import pytest

from surfeledit import core, scenario as S
from surfeledit.errors import InvalidArgumentError

BAD = [
    dict(algorithm="fastest"),
    dict(sphere_margin=-0.5),
    dict(sphere_margin=float("nan")),
    dict(boundary_n=-1),
    dict(boundary_n=0),
    dict(boundary_i=0),
    dict(boundary_n=4, boundary_i=5),
    dict(boundary_n=2.5),
    dict(threshold=float("nan")),
    dict(threads=-2),
    dict(split_threshold=0.5),
    dict(no_such_setting=1),
    dict(algorithm=3),
    dict(algorithm="robust", boundary_n=-1),  # one bad value spoils the whole request
]


@pytest.mark.parametrize("bad", BAD, ids=[",".join(f"{k}={v}" for k, v in b.items()) for b in BAD])
def test_bad_setting_is_typed_and_changes_nothing(scenarios, bad):
    sc = S.Scenario(scenarios["concave"].scene, 40, scenarios["concave"].motion)
    b = S.LocalBackend(1)
    b.start(sc.scene)
    b.configure(algorithm="temporal", threads=1)
    params = sc.step_params()
    for _ in range(30):
        b.deform(**params)
    before = b.session.settings()
    colliding_before = np.asarray(b.session.colliding()).copy()
    assert len(colliding_before) > 0
    with pytest.raises(InvalidArgumentError) as e:
        b.configure(**bad)
    assert e.value.field in bad  # names the offending setting
    assert b.session.settings() == before
    assert np.array_equal(b.session.colliding(), colliding_before)
    # The detector kept its state: the run goes on exactly as an undisturbed one.
    ref = S.LocalBackend(1)
    ref.start(sc.scene)
    ref.configure(algorithm="temporal", threads=1)
    for _ in range(30):
        ref.deform(**params)
    for _ in range(10):
        assert np.array_equal(b.deform(**params).colliding, ref.deform(**params).colliding)


def test_defaults_and_switching_keep_the_model(scenarios):
    sc = scenarios["concave"]
    b = S.LocalBackend(1)
    b.start(sc.scene)
    s = b.session.settings()
    assert s["algorithm"] == "robust" and s["boundary_n"] == 10 and s["boundary_i"] == 5
    params = sc.step_params()
    for _ in range(5):
        b.deform(**params)
    pos = b.session.positions().copy()
    b.configure(algorithm="simple")
    assert np.array_equal(b.session.positions(), pos)
    assert b.session.settings()["algorithm"] == "simple"
