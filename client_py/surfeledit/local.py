"""The in-process editing session: :class:`LocalSession` wraps ``surfeledit.core.EditSession`` (the
C++ session the server holds per session) and returns the result types of :mod:`surfeledit.results`,
so it satisfies :class:`surfeledit.session_api.EditingSession` like the remote :class:`surfeledit.Session`.

Needs the compiled module ``surfeledit.core`` (built by CMake with ``SURFELEDIT_BUILD_PYTHON``).
Array shapes and dtypes are checked as the remote session checks them (:mod:`surfeledit.arrays`), values by the
core; both raise the typed errors of :mod:`surfeledit.errors`.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any, Dict, List, Optional

import numpy as np

from .arrays import (INT32, VERSIONS, ArrayLike, Vec3Like, as_float, as_ids, as_int, as_points, as_radii, as_vec3,
                     readonly)
from .results import (Backoff, BlendResult, Changes, CollisionStats, Curve, FillResult, HistoryEntry, MergeResult,
                      SettingValue, State, StepResult, blend_result, clips_or_none, fill_result)
from .session_api import StateArrays, settings_doc

__all__ = ["LocalSession"]

_STATS_FIELDS = tuple(f.name for f in dataclasses.fields(CollisionStats))


def _step_result(o: Any, version: int, call_ms: float) -> StepResult:
    """The :class:`StepResult` of a core ``StepOutcome`` (timings as the server reports them)."""
    colliding = np.asarray(o.colliding, np.uint64)
    depths = np.asarray(o.depths, np.float64)
    inserted = np.asarray(o.inserted, np.uint64)
    features = np.asarray(o.features, np.uint64)
    readonly((colliding, depths, inserted, features))
    raw = o.stats
    stats = CollisionStats(**{k: raw[k] for k in _STATS_FIELDS if k in raw})
    timings = {"apply": float(o.deform_ms)}
    if o.detected:
        timings["detect"] = float(stats.detect_ms)
    if inserted.size:
        timings["resample"] = float(o.resample_ms)
    timings["total"] = call_ms
    return StepResult(seq=int(o.seq), version=version, moved=int(o.moved),
                      center=np.asarray(o.center, np.float64).reshape(3), timings=timings, round_trip_ms=call_ms,
                      detected=bool(o.detected), colliding=colliding, depths=depths, stats=stats, inserted=inserted,
                      response=str(o.response), backoff=Backoff(**o.backoff), features=features)


def _ids(a: Optional[ArrayLike], name: str) -> np.ndarray:
    """(K,) uint64 ids for the core, checked as the remote session checks them (:func:`surfeledit.arrays.as_ids`:
    InvalidArgumentError naming ``name`` for another shape, a non-integer dtype or a negative id)."""
    return np.asarray(as_ids(a, name), np.uint64)


def _curves(raw: Any) -> List[Curve]:
    """:class:`Curve` objects of the core's ``[{points, closed}]``."""
    out = []
    for c in raw:
        points = np.asarray(c["points"], np.float64).reshape(-1, 3)
        readonly((points,))
        out.append(Curve(points=points, closed=bool(c["closed"])))
    return out


