"""The scenario runner over DDS with a real server gives the same colliding ids as in-process."""

import numpy as np
import pytest

import surfeledit
from service import domains
from service.conftest import free_domain
from surfeledit import scenario as S


def test_remote_equals_in_process(scenarios):
    if not hasattr(surfeledit.Session, "configure"):
        pytest.skip("the DDS client has no Session.configure yet")
    if surfeledit.find_server_executable() is None:
        pytest.skip("surfeledit-server is not built")
    sc = S.Scenario(scenarios["concave"].scene, 40, scenarios["concave"].motion)
    domain = free_domain()
    with surfeledit.connect(domain=domain, spawn=True) as client:
        backend = S.RemoteBackend(client, "scenario-test")
        try:
            remote = {(alg, inside): S.run(sc, alg, backend=backend, settings={"threads": 1, "inside": inside})
                      for alg in ("temporal", "robust") for inside in ("nearest", "winding")}
        except surfeledit.InvalidArgumentError as e:
            if e.field == "op":  # a server built before OP_CONFIGURE: not this code's failure
                pytest.skip(f"the server found ({surfeledit.find_server_executable()}) predates OP_CONFIGURE: {e}")
            raise
        backend.close()
    domains.release(domain)
    for (alg, inside), res in remote.items():
        local = S.run(sc, alg, backend=S.LocalBackend(1), settings={"threads": 1, "inside": inside})
        assert max(len(c) for c in local.colliding) > 0
        for k, (a, b) in enumerate(zip(res.colliding, local.colliding), 1):
            assert np.array_equal(a, b), f"{alg}/{inside} step {k}"
        assert [r.precision for r in res.records] == [r.precision for r in local.records]
