"""A tool per client (issue 11 §1) against a real server with two real clients: locks, release (and
leaving) freeing them, and two arms of one body, each driven by one client, swung into each other --
the collision checked against the exact signed distance of the capsule where the other client moved it.
"""

from __future__ import annotations

from typing import Callable, Tuple

import numpy as np
import pytest

import surfeledit
from surfeledit import errors

core = pytest.importorskip("surfeledit.core")

SPACING = 0.02
ARM_R, ARM_HALF = 0.1, 0.25
ARM_Z = 0.2 + ARM_HALF + ARM_R - 0.03  # capsule centres, slightly into the body
ARM_A, ARM_B = (-0.4, 0.0, ARM_Z), (0.4, 0.0, ARM_Z)


def two_arms() -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A box body (part 0) and two capsule arms standing on it (part 1 at x = -0.4, part 2 at x = +0.4)."""
    scene = core.Scene()
    scene.add(core.make_box((0.7, 0.2, 0.2)))
    scene.add(core.make_capsule(ARM_R, ARM_HALF, center=ARM_A))
    scene.add(core.make_capsule(ARM_R, ARM_HALF, center=ARM_B))
    s = scene.sample(spacing=SPACING, seed=7)
    return (np.asarray(s.positions), np.asarray(s.normals), np.asarray(s.radii), np.asarray(s.part))


def open_shared(make_client: Callable[[], surfeledit.Client], name: str):
    owner, other = make_client(), make_client()
    positions, normals, radii, part = two_arms()
    a = owner.open_session(name)
    a.load_points(positions, normals, radii)
    b = other.join_session(name, token=a.invite("editor"))
    ids = np.arange(len(part))
    return owner, other, a, b, ids, part, positions


def claim_arms(a: surfeledit.Session, b: surfeledit.Session, ids: np.ndarray,
               part: np.ndarray) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each client's tool moves its own arm (a: arm A, b: arm B), the rest rigid to it; (arm A, arm B, body) ids."""
    arm_a, arm_b, body = ids[part == 1], ids[part == 2], ids[part == 0]
    a.set_regions(zero=np.concatenate([body, arm_b]), one=arm_a)
    b.set_regions(zero=np.concatenate([body, arm_a]), one=arm_b)
    return arm_a, arm_b, body


def test_locks_conflict_naming_the_client_and_release_frees_them(
        make_client: Callable[[], surfeledit.Client]) -> None:
    owner, other, a, b, ids, part, _ = open_shared(make_client, "locks")
    arm_a, arm_b, body = ids[part == 1], ids[part == 2], ids[part == 0]
    a.set_regions(zero=np.concatenate([body, arm_b]), one=arm_a)
    b.configure(algorithm="simple")  # settings are per tool: a's stay
    assert a.settings()["algorithm"] == "robust" and b.settings()["algorithm"] == "simple"
    version = a.version
    # b asks to move both arms: every surfel of arm A is in a's lock.
    with pytest.raises(errors.ConflictError) as refused:
        b.set_regions(zero=body, one=np.concatenate([arm_a, arm_b]))
    assert refused.value.field == "set_regions.regions"
    assert f"{len(arm_a)} surfel(s)" in str(refused.value) and owner.client_id in str(refused.value)
    b.info()
    assert b.version == a.version == version  # nothing changed
    # Its own arm: accepted; each client deforms its own arm only.
    b.set_regions(zero=np.concatenate([body, arm_a]), one=arm_b)
    before = b.version
    b.deform(translation=(-0.02, 0.0, 0.0))
    assert np.array_equal(b.changes_since(before).ids, np.sort(arm_b).astype(np.uint64))
    # a releases: one history entry by a, a new version; b may now take arm A too.
    assert a.release() is True
    last = a.history()[-1]
    assert (last.op, last.client, len(last.touched)) == ("release", owner.client_id, 0)
    assert a.release() is False  # nothing left to release
    b.set_regions(zero=body, one=np.concatenate([arm_a, arm_b]))
    # a cannot take arm A back while b holds it ...
    with pytest.raises(errors.ConflictError):
        a.set_regions(zero=np.concatenate([body, arm_b]), one=arm_a)
    # ... until b leaves: closing the session releases its tool.
    b.close()
    a.set_regions(zero=np.concatenate([body, arm_b]), one=arm_a)
    assert a.history()[-2].op == "release" and a.history()[-2].client == other.client_id


def _check_exact(session, arm: np.ndarray, other_center, found: set, where: str) -> int:
    """The colliding set of the tool moving ``arm`` against the exact solids where they are now: every surfel
    deeper than 2 spacings in the other arm (farther than 0.1 from the body, where the nearest zero surfel
    may be the body's face) is reported; every reported one is within 2 spacings of the other arm or the
    body. Returns how many were that deep."""
    body = core.Scene()
    body.add(core.make_box((0.7, 0.2, 0.2)))
    other = core.Scene()
    other.add(core.make_capsule(ARM_R, ARM_HALF, center=tuple(other_center)))
    state = session.state()
    p = state.positions[np.searchsorted(state.ids, arm)]
    d_body, d_other = body.sdf(p), other.sdf(p)
    d = np.minimum(d_body, d_other)
    tol = 2.0 * SPACING
    deep = arm[(d < -tol) & (d_body > 0.1)]
    missed = set(int(i) for i in deep) - found
    assert not missed, f"{where}: deep surfels not reported: {sorted(missed)[:10]}"
    reported = np.isin(arm, list(found))
    assert np.all(d[reported] < tol), f"{where}: reported far from the other arm and the body"
    return len(deep)