class LocalSession(StateArrays):
    """An editing session in this process (no server): ``LocalSession("name", threads=0)``.

    Args:
        name: the session's name (reports and logs only).
        threads: worker threads for batch work (0 = all cores, at most 256), and every tool's starting
            ``threads`` setting (detection; at most the hardware threads).

    Attributes:
        core: the wrapped ``surfeledit.core.EditSession``, for in-process-only extras.
    """

    def __init__(self, name: str = "local", threads: int = 0) -> None:
        from . import core  # the compiled module; imported here so the remote client works without it

        self.name = name
        self.core = core.EditSession(name, threads=int(threads))
        self._closed = False

    def __enter__(self) -> "LocalSession":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"LocalSession({self.name!r}, version={self.version})"

    @property
    def version(self) -> int:
        """The session version (bumped by every change of the model or the regions)."""
        return int(self.core.version)

    def close(self) -> None:
        """Marks the session closed (the model is freed with the object)."""
        self._closed = True

    # -- the EditingSession contract ---------------------------------------------------------
    def load_points(self, positions: ArrayLike, normals: ArrayLike, radii: Optional[ArrayLike] = None) -> None:
        """Replaces the model: positions (P, 3), normals (P, 3), radii (P,) or None (estimated)."""
        self.core.load_points(positions, normals, radii)

    def set_regions(self, zero: Optional[ArrayLike] = None, one: Optional[ArrayLike] = None, author: str = "") -> None:
        """Sets the zero and the one region by (K,) integer ids, of the tool of ``author`` (a client id; the
        default tool ``""`` when a single user edits: several authors replay what several clients did)."""
        self.core.set_regions(zero=_ids(zero, "zero"), one=_ids(one, "one"), author=author)

    def deform(self, translation: Vec3Like = (0.0, 0.0, 0.0), axis: Vec3Like = (0.0, 0.0, 1.0),
               angle: float = 0.0, center: Optional[Vec3Like] = None, blend: str = "smooth",
               author: str = "") -> StepResult:
        """One deformation step of the tool of ``author`` (see :meth:`surfeledit.session_api.EditingSession.deform`);
        ``round_trip_ms`` and ``timings["total"]`` are the whole call."""
        t0 = time.perf_counter()
        o = self.core.deform(translation=as_vec3(translation, "translation"), axis=as_vec3(axis, "axis"),
                             angle=as_float(angle, "angle"),
                             center=None if center is None else as_vec3(center, "center"),
                             blend=blend, author=author)
        call_ms = (time.perf_counter() - t0) * 1e3
        return _step_result(o, self.version, call_ms)

    def configure(self, **settings: SettingValue) -> None:
        """Changes settings by name, all or none (InvalidArgumentError naming the setting)."""
        self.core.configure(**settings)

    def settings(self) -> Dict[str, SettingValue]:
        """Every setting with its current value (integral settings as int)."""
        return dict(self.core.settings())

    def remove(self, ids: ArrayLike) -> None:
        """Removes surfels by (K,) integer id."""
        self.core.remove(_ids(ids, "ids"))

    def release(self, author: str = "") -> bool:
        """Frees the tool of ``author``: its regions, detector and lock (one history entry, a new version);
        False (nothing changes) when it has no regions."""
        return bool(self.core.release(author=author))

    def undo(self) -> int:
        """Undoes the last change; returns the new version (ConflictError: nothing to undo)."""
        return int(self.core.undo())

    def redo(self) -> int:
        """Redoes the last undone change; returns the new version (ConflictError: nothing to redo)."""
        return int(self.core.redo())

    def history(self) -> List[HistoryEntry]:
        """The history entries, oldest first."""
        return [HistoryEntry(version=int(h["version"]), op=str(h["op"]), client=str(h["client"]),
                             touched=np.asarray(h["touched"], np.uint64), undone=bool(h["undone"]))
                for h in self.core.history()]

    def merge(self, crease: bool = True) -> MergeResult:
        """Merges the regions now (see :meth:`surfeledit.session_api.EditingSession.merge`)."""
        return self._merge_result(self.core.merge(crease=bool(crease)))

    def _merge_result(self, m: Dict[str, Any]) -> MergeResult:
        """The :class:`MergeResult` of the core's merge / boolean dict."""
        ids = [np.asarray(m[k], np.uint64) for k in ("removed", "features", "moved", "inserted")]
        readonly(ids)
        return MergeResult(*ids, curves=_curves(m["curves"]), version=self.version,
                           timings={"merge": float(m["merge_ms"]), "crease": float(m["crease_ms"]),
                                    "curves": float(m["curves_ms"])})

    def blend(self, iterations: int = 50, range_factor: float = 4.0, dt: float = 0.1, repulsion: str = "weight",
              weight: str = "compact", only_grow: bool = False, adaptive: bool = False,
              neighbourhood: str = "cached", features: Optional[ArrayLike] = None,
              projection: str = "mls") -> BlendResult:
        """Blend tool (see :meth:`surfeledit.session_api.EditingSession.blend`)."""
        f = None if features is None else _ids(features, "features")
        raw = self.core.blend(iterations=as_int(iterations, "iterations", *INT32),
                              range_factor=as_float(range_factor, "range_factor"), dt=as_float(dt, "dt"),
                              repulsion=str(repulsion), weight=str(weight), only_grow=bool(only_grow),
                              adaptive=bool(adaptive), neighbourhood=str(neighbourhood), features=f,
                              projection=str(projection))
        return blend_result(raw, self.version)

    def boolean(self, op: str, positions: ArrayLike, normals: ArrayLike,
                radii: Optional[ArrayLike] = None) -> MergeResult:
        """Boolean with model B (see :meth:`surfeledit.session_api.EditingSession.boolean`)."""
        pos = as_points(positions, "positions")
        nrm = as_points(normals, "normals", pos.shape[0])
        return self._merge_result(self.core.boolean(str(op), pos, nrm, as_radii(radii, pos.shape[0])))

    def fill_holes(self, max_diameter: float, iterations: int = 10,
                   boundary: Optional[ArrayLike] = None, projection: str = "mls") -> FillResult:
        """Hole filling (see :meth:`surfeledit.session_api.EditingSession.fill_holes`)."""
        b = None if boundary is None else _ids(boundary, "boundary")
        raw = self.core.fill_holes(as_float(max_diameter, "max_diameter"),
                                   iterations=as_int(iterations, "iterations", *INT32), boundary=b,
                                   projection=str(projection))
        return fill_result(raw, self.version)

    def intersection_curves(self, refine_angle: float = 0.5) -> List[Curve]:
        """Curves through the last merge's crease (see :meth:`surfeledit.session_api.EditingSession.intersection_curves`)."""
        return _curves(self.core.intersection_curves(refine_angle=as_float(refine_angle, "refine_angle")))

    def report(self) -> Dict[str, Any]:
        """``surfels``, ``structures`` {name: bytes}, ``total_bytes``, ``bytes_per_surfel`` and
        ``hierarchy_status`` (``'fresh'`` | ``'refit'`` | ``'rebuilding'``, ``''`` without a hierarchy)."""
        return dict(self.core.report())

    def state(self) -> State:
        """The whole model now, ids ascending (arrays read-only; the core hands out copies)."""
        c = self.core
        ids = np.asarray(c.ids(), np.uint64)
        arrays = [np.asarray(c.positions(), np.float64), np.asarray(c.normals(), np.float64),
                  np.asarray(c.radii(), np.float64)]
        raw = c.clips()
        clips = None if raw is None else np.hstack([np.asarray(raw[0], np.float64), np.asarray(raw[1], np.float64)])
        if ids.size > 1 and not bool(np.all(ids[1:] > ids[:-1])):
            order = np.argsort(ids, kind="stable")
            ids, arrays = ids[order], [a[order] for a in arrays]
            clips = None if clips is None else clips[order]
        clips = clips_or_none(clips)
        readonly([ids] + arrays + ([clips] if clips is not None else []))
        return State(self.version, ids, *arrays, clips=clips)

    def changes_since(self, version: int) -> Changes:
        """Nothing when ``version`` is the current one; otherwise the whole model (``full``: the
        in-process session keeps no change log)."""
        st = self.state()
        if as_int(version, "version", *VERSIONS) == st.version:
            none = np.zeros((0, 3))
            return Changes(st.version, False, st.ids[:0], none, none, st.radii[:0], st.ids[:0])
        return Changes(st.version, True, st.ids, st.positions, st.normals, st.radii, st.ids[:0], st.clips)

    # -- in-process only ---------------------------------------------------------------------
    def colliding(self) -> np.ndarray:
        """(C,) uint64 ids colliding after the last step, ascending."""
        return np.asarray(self.core.colliding(), np.uint64)

    def hierarchy(self) -> Dict[str, Any]:
        """The detector's trees: ``status``, ``zero_build_ms``, ``deformable_build_ms``, ``last_rebuild_ms``,
        ``rebuilds_adopted``."""
        return dict(self.core.hierarchy())

    def rebuild(self) -> bool:
        """Starts a background rebuild of the deformable tree; False when there is none or one is under way."""
        return bool(self.core.rebuild())


LocalSession.configure.__doc__ = (LocalSession.configure.__doc__ or "") + settings_doc()
