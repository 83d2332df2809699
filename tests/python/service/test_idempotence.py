"""Re-sending a request id returns the stored reply and never applies the request twice."""

from __future__ import annotations

import numpy as np

import surfeledit
from surfeledit import proto

from .conftest import Scene


def test_repeated_request_is_answered_not_reapplied(client: surfeledit.Client, scene: Scene) -> None:
    pos, nrm, rad, part = scene
    with client.open_session("idem") as s:
        s.load_points(pos, nrm, rad)
        ids = s.ids()
        s.set_regions(zero=ids[part == 0], one=ids[part == 1])

        req = client.new_request(proto.Op.OP_DEFORM, "idem", deform=proto.Deform(
            translation=proto.Vec3(0.0, 0.0, -0.05), axis=proto.Vec3(0.0, 0.0, 1.0), blend="smooth"))
        first = client.call(req)
        after_first = s.info()
        positions = s.positions().copy()

        again = client.call(req)  # same client id and request id
        assert again == first  # the stored reply, timings included
        assert again.step[0].seq == 1
        info = s.info()
        assert info.state_hash == after_first.state_hash
        np.testing.assert_array_equal(s.positions(), positions)

        # A new request id is applied: step 2.
        nxt = client.call(client.new_request(proto.Op.OP_DEFORM, "idem", deform=req.deform[0]))
        assert nxt.step[0].seq == 2 and nxt.version == first.version + 1

        # Errors are cached too: the same failing request gets the same error reply.
        bad = client.new_request(proto.Op.OP_JOIN_SESSION, "no-such-session")
        r1 = client.call(bad, check=False)
        r2 = client.call(bad, check=False)
        assert r1.status == proto.Status.STATUS_NOT_FOUND and r2 == r1
