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


def test_integers_come_back_as_int_and_messages_are_uniform():
    s = core.EditSession()
    s.configure(cluster_size=7, boundary_n=12, threshold=1)
    got = s.settings()
    assert type(got["cluster_size"]) is int and got["cluster_size"] == 7
    assert type(got["boundary_n"]) is int and type(got["threads"]) is int
    assert type(got["threshold"]) is float and got["threshold"] == 1.0
    s.configure(boundary_n=8.0)  # an integral float is still accepted for an integer setting
    assert s.settings()["boundary_n"] == 8
    with pytest.raises(InvalidArgumentError, match=r"boundary_n: expects an integer in \[1, 256\], got 2\.5"):
        s.configure(boundary_n=2.5)
    with pytest.raises(InvalidArgumentError, match="algorithm: unknown value 'x'; expected one of none, simple,"):
        s.configure(algorithm="x")
    with pytest.raises(InvalidArgumentError, match="unknown setting 'foo'; known: algorithm, threshold,") as e:
        s.configure(foo=1)
    assert e.value.field == "foo"
    with pytest.raises(InvalidArgumentError, match="cluster_size"):
        s.configure(cluster_size=2**70)


def test_setting_specs_describe_every_setting():
    specs = core.setting_specs()
    defaults = core.EditSession().settings()
    assert [x["name"] for x in specs] == list(defaults)
    kinds = {"number": float, "integer": int, "bool": bool, "text": str}
    for x in specs:
        assert set(x) == {"name", "kind", "default", "min", "max", "min_exclusive", "choices", "expects", "doc"}
        assert type(x["default"]) is kinds[x["kind"]], x
        assert x["default"] == defaults[x["name"]]
        assert bool(x["choices"]) == (x["kind"] == "text")
        assert x["doc"] and x["expects"]
    by_name = {x["name"]: x for x in specs}
    assert by_name["boundary_n"]["min"] == 1 and by_name["boundary_n"]["max"] == 256  # bounded (docs/hardening.md)
    assert by_name["max_variation"]["min"] == 0.0 and by_name["max_variation"]["max"] == 1.0
    assert by_name["split_threshold"]["min_exclusive"] and by_name["split_threshold"]["expects"] == "a finite number in (1, 1e+06]"
    assert by_name["algorithm"]["choices"] == ["none", "simple", "improved", "temporal", "robust"]
    for x in specs:  # the keyword docs are built from the table
        assert x["name"] + ": " + x["doc"] in core.EditSession.configure.__doc__
