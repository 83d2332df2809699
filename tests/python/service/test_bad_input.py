"""Malformed requests get the right typed error; the server stays up and the model is unchanged."""

from __future__ import annotations

from typing import Any, Callable, Iterator, Tuple, Type

import numpy as np
import pytest

import surfeledit
from surfeledit import errors, proto

from .conftest import Scene


@pytest.fixture
def loaded(client: surfeledit.Client, scene: Scene) -> Iterator[Tuple[surfeledit.Client, surfeledit.Session, Scene]]:
    pos, nrm, rad, part = scene
    s = client.open_session("bad")
    s.load_points(pos, nrm, rad)
    ids = s.ids()
    s.set_regions(zero=ids[part == 0], one=ids[part == 1])
    s.deform(translation=(0.0, 0.0, -0.01))
    yield client, s, scene
    s.close()


def expect_unchanged(client: surfeledit.Client, session: surfeledit.Session, error: Type[Exception],
                     action: Callable[[], Any], field: str = "") -> errors.SurfelEditError:
    """Runs ``action``, expects ``error``; then checks the server answers and the model did not change."""
    before = session.info()
    with pytest.raises(error) as info:
        action()
    exc = info.value
    assert isinstance(exc, errors.SurfelEditError)
    assert exc.message
    if field:
        assert field in exc.field, f"field {exc.field!r} does not name {field!r} ({exc.message})"
    assert client.info().version  # the server still answers
    after = session.info()
    assert after.state_hash == before.state_hash
    assert after.surfels == before.surfels
    assert session.version == session.client.request(proto.Op.OP_INFO, session.name).version
    return exc


def bad_copy(a: np.ndarray, row: int, value: float) -> np.ndarray:
    b = a.copy()
    b[row, 1] = value
    return b


def test_nan_and_inf_coordinates(loaded: Any) -> None:
    client, s, (pos, nrm, rad, part) = loaded
    expect_unchanged(client, s, errors.InvalidArgumentError,
                     lambda: s.load_points(bad_copy(pos, 17, np.nan), nrm, rad), "positions")
    expect_unchanged(client, s, errors.InvalidArgumentError,
                     lambda: s.load_points(pos, bad_copy(nrm, 5, np.inf), rad), "normals")
    bad_rad = rad.copy()
    bad_rad[3] = -1.0
    expect_unchanged(client, s, errors.InvalidArgumentError, lambda: s.load_points(pos, nrm, bad_rad), "radii")
    expect_unchanged(client, s, errors.InvalidArgumentError,
                     lambda: s.deform(translation=(0.0, np.nan, 0.0)), "translation")
    expect_unchanged(client, s, errors.InvalidArgumentError, lambda: s.deform(angle=np.inf), "angle")


def test_wrong_shapes_client_side_and_server_side(loaded: Any) -> None:
    client, s, (pos, nrm, rad, part) = loaded
    expect_unchanged(client, s, errors.InvalidArgumentError, lambda: s.load_points(pos[:, :2], nrm), "positions")
    expect_unchanged(client, s, errors.InvalidArgumentError, lambda: s.load_points(pos, nrm[:-1]), "normals")
    expect_unchanged(client, s, errors.InvalidArgumentError, lambda: s.load_points(pos, nrm, rad[:-1]), "radii")
    expect_unchanged(client, s, ValueError, lambda: s.deform(translation=(1.0, 2.0)), "translation")
    expect_unchanged(client, s, errors.InvalidArgumentError, lambda: s.set_regions(zero=[[1, 2]], one=[3]), "zero")

    # The same mistakes sent raw reach the server's own checks.
    def raw_chunk() -> None:
        client.request(proto.Op.OP_LOAD_BEGIN, "bad", load_begin=proto.LoadBegin(total=2, has_radii=False))
        client.request(proto.Op.OP_LOAD_CHUNK, "bad", load_chunk=proto.LoadChunk(
            offset=0, positions=[0.0, 1.0, 2.0, 3.0, 4.0], normals=[0.0, 0.0, 1.0] * 2))
    expect_unchanged(client, s, errors.InvalidArgumentError, raw_chunk, "load_chunk")
    # An argument sequence with two elements (exactly one is required).
    expect_unchanged(client, s, errors.InvalidArgumentError, lambda: client.request(
        proto.Op.OP_DEFORM, "bad", deform=[proto.Deform(blend="smooth")] * 2), "deform")
    expect_unchanged(client, s, errors.InvalidArgumentError,
                     lambda: client.request(proto.Op.OP_DEFORM, "bad"), "deform")