def test_two_arms_swung_into_each_other_are_detected_where_the_other_client_moved_them(
        make_client: Callable[[], surfeledit.Client]) -> None:
    # Each client drives one arm with its own tool (Robust, the default): they swing into each other and
    # back out, alternately (a by 0.05, b by 0.04 a step), and after every step the stepping client's
    # colliding set is checked against the exact capsules where each client moved its arm -- its detector
    # follows the other client's moves step by step (docs/collaboration.md), and a surfel stays reported
    # for as long as it is inside, whichever arm moved last.
    _, _, a, b, ids, part, _ = open_shared(make_client, "arms")
    arm_a, arm_b, body = claim_arms(a, b, ids, part)
    centers = {"a": np.array(ARM_A), "b": np.array(ARM_B)}
    schedule = [("b", -0.04), ("a", 0.05)] * 7 + [("b", -0.04), ("a", 0.0)]  # overlap 0.07 at the end
    deep = 0
    clients = {"a": (a, arm_a, "b"), "b": (b, arm_b, "a")}
    for k, (tool, dx) in enumerate(schedule + [(t, -dx) for t, dx in reversed(schedule[-6:])]):
        session, arm, other = clients[tool]
        step = session.deform(translation=(dx, 0.0, 0.0))
        assert step.detected
        centers[tool] = centers[tool] + np.array([dx, 0.0, 0.0])
        found = set(int(i) for i in step.colliding)
        n = _check_exact(session, arm, centers[other], found, f"{tool} step {k}")
        if k < len(schedule):
            deep += n
    assert deep > 20  # not vacuous
    # Where arm B was before b moved it, arm A is nowhere near: a view of the rigid part as it was when
    # a's detector was built would have found nothing.
    state = a.state()
    old = core.Scene()
    old.add(core.make_capsule(ARM_R, ARM_HALF, center=ARM_B))
    assert np.all(old.sdf(state.positions[np.searchsorted(state.ids, arm_a)]) > 0.05)


def _rows(state, ids: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    rows = np.searchsorted(state.ids, ids)
    return state.positions[rows].copy(), state.normals[rows].copy()


def _expected_refusal(history, client: str):
    """From the history alone: the version and client of the first later entry of another client touching a
    surfel of ``client``'s last applied entry (None: the undo must be accepted)."""
    mine = [k for k, h in enumerate(history) if h.client == client and not h.undone]
    if not mine:
        return None
    target = history[mine[-1]]
    touched = set(int(i) for i in target.touched)
    for h in history[mine[-1] + 1:]:
        if h.client != client and touched & set(int(i) for i in h.touched):
            return h.version, h.client
    return None


def test_each_client_undoes_its_own_op_and_is_refused_when_another_clients_later_op_overlaps(
        make_client: Callable[[], surfeledit.Client]) -> None:
    owner, other, a, b, ids, part, _ = open_shared(make_client, "undo")
    arm_a, arm_b, body = claim_arms(a, b, ids, part)
    a0, b0 = _rows(a.state(), arm_a), _rows(a.state(), arm_b)
    a.deform(translation=(0.03, 0.0, 0.0))
    b.deform(translation=(-0.03, 0.0, 0.0))
    b1 = _rows(b.state(), arm_b)
    # a's step is not its session's last change, but b's later step touched other surfels: undone, exact.
    assert _expected_refusal(a.history(), owner.client_id) is None
    a.undo()
    s = a.state()
    for got, want in zip(_rows(s, arm_a) + _rows(s, arm_b), a0 + b1):
        np.testing.assert_array_equal(got, want)
    a.redo()
    b.undo()
    for got, want in zip(_rows(b.state(), arm_b), b0):
        np.testing.assert_array_equal(got, want)
    b.redo()
    # Overlap: a releases arm A, b takes it over and moves it, then gives it back; a takes it again.
    a.release()
    b.release()
    b.set_regions(zero=np.concatenate([body, arm_b]), one=arm_a)
    b.deform(translation=(0.0, 0.0, 0.02))
    b.release()
    a.set_regions(zero=np.concatenate([body, arm_b]), one=arm_a)
    a.undo()  # its set_regions
    a.undo()  # its release: its regions and lock come back
    hit = _expected_refusal(a.history(), owner.client_id)
    assert hit is not None and hit[1] == other.client_id
    version, before = a.version, a.state()
    with pytest.raises(errors.ConflictError) as refused:
        a.undo()  # its step: b's later step moved the same surfels
    assert refused.value.field == "history"
    assert f"(version {hit[0]})" in str(refused.value) and other.client_id in str(refused.value)
    after = a.state()
    assert a.info() is not None and a.version == version
    np.testing.assert_array_equal(after.positions, before.positions)


def test_local_session_releases_its_tool() -> None:
    from surfeledit.local import LocalSession

    positions, normals, radii, part = two_arms()
    ids = np.arange(len(part))
    with LocalSession("local", threads=1) as s:
        s.load_points(positions, normals, radii)
        assert s.release() is False  # no regions: nothing to release, same version
        version = s.version
        assert s.version == version
        s.set_regions(zero=ids[part != 1], one=ids[part == 1])
        s.deform(translation=(0.01, 0.0, 0.0))
        assert s.release() is True and s.history()[-1].op == "release"
        with pytest.raises(errors.ConflictError):
            s.deform(translation=(0.01, 0.0, 0.0))  # no regions any more
        s.undo()  # the release: regions back
        assert s.deform(translation=(0.01, 0.0, 0.0)).moved > 0
