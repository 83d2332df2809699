"""The compact update encoding (PROTOCOL.md "Updates, compact"; issue 14): a compact watcher and a full
watcher of one session receive the same changes, the compact one within the stated error bounds of the
full one's exact doubles, and its replay reconstructs the session's state within those bounds."""

from __future__ import annotations

from typing import List

import numpy as np
import pytest

import surfeledit
from surfeledit.compact import OCTAHEDRAL_MAX_ANGLE

from .conftest import Scene

STEPS = [dict(translation=(0.0, 0.0, -0.02)), dict(axis=(0.0, 1.0, 0.0), angle=0.05, center=(0.0, 0.0, 0.4)),
         dict(translation=(0.01, 0.0, 0.0), axis=(1.0, 0.0, 0.0), angle=-0.04, center=(0.0, 0.0, 0.4))]


def collect(watcher: surfeledit.Watcher, n: int) -> List[surfeledit.UpdateEvent]:
    events = []
    while len(events) < n:
        ev = watcher.get(timeout=10.0)
        assert ev is not None, f"{watcher.encoding}: only {[(e.cause, e.version) for e in events]} arrived"
        events.append(ev)
    return events


def angles(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angles between the rows of a and b (accurate near zero)."""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=1), np.einsum("ij,ij->i", a, b))


def assert_within_bounds(compact: surfeledit.UpdateEvent, full: surfeledit.UpdateEvent) -> None:
    extent = full.positions.max(axis=0) - full.positions.min(axis=0)  # >= every part's extent
    bound = np.ldexp(extent, -25) + np.ldexp(np.abs(full.positions), -51)
    assert np.all(np.abs(compact.positions - full.positions) <= bound), f"v{full.version} positions"
    assert angles(compact.normals, full.normals).max() <= OCTAHEDRAL_MAX_ANGLE, f"v{full.version} normals"
    assert np.all(np.abs(compact.radii - full.radii) <= np.ldexp(full.radii, -24)), f"v{full.version} radii"


@pytest.mark.parametrize("offset", [0.0, 1e6])
def test_a_compact_watcher_sees_every_change_within_the_stated_bounds(client: surfeledit.Client, scene: Scene,
                                                                     offset: float) -> None:
    pos, nrm, rad, part = scene
    pos = pos + offset
    session = client.open_session("compact")
    full_w, compact_w = session.watch(), session.watch(encoding="compact")
    session.load_points(pos, nrm, rad)
    loaded = session.state()
    session.set_regions(zero=loaded.ids[part == 0], one=loaded.ids[part == 1])
    for s in STEPS:
        c = s.get("center")
        session.deform(**(dict(s, center=(c[0] + offset, c[1] + offset, c[2] + offset)) if c else s))
    full, compact = collect(full_w, 2 + len(STEPS)), collect(compact_w, 2 + len(STEPS))
    assert [(e.version, e.cause) for e in compact] == [(e.version, e.cause) for e in full]
    replay_p, replay_n = compact[0].positions.copy(), compact[0].normals.copy()
    for c, f in zip(compact, full):
        np.testing.assert_array_equal(c.ids, f.ids)
        np.testing.assert_array_equal(c.removed, f.removed)
        np.testing.assert_array_equal(c.colliding, f.colliding)
        assert (c.full, c.step, c.author, c.detected) == (f.full, f.step, f.author, f.detected)
        if len(f.ids):
            assert_within_bounds(c, f)
        if c.cause == "deform":
            assert len(c.ids) > 0
            # It came compact: float32 offsets cannot reproduce thousands of moved doubles exactly.
            assert not np.array_equal(c.positions, f.positions)
            replay_p[c.ids.astype(np.int64)] = c.positions
            replay_n[c.ids.astype(np.int64)] = c.normals
    # The compact replay is the session's state within the bounds (the full encoding's exactness is
    # tested in test_end_to_end.py).
    st = session.state()
    extent = st.positions.max(axis=0) - st.positions.min(axis=0)
    assert np.all(np.abs(replay_p - st.positions) <= np.ldexp(extent, -25) + np.ldexp(np.abs(st.positions), -51))
    assert angles(replay_n, st.normals).max() <= OCTAHEDRAL_MAX_ANGLE
    full_w.close()
    compact_w.close()
    session.close()


def test_an_unknown_encoding_is_a_typed_error(client: surfeledit.Client) -> None:
    session = client.open_session("bad-encoding")
    with pytest.raises(surfeledit.InvalidArgumentError) as e:
        session.watch(encoding="float16")
    assert e.value.field == "encoding"
    session.close()