def test_zero_normals_zero_axis_bad_blend(loaded: Any) -> None:
    client, s, (pos, nrm, rad, part) = loaded
    zero = nrm.copy()
    zero[9] = 0.0
    expect_unchanged(client, s, errors.InvalidArgumentError, lambda: s.load_points(pos, zero, rad), "normals")
    expect_unchanged(client, s, errors.InvalidArgumentError,
                     lambda: s.deform(axis=(0.0, 0.0, 0.0), angle=0.2), "axis")
    expect_unchanged(client, s, errors.InvalidArgumentError, lambda: s.deform(blend="cubic"), "blend")


def test_unknown_ids_and_overlapping_regions(loaded: Any) -> None:
    client, s, (pos, nrm, rad, part) = loaded
    ids = s.ids()
    expect_unchanged(client, s, errors.NotFoundError,
                     lambda: s.set_regions(zero=ids[part == 0], one=[len(pos) + 1000]), "one")
    expect_unchanged(client, s, errors.ConflictError,
                     lambda: s.set_regions(zero=ids[part == 0], one=ids[:10]), "")
    # Empty one region (a selector that matches nothing).
    expect_unchanged(client, s, errors.SurfelEditError,
                     lambda: s.set_regions(zero=ids[part == 0], one_sphere=((100.0, 0.0, 0.0), 0.1)), "one")


def test_empty_model(loaded: Any) -> None:
    client, s, _ = loaded
    expect_unchanged(client, s, errors.InvalidArgumentError,
                     lambda: s.load_points(np.zeros((0, 3)), np.zeros((0, 3))), "")


def test_unknown_sessions_and_files(loaded: Any) -> None:
    client, s, _ = loaded
    expect_unchanged(client, s, errors.NotFoundError, lambda: client.join_session("no-such-session"), "session")
    # Not attached to an existing session: CONFLICT on field `session`.
    other = client.open_session("other")
    other.close()
    expect_unchanged(client, s, (errors.ConflictError, errors.NotFoundError),
                     lambda: client.request(proto.Op.OP_DEFORM, "other", deform=proto.Deform(blend="smooth")),
                     "session")
    expect_unchanged(client, s, (errors.NotFoundError, errors.ServerIOError),
                     lambda: s.load_file("/nonexistent/model.ply"))


def test_oversized_chunks_and_models(loaded: Any) -> None:
    client, s, _ = loaded
    limit = int(client.info().max_chunk_surfels)
    n = limit + 1

    def oversized() -> None:
        client.request(proto.Op.OP_LOAD_BEGIN, "bad", load_begin=proto.LoadBegin(total=n, has_radii=False))
        client.request(proto.Op.OP_LOAD_CHUNK, "bad", load_chunk=proto.LoadChunk(
            offset=0, positions=[0.5] * (3 * n), normals=[0.0, 0.0, 1.0] * n))
    exc = expect_unchanged(client, s, errors.TooLargeError, oversized, "load_chunk")
    assert str(limit) in exc.message
    big = int(client.info().max_model_surfels) + 1
    expect_unchanged(client, s, errors.TooLargeError, lambda: client.request(
        proto.Op.OP_LOAD_BEGIN, "bad", load_begin=proto.LoadBegin(total=big, has_radii=True)), "load_begin")
    # A commit without a (complete) upload changes nothing either.
    expect_unchanged(client, s, errors.SurfelEditError, lambda: client.request(proto.Op.OP_LOAD_COMMIT, "bad"))
