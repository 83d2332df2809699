"""Issue 12 against a real server: no request takes it down, a refused request changes nothing (version,
state hash, positions), and every request gets exactly one typed reply, also with enum values the
protocol does not know (they travel as ``long``; see proto/PROTOCOL.md, "Reply guarantee")."""

from __future__ import annotations

import math
import os
import time
from typing import Any, Tuple

import numpy as np
import pytest

import surfeledit
from surfeledit import errors, proto

from .test_bad_input import loaded  # noqa: F401  (fixture: a loaded session with regions)


def snapshot(s: surfeledit.Session) -> Tuple[int, int, np.ndarray]:
    """(version as the server reports it, state hash, positions #P by 3) read from the server."""
    info = s.client.request(proto.Op.OP_INFO, s.name)
    return int(info.version), int(info.session_info[0].state_hash), np.array(s.changes_since(0).positions, copy=True)


def refused_twice_unchanged(s: surfeledit.Session, field: str, **step: Any) -> None:
    """The step is refused (InvalidArgument naming `field`) twice in a row; nothing changes either time."""
    before = snapshot(s)
    for _ in range(2):
        with pytest.raises(errors.InvalidArgumentError) as e:
            s.deform(**step)
        assert field in e.value.field, (e.value.field, e.value.message)
        after = snapshot(s)
        assert after[0] == before[0] and after[1] == before[1]
        np.testing.assert_array_equal(after[2], before[2])
    assert np.isfinite(before[2]).all()


def test_configure_threads_beyond_the_hardware_is_refused_and_the_server_survives(loaded: Any) -> None:
    client, s, _ = loaded
    before = snapshot(s)
    for value in (2147483647, (os.cpu_count() or 1) + 1, -1):
        with pytest.raises(errors.InvalidArgumentError) as e:
            s.configure(threads=value)
        assert e.value.field == "threads", e.value.field
        assert str(value) in e.value.message
    assert client.info().version  # still up
    assert snapshot(s)[:2] == before[:2]
    s.configure(threads=os.cpu_count() or 1)  # the hardware's count itself is fine
    s.deform(translation=(0.0, 0.0, -0.001))


def test_a_step_to_1e308_is_refused_twice_and_changes_nothing(loaded: Any) -> None:
    _, s, _ = loaded
    refused_twice_unchanged(s, "translation", translation=(1e308, 0.0, 0.0))
    refused_twice_unchanged(s, "translation", translation=(1e12, 0.0, 0.0))  # beyond 1e6 model extents
    refused_twice_unchanged(s, "center", axis=(0, 0, 1), angle=0.1, center=(1e300, 0.0, 0.0))
    refused_twice_unchanged(s, "angle", axis=(0, 0, 1), angle=1e9)
    # The session is not poisoned: a normal step and a configure still work.
    v = snapshot(s)[0]
    s.deform(translation=(0.0, 0.0, -0.001))
    s.configure(algorithm="simple")
    assert snapshot(s)[0] > v


def test_a_collapsing_axis_is_refused(loaded: Any) -> None:
    _, s, _ = loaded
    refused_twice_unchanged(s, "axis", axis=(1e200, 1e200, 0.0), angle=math.pi / 2)
    refused_twice_unchanged(s, "axis", axis=(1e-170, 1e-170, 0.0), angle=math.pi / 2)
    refused_twice_unchanged(s, "axis", axis=(0.0, 0.0, 0.0), angle=0.5)
    # A large but representable axis is a valid direction: the rotation stays rigid on the one region.
    pos_before = snapshot(s)[2]
    s.deform(axis=(1e100, 1e100, 0.0), angle=math.pi / 2)
    pos_after = snapshot(s)[2]
    moved = np.linalg.norm(pos_after - pos_before, axis=1) > 0
    assert moved.any()


def raw_reply(client: surfeledit.Client, request: "proto.Request", timeout: float = 3.0) -> "proto.Reply":
    """Sends a hand-made request once and returns its reply (no retry); fails if none comes in time."""
    t0 = time.monotonic()
    reply = client.call(request, check=False, timeout=timeout, retries=0)
    assert time.monotonic() - t0 < timeout
    return reply


def test_unknown_enum_values_get_one_typed_reply_quickly(loaded: Any) -> None:
    client, s, _ = loaded
    before = snapshot(s)
    for op in (99, -1, 2**31 - 1):
        req = client.new_request(proto.Op.OP_INFO, s.name)
        req.op = op
        reply = raw_reply(client, req)
        assert reply.status == proto.Status.STATUS_INVALID_ARGUMENT
        assert reply.field == "op", reply.field
        assert reply.version == before[0]
    sel = proto.Selector(kind=7, center=proto.Vec3(0, 0, 0), radius=1.0)
    req = client.new_request(proto.Op.OP_SET_REGIONS, s.name, set_regions=proto.SetRegions(
        zero=proto.RegionSpec(ids=[0]), one=proto.RegionSpec(selectors=[sel])))
    reply = raw_reply(client, req)
    assert reply.status == proto.Status.STATUS_INVALID_ARGUMENT
    assert reply.field == "set_regions.one.selectors[0].kind", reply.field
    setting = proto.Setting(name="boundary_n", kind=9, number=3.0)
    req = client.new_request(proto.Op.OP_CONFIGURE, s.name, configure=proto.Configure(settings=[setting]))
    reply = raw_reply(client, req)
    assert reply.status == proto.Status.STATUS_INVALID_ARGUMENT
    assert reply.field == "boundary_n" and "kind 9" in reply.message
    assert snapshot(s)[:2] == before[:2]
    # A repeat of an answered bad request is answered again (one reply per send, from the cache).
    assert raw_reply(client, req).request_id == req.request_id
