"""Result types of a session, the same for the remote :class:`~surfeledit.Session` and the in-process
:class:`~surfeledit.local.LocalSession` (frozen dataclasses of numpy arrays; no wire types).

Conventions: ids ``(P,) uint64`` ascending; positions / normals ``(P, 3) float64`` in model units
(normals unit length); radii ``(P,) float64`` in model units; times in milliseconds.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable, Dict, List, Optional, Union

import numpy as np

from .arrays import NO_IDS

__all__ = ["CollisionStats", "Backoff", "StepResult", "HistoryEntry", "Curve", "MergeResult", "State", "Changes",
           "UpdateEvent", "SettingValue", "merge", "clips_or_none", "BlendResult", "Hole", "FillResult",
           "blend_result", "fill_result"]

#: A session setting's value: a flag, an integer, a number or a text.
SettingValue = Union[bool, int, float, str]


def _no_values() -> np.ndarray:
    return np.zeros(0, np.float64)


@dataclasses.dataclass(frozen=True)
class CollisionStats:
    """The collision detector's counters of one step (all zero when no detector ran).

    Attributes:
        deformable: deformable surfels considered. tested: surfels (re)evaluated this step.
        queries: nearest-neighbour queries made this step. colliding: surfels reported colliding.
        detect_ms: this step's detection time. preprocess_ms: the detector's last (re)initialisation.
        nv, np, nu: the bounding-volume hierarchies' node visits, node-pair tests and node updates of
            this step (0 without a hierarchy).
        asleep: deformable surfels not read this step: a step with a displacement bound (a translation)
            skips blocks of rows that provably stayed inside their quiet spheres (Robust and Temporal).

    Fields can also be read by name, ``stats["detect_ms"]``, as the in-process dict was.
    """

    deformable: int = 0
    tested: int = 0
    queries: int = 0
    colliding: int = 0
    detect_ms: float = 0.0
    preprocess_ms: float = 0.0
    nv: int = 0
    np: int = 0
    nu: int = 0
    asleep: int = 0

    def __getitem__(self, name: str) -> Union[int, float]:
        if name not in _STATS_FIELDS:
            raise KeyError(name)
        return getattr(self, name)

    def as_dict(self) -> Dict[str, float]:
        """``{field: value}`` as floats."""
        return {name: float(getattr(self, name)) for name in _STATS_FIELDS}


_STATS_FIELDS = tuple(f.name for f in dataclasses.fields(CollisionStats))


@dataclasses.dataclass(frozen=True)
class Backoff:
    """What a back-off response did (zeros and ``kept=1`` otherwise).

    Attributes:
        iterations: re-tests made. kept: fraction of the requested step that was kept, in [0, 1].
        final_depth: largest penetration depth after the response, model units.
    """

    iterations: int = 0
    kept: float = 1.0
    final_depth: float = 0.0


@dataclasses.dataclass(frozen=True)
class HistoryEntry:
    """One entry of a session's edit history.

    Attributes:
        version: session version after the change. op: ``"load"``, ``"set_regions"``, ``"deform"``,
        ``"configure"``, ``"remove"`` or ``"merge"``. client: who made it (``""`` in-process).
        touched: (K,) uint64 ids changed, inserted or removed, ascending. undone: in the redo tail.
    """

    version: int
    op: str
    client: str
    touched: np.ndarray
    undone: bool = False


@dataclasses.dataclass(frozen=True)
class StepResult:
    """The outcome of one deformation step.

    Attributes:
        seq: 1-based step number in the session.
        version: session version after the step.
        moved: number of surfels displaced.
        center: rotation centre used, (3,) float64, model units.
        timings: timings in ms (at least ``total``; deform adds ``apply``, and ``detect`` when a
            detector ran, ``resample`` when surfels were split).
        round_trip_ms: caller-measured time of the whole call (over DDS: request to reply).
        detected: a collision detector ran (the session's algorithm is not ``"none"``).
        colliding: (C,) uint64 ids of the surfels colliding after the step, ascending.
        depths: (C,) float64 penetration depth estimate per colliding id, model units.
        stats: the detector's :class:`CollisionStats` for this step.
        inserted: (I,) uint64 ids of surfels inserted by dynamic resampling in this step.
        response: the session's response: ``"none"`` (nothing collided), ``"reported"``, ``"cancelled"``
            (the step was taken back; ``colliding`` lists what would have collided), ``"backed_off"`` or
            ``"merged"`` (the step was kept and the regions merged; ``colliding`` lists what collided, now removed).
        backoff: :class:`Backoff` of a back-off response.
        features: (F,) uint64 feature surfel ids of a merge (response ``"merged"``), ascending.
    """

    seq: int
    version: int
    moved: int
    center: np.ndarray
    timings: Dict[str, float]
    round_trip_ms: float
    detected: bool = False
    colliding: np.ndarray = dataclasses.field(default_factory=lambda: NO_IDS)
    depths: np.ndarray = dataclasses.field(default_factory=_no_values)
    stats: CollisionStats = dataclasses.field(default_factory=CollisionStats)
    inserted: np.ndarray = dataclasses.field(default_factory=lambda: NO_IDS)
    response: str = "none"
    backoff: Backoff = dataclasses.field(default_factory=Backoff)
    features: np.ndarray = dataclasses.field(default_factory=lambda: NO_IDS)


@dataclasses.dataclass(frozen=True)
class Curve:
    """An intersection curve of a merge.

    Attributes:
        points: (K, 3) float64, model units, in curve order.
        closed: the last point connects back to the first.
    """

    points: np.ndarray
    closed: bool = False


@dataclasses.dataclass(frozen=True)
class MergeResult:
    """What a merge did (``session.merge()``).

    Attributes:
        removed: (R,) uint64 ids removed (the colliding deformable surfels, the zero surfels inside), ascending.
        features: (F,) uint64 feature surfel ids of both sides (kept), ascending.
        moved: (M,) uint64 ids the crease moved onto the intersection (now clipped), ascending.
        inserted: (I,) uint64 ids of the gap-covering copies.
        curves: the intersection curves (default refinement) as :class:`Curve`.
        version: session version after the merge (unchanged when nothing collided).
        timings: ``merge``, ``crease``, ``curves`` in ms.
    """

    removed: np.ndarray
    features: np.ndarray
    moved: np.ndarray
    inserted: np.ndarray
    curves: List[Curve]
    version: int
    timings: Dict[str, float] = dataclasses.field(default_factory=dict)


def clips_or_none(clips: Optional[np.ndarray]) -> Optional[np.ndarray]:
    """``clips`` (P, 6), or None when no surfel is clipped (every direction zero) -- the one form of
    "no clip lines" both sessions report."""
    if clips is None or not bool(np.any(clips[:, 3:])):
        return None
    return clips


@dataclasses.dataclass(frozen=True)
class State:
    """The whole model at ``version``; arrays are read-only (copy to edit).

    Attributes:
        version: session version.
        ids: (P,) uint64, ascending.
        positions: (P, 3) float64, model units.
        normals: (P, 3) float64, unit length.
        radii: (P,) float64, model units.
        clips: (P, 6) float64 clip lines of a merge's crease, or None when no surfel is clipped: columns
            0:3 a point of the line (model units, in the surfel's tangent plane), 3:6 its unit direction
            (zero: that surfel is unclipped). A clipped disc keeps the half
            ``{y : (y - point) . (normal x direction) >= 0}``; a renderer draws the crease along the lines.
    """

    version: int
    ids: np.ndarray
    positions: np.ndarray
    normals: np.ndarray
    radii: np.ndarray
    clips: Optional[np.ndarray] = None

    def __len__(self) -> int:
        return int(self.ids.shape[0])


@dataclasses.dataclass(frozen=True)
class Changes:
    """What changed since a version (over DDS: the answer of ``changes_only`` GET_STATE, all pages joined).

    Attributes:
        version: session version the changes lead to.
        full: True when the arrays are the whole model (it was replaced since then, or the session
            cannot tell what changed); apply them as a new model.
        ids: (C,) uint64 changed or inserted ids, ascending; positions (C, 3), normals (C, 3), radii (C,).
        removed: (R,) uint64 ids removed since then.
        clips: (C, 6) clip lines of the changed surfels (as :attr:`State.clips`), or None when the
            model has none (the changed surfels are unclipped).
    """

    version: int
    full: bool
    ids: np.ndarray
    positions: np.ndarray
    normals: np.ndarray
    radii: np.ndarray
    removed: np.ndarray
    clips: Optional[np.ndarray] = None


@dataclasses.dataclass(frozen=True)
class UpdateEvent:
    """One change published by the server, all ``parts`` reassembled.

    Attributes:
        session: session name. version: version after the change.
        cause: ``"load"``, ``"regions"``, ``"deform"``, ``"remove"``, ``"undo"``, ``"redo"`` or ``"close"``.
        full: a new model (replaces everything the watcher had). step: deform step number (0 otherwise).
        author: the client id whose op made the change (``""`` for a session dropped after its grace period).
        ids (N,) uint64, positions (N, 3), normals (N, 3), radii (N,) float64 of the changed surfels
        (for a deform: moved surfels and those inserted by resampling); removed (R,) uint64.
        detected: deform: a collision detector ran, and ``colliding`` (K,) uint64 holds every id
        colliding after the step, ascending (empty otherwise).
        clips: (N, 6) clip lines of the changed surfels (as :attr:`State.clips`), or None when the model
        has none (then the changed surfels are unclipped); cause ``"merge"`` (or a step with response
        ``"merge"``) is when they appear.

    When the server's update queue backs up, it merges a session's queued updates into one (the
    newest version, cause and step, with everything changed since the oldest merged one), so versions
    may skip; applying updates in version order still gives the current state.
    """

    session: str
    version: int
    cause: str
    full: bool
    step: int
    ids: np.ndarray
    positions: np.ndarray
    normals: np.ndarray
    radii: np.ndarray
    removed: np.ndarray
    detected: bool = False
    author: str = ""
    colliding: np.ndarray = dataclasses.field(default_factory=lambda: NO_IDS)
    clips: Optional[np.ndarray] = None


def merge(cache: State, ch: Changes) -> State:
    """``cache`` with incremental changes ``ch`` applied (ids stay ascending; ``cache`` is not modified)."""
    ids, pos, nrm, rad = cache.ids, cache.positions, cache.normals, cache.radii
    # Clip lines: zeros (unclipped) wherever neither side has any.
    with_clips = cache.clips is not None or ch.clips is not None
    clp = cache.clips if cache.clips is not None else np.zeros((ids.size, 6))
    ch_clp = ch.clips if ch.clips is not None else np.zeros((ch.ids.size, 6))
    if ch.removed.size:
        keep = ~np.isin(ids, ch.removed)
        ids, pos, nrm, rad, clp = ids[keep], pos[keep], nrm[keep], rad[keep], clp[keep]
    ids, pos, nrm, rad, clp = ids.copy(), pos.copy(), nrm.copy(), rad.copy(), clp.copy()
    if ch.ids.size:
        idx = np.searchsorted(ids, ch.ids)
        found = idx < ids.size
        found[found] = ids[idx[found]] == ch.ids[found]
        rows = idx[found]
        pos[rows], nrm[rows], rad[rows] = ch.positions[found], ch.normals[found], ch.radii[found]
        clp[rows] = ch_clp[found]
        if not found.all():
            new = ~found
            ids = np.concatenate([ids, ch.ids[new]])
            pos = np.concatenate([pos, ch.positions[new]])
            nrm = np.concatenate([nrm, ch.normals[new]])
            rad = np.concatenate([rad, ch.radii[new]])
            clp = np.concatenate([clp, ch_clp[new]])
            order = np.argsort(ids, kind="stable")
            ids, pos, nrm, rad, clp = ids[order], pos[order], nrm[order], rad[order], clp[order]
    return State(ch.version, ids, pos, nrm, rad, clips_or_none(clp) if with_clips else None)


@dataclasses.dataclass(frozen=True)
class BlendResult:
    """What a blend did (``session.blend()``, docs/particles.md "Blend").

    Attributes:
        particles: particles the blend started with (the blend region; the crease's copies are not particles).
        moved: (M,) uint64 ids of region surfels that became particles again (same ids), ascending.
        inserted: (I,) uint64 ids of surfels made from split-off particles (``adaptive``).
        removed: (R,) uint64 ids removed: killed particles and the crease's gap-covering copies, ascending.
        energy: (iterations,) float64 energy of the particle system before each iteration (spacing units).
        substeps: sub-steps over all iterations (a dt above the stable step is split).
        ms: time of the whole blend on the server / in the core.
        version: session version after the blend.
    """

    particles: int
    moved: np.ndarray
    inserted: np.ndarray
    removed: np.ndarray
    energy: np.ndarray
    substeps: int
    ms: float
    version: int


@dataclasses.dataclass(frozen=True)
class Hole:
    """One hole ``fill_holes()`` filled: ``boundary`` (B,) uint64 ids of its boundary surfels (ascending),
    ``diameter`` (model units), ``inserted`` (I,) uint64 ids of the surfels that fill it."""

    boundary: np.ndarray
    diameter: float
    inserted: np.ndarray


@dataclasses.dataclass(frozen=True)
class FillResult:
    """What ``fill_holes()`` did: ``holes`` (the filled ones), ``skipped`` (loops wider than max_diameter,
    left alone), ``inserted`` (every inserted id, ascending), ``ms``, ``version`` (unchanged when nothing
    was inserted)."""

    holes: List[Hole]
    skipped: int
    inserted: np.ndarray
    ms: float
    version: int


def _field(raw: Any) -> Callable[[str], Any]:
    """Reads a field of a core dict or of a wire struct by name."""
    return raw.__getitem__ if isinstance(raw, dict) else lambda name: getattr(raw, name)


def _ids(values: Any) -> np.ndarray:
    a = np.asarray(values, np.uint64).reshape(-1)
    a.setflags(write=False)
    return a


def blend_result(raw: Any, version: int) -> BlendResult:
    """The :class:`BlendResult` of the core's dict or the wire's BlendResult (same field names)."""
    f = _field(raw)
    energy = np.asarray(f("energy"), np.float64).reshape(-1)
    energy.setflags(write=False)
    return BlendResult(particles=int(f("particles")), moved=_ids(f("moved")), inserted=_ids(f("inserted")),
                       removed=_ids(f("removed")), energy=energy, substeps=int(f("substeps")), ms=float(f("ms")),
                       version=version)


def fill_result(raw: Any, version: int) -> FillResult:
    """The :class:`FillResult` of the core's dict or the wire's FillResult (same field names)."""
    f = _field(raw)
    holes = []
    for h in f("holes"):
        g = _field(h)
        holes.append(Hole(boundary=_ids(g("boundary")), diameter=float(g("diameter")), inserted=_ids(g("inserted"))))
    return FillResult(holes=holes, skipped=int(f("skipped")), inserted=_ids(f("inserted")), ms=float(f("ms")),
                      version=version)
