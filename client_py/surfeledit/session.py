"""The remote editing session: :class:`Session`, one named session of a server, over a :class:`~surfeledit.Client`.

It satisfies :class:`surfeledit.session_api.EditingSession` with the result types of
:mod:`surfeledit.results`, like the in-process :class:`surfeledit.local.LocalSession`. Arrays are
numpy, row-major, in the server's id order; angles are radians, times milliseconds.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, Dict, List, Optional, Union

import numpy as np

from . import errors, wire_arrays
from ._protocol import proto
from .arrays import (VERSIONS, ArrayLike, SelectorLike, Vec3Like, as_float, as_ids, as_int, as_points, as_radii,
                     readonly, vec3)
from .results import Backoff, CollisionStats, Curve, HistoryEntry, MergeResult, SettingValue, State, StepResult
from .session_blend import BlendOps
from .session_presence import PresenceOps
from .session_state import StateOps
from .session_tools import ToolOps
from .session_api import StateArrays, settings_doc
from .presence import PresenceCallback
from .watcher import Watcher

if TYPE_CHECKING:
    from .connection import Client

__all__ = ["Session"]

_log = logging.getLogger("surfeledit")


def _setting(name: str, value: Any) -> "proto.Setting":
    """One named setting by the Python type of its value (bool, int/float, str)."""
    if not isinstance(name, str) or not name:
        raise errors.InvalidArgumentError(f"setting names must be non-empty strings, got {name!r}", str(name))
    if isinstance(value, (bool, np.bool_)):
        return proto.Setting(name=name, kind=proto.SettingKind.SETTING_BOOL, flag=bool(value))
    if isinstance(value, (int, np.integer)):
        return proto.Setting(name=name, kind=proto.SettingKind.SETTING_INT, number=float(value))
    if isinstance(value, (float, np.floating)):
        return proto.Setting(name=name, kind=proto.SettingKind.SETTING_NUMBER, number=float(value))
    if isinstance(value, str):
        return proto.Setting(name=name, kind=proto.SettingKind.SETTING_TEXT, text=value)
    raise errors.InvalidArgumentError(
        f"setting {name!r} must be a bool, a number or a string, got {type(value).__name__}", name)


def _setting_value(s: "proto.Setting") -> SettingValue:
    kind = s.kind
    if kind == proto.SettingKind.SETTING_BOOL:
        return bool(s.flag)
    if kind == proto.SettingKind.SETTING_TEXT:
        return str(s.text)
    if kind == proto.SettingKind.SETTING_INT:
        return int(s.number)
    return float(s.number)


def _step_result(reply: "proto.Reply", round_trip_ms: float) -> StepResult:
    """The :class:`StepResult` of a DEFORM reply (the only place that reads the wire's step type)."""
    if not reply.step:
        # Never a default StepResult: a deform reply without its result is not this request's answer.
        raise errors.ReplyMismatchError(f"deform reply (request {reply.request_id}) without a step result", "step")
    step = reply.step[0]
    colliding = np.asarray(step.colliding, dtype=np.uint64)
    depths = np.asarray(step.depths, dtype=np.float64)
    if depths.shape != colliding.shape:
        raise errors.InternalServerError(
            f"step reply has {depths.size} depths for {colliding.size} colliding ids", "step.depths")
    inserted = np.asarray(step.inserted, dtype=np.uint64)
    features = np.asarray(step.features, dtype=np.uint64)
    readonly((colliding, depths, inserted, features))
    st = step.stats
    stats = CollisionStats(deformable=int(st.deformable), tested=int(st.tested), queries=int(st.queries),
                           colliding=int(st.colliding), detect_ms=float(st.detect_ms),
                           preprocess_ms=float(st.preprocess_ms), nv=int(st.nv), np=int(st.np), nu=int(st.nu),
                           asleep=int(st.asleep))
    return StepResult(seq=int(step.seq), version=int(reply.version), moved=int(step.moved),
                      center=np.array([step.center.x, step.center.y, step.center.z]),
                      timings={t.name: float(t.ms) for t in reply.timings}, round_trip_ms=round_trip_ms,
                      detected=bool(step.detected), colliding=colliding, depths=depths, stats=stats,
                      inserted=inserted, response=str(step.response) or "none",
                      backoff=Backoff(iterations=int(step.backoff_iterations), kept=float(step.backoff_kept),
                                      final_depth=float(step.backoff_depth)),
                      features=features)


def _pair(selector: Any, name: str, form: str) -> Any:
    """A selector's two parts; InvalidArgumentError naming ``name`` when it is not a pair ``form``."""
    try:
        first, second = selector
    except (TypeError, ValueError):
        raise errors.InvalidArgumentError(f"{name} must be a pair {form}, got {selector!r}", name) from None
    return first, second


def _curves(wire: Any) -> List[Curve]:
    """:class:`Curve` objects of wire ``Curve`` samples (points read-only)."""
    out = []
    for c in wire:
        points = np.asarray(c.points, np.float64).reshape(-1, 3)
        readonly((points,))
        out.append(Curve(points=points, closed=bool(c.closed)))
    return out


class Session(BlendOps, PresenceOps, ToolOps, StateOps, StateArrays):
    """An opened or joined editing session; close it (or use ``with``) to detach.

    Attributes:
        client: the connection. name: the session's name.
        version: the session version of the last reply (0 before the first load).

    Optimistic concurrency: ``set_regions``, ``deform``, ``configure``, ``remove``, ``undo``, ``redo`` and
    ``merge`` take ``expect_version=v``: the op runs only when the session is still at version ``v``
    (:class:`~surfeledit.errors.ConflictError` with field ``"expect_version"`` naming the current version
    when another client's op came first; nothing changes). None: no condition.
    """

    def __init__(self, client: "Client", name: str, reply: "proto.Reply") -> None:
        self.client = client
        self.name = name
        self.version = 0
        self._info: Optional["proto.SessionInfo"] = None
        self._cache: Optional[State] = None
        self._closed = False
        self._absorb(reply)
        client.attach(self)

    def __enter__(self) -> "Session":
        return self

    def __exit__(self, *exc: Any) -> None:
        try:
            self.close()
        except errors.SurfelEditError:
            if exc[0] is None:
                raise
            _log.warning("closing session %r failed", self.name, exc_info=True)

    def __repr__(self) -> str:
        return f"Session({self.name!r}, version={self.version})"

    def close(self) -> None:
        """Detaches from the session (the server drops it when its last client leaves)."""
        self.client.detach(self)
        if self._closed or self.client.closed:
            self._closed = True
            return
        self._closed = True
        self._request(proto.Op.OP_CLOSE_SESSION)

    def _request(self, op: "proto.Op", expect_version: Optional[int] = None, **args: Any) -> "proto.Reply":
        """One request on this session (``expect_version``: the version the session must be at);
        keeps :attr:`version` and the last session info up to date."""
        if expect_version is not None:
            args["expect_version"] = [as_int(expect_version, "expect_version", *VERSIONS)]
        return self._absorb(self.client.request(op, self.name, **args))

    def _absorb(self, reply: "proto.Reply") -> "proto.Reply":
        """Keeps the version and the session info a reply carries."""
        if reply.version:
            self.version = int(reply.version)
        if reply.session_info:
            self._info = reply.session_info[0]
        return reply

    # -- access ------------------------------------------------------------------------------
    def invite(self, role: str = "editor") -> str:
        """A token that lets another client join this session (``client.join_session(name, token=...)``)
        as ``role``: ``"editor"`` (reads and changes) or ``"viewer"`` (reads only). Owner only
        (:class:`~surfeledit.errors.PermissionDeniedError` otherwise); tokens stay valid until the
        session is dropped and may be used by several clients."""
        if role not in ("editor", "viewer"):
            raise errors.InvalidArgumentError(f"role {role!r}: expected 'editor' or 'viewer'", "invite.role")
        reply = self._request(proto.Op.OP_INVITE, invite=proto.Invite(role=role))
        if not reply.token:
            raise errors.ReplyMismatchError("invite reply without a token", "token")
        return str(reply.token)

    # -- info --------------------------------------------------------------------------------
    def info(self) -> "proto.SessionInfo":
        """Session info: ``surfels``, ``has_regions``, ``state_hash``, ``clients``, ``bytes_per_surfel``,
        ``structures`` (name, bytes), ``settings`` (every setting; :meth:`settings` as a dict)."""
        reply = self._request(proto.Op.OP_INFO)
        if not reply.session_info:
            raise errors.NotFoundError(f"session {self.name!r} not reported by the server", "session")
        return self._info

    def report(self) -> Dict[str, Any]:
        """What the session holds: ``{"surfels": int, "structures": {name: bytes}, "total_bytes": int,
        "bytes_per_surfel": float}`` (from :meth:`info`)."""
        info = self.info()
        structures = {s.name: int(s.bytes) for s in info.structures}
        return dict(surfels=int(info.surfels), structures=structures, total_bytes=sum(structures.values()),
                    bytes_per_surfel=float(info.bytes_per_surfel))

    # -- loading -----------------------------------------------------------------------------
    def load_points(self, positions: ArrayLike, normals: ArrayLike,
                    radii: Optional[ArrayLike] = None) -> "proto.SessionInfo":
        """Replaces the model with the given surfels (chunked upload, atomic on the server).

        Args:
            positions: (P, 3) float64, model units.
            normals: (P, 3) float64, non-zero (normalised by the server).
            radii: (P,) float64 > 0, model units; None lets the server estimate them from spacing.

        Raises InvalidArgumentError (client side) on wrong shapes; the server validates values
        (finite, non-zero normals, positive radii) at commit and raises the typed error.
        Returns the session info.
        """
        self._upload(positions, normals, radii)
        self._request(proto.Op.OP_LOAD_COMMIT)
        self._cache = None
        return self._info

    def _upload(self, positions: ArrayLike, normals: ArrayLike, radii: Optional[ArrayLike]) -> None:
        """Sends surfels as the client's upload into this session (LOAD_BEGIN and the chunks; the op
        that consumes it follows: LOAD_COMMIT, or BOOLEAN for model B)."""
        pos = as_points(positions, "positions")
        nrm = as_points(normals, "normals", pos.shape[0])
        rad = as_radii(radii, pos.shape[0])
        total = pos.shape[0]
        chunk = self.client.max_chunk_surfels
        # Arrays go out as blocks of bytes where the binding allows it (wire_arrays.py), else as lists.
        seq = (lambda a: a) if wire_arrays.sends_arrays(proto.LoadChunk) else (lambda a: a.tolist())
        self._request(proto.Op.OP_LOAD_BEGIN, load_begin=proto.LoadBegin(total=total, has_radii=rad is not None))
        for off in range(0, total, chunk):
            end = min(total, off + chunk)
            self._request(proto.Op.OP_LOAD_CHUNK, load_chunk=proto.LoadChunk(
                offset=off,
                positions=seq(np.ascontiguousarray(pos[off:end]).ravel()),
                normals=seq(np.ascontiguousarray(nrm[off:end]).ravel()),
                radii=seq(rad[off:end]) if rad is not None else []))

    def load_file(self, path: Union[str, Path]) -> "proto.SessionInfo":
        """Loads a file on the server (.ply, .pcd, .obj, ASCII .off, .stl; .xyz or .pwn: text, x y z [nx ny nz] per
        line) as the new model: a path below the server's ``--data-root`` (relative paths are taken from there; file
        loading is off without it). The file is read off the server's request thread: other clients are served meanwhile."""
        self._request(proto.Op.OP_LOAD_FILE, load_file=proto.LoadFile(path=str(path)))
        self._cache = None
        return self._info

    # -- regions and deformation -------------------------------------------------------------
    def set_regions(self, zero: Optional[ArrayLike] = None, one: Optional[ArrayLike] = None,
                    zero_sphere: Optional[SelectorLike] = None, one_sphere: Optional[SelectorLike] = None,
                    zero_box: Optional[SelectorLike] = None, one_box: Optional[SelectorLike] = None,
                    expect_version: Optional[int] = None) -> "proto.SessionInfo":
        """Sets the zero region (never moves) and the one region (moves fully).

        Each region is the union of its ids ((K,) integer) and selectors, applied to the current
        positions: ``*_sphere = (center (3,), radius)``, ``*_box = (center (3,), half_extents (3,))``,
        model units. Both regions must end up non-empty and disjoint (server-checked: ConflictError).
        """
        def spec(ids: Optional[ArrayLike], sphere: Optional[SelectorLike], box: Optional[SelectorLike],
                 name: str) -> "proto.RegionSpec":
            selectors = []
            if sphere is not None:
                center, radius = _pair(sphere, f"{name}_sphere", "(center (3,), radius)")
                selectors.append(proto.Selector(kind=proto.SelectorKind.SELECTOR_SPHERE,
                                                center=vec3(center, f"{name}_sphere.center"),
                                                radius=as_float(radius, f"{name}_sphere.radius")))
            if box is not None:
                center, half = _pair(box, f"{name}_box", "(center (3,), half_extents (3,))")
                selectors.append(proto.Selector(kind=proto.SelectorKind.SELECTOR_BOX,
                                                center=vec3(center, f"{name}_box.center"),
                                                half_extents=vec3(half, f"{name}_box.half_extents")))
            return proto.RegionSpec(ids=as_ids(ids, name), selectors=selectors)

        arg = proto.SetRegions(zero=spec(zero, zero_sphere, zero_box, "zero"),
                               one=spec(one, one_sphere, one_box, "one"))
        self._request(proto.Op.OP_SET_REGIONS, expect_version, set_regions=arg)
        return self._info

    def deform(self, translation: Vec3Like = (0.0, 0.0, 0.0), axis: Vec3Like = (0.0, 0.0, 1.0),
               angle: float = 0.0, center: Optional[Vec3Like] = None, blend: str = "smooth",
               expect_version: Optional[int] = None) -> StepResult:
        """Applies one deformation step (then resampling and collision detection as configured).

        Args:
            translation: (3,) model units, applied fully to the one region.
            axis: (3,) rotation axis (normalised by the server; non-zero when ``angle != 0``).
            angle: radians.
            center: (3,) rotation centre; None -> centroid of the one region.
            blend: ``"smooth"``, ``"quadratic"`` or ``"linear"``.
            expect_version: run only if the session is at this version (ConflictError otherwise).
        """
        arg = proto.Deform(translation=vec3(translation, "translation"), axis=vec3(axis, "axis"),
                           angle=as_float(angle, "angle"), has_center=center is not None,
                           center=vec3(center, "center") if center is not None else proto.Vec3(),
                           blend=str(blend))
        t0 = time.perf_counter()
        reply = self._request(proto.Op.OP_DEFORM, expect_version, deform=arg)
        return _step_result(reply, (time.perf_counter() - t0) * 1e3)

    # -- settings and removal ----------------------------------------------------------------
    def configure(self, *, expect_version: Optional[int] = None, **settings: SettingValue) -> "proto.SessionInfo":
        """Changes session settings, all or none, e.g. ``configure(algorithm="temporal", boundary_n=8)``.

        Every setting is listed below (from the server's settings table). A bool is sent as a flag, an
        int as an integer, a float as a number, a str as text. The collision detector is re-initialised
        from the current model; the model and the version do not change.

        Returns the session info (its ``settings`` list every setting). Raises
        :class:`~surfeledit.errors.InvalidArgumentError` naming the setting (``.field``) for an unknown
        name, a value of the wrong kind or a bad value (nothing changes); a value of another Python
        type is refused before sending.
        """
        arg = proto.Configure(settings=[_setting(name, value) for name, value in settings.items()])
        self._request(proto.Op.OP_CONFIGURE, expect_version, configure=arg)
        return self._info

    def settings(self) -> Dict[str, SettingValue]:
        """Every session setting with its current value: ``{name: bool | int | float | str}``."""
        return {s.name: _setting_value(s) for s in self.info().settings}

    def remove(self, ids: ArrayLike, expect_version: Optional[int] = None) -> "proto.SessionInfo":
        """Removes surfels by id ((K,) integer); the other ids stay as they are.

        Raises :class:`~surfeledit.errors.NotFoundError` for an unknown id and
        :class:`~surfeledit.errors.ConflictError` when the zero or the one region would be left empty
        (nothing is removed then). Returns the session info.
        """
        id_list = as_ids(ids, "ids")
        if not id_list:
            raise errors.InvalidArgumentError("remove needs at least one id", "ids")
        self._request(proto.Op.OP_REMOVE, expect_version, remove=proto.Remove(ids=id_list))
        return self._info

    # -- history -----------------------------------------------------------------------------
    def undo(self, expect_version: Optional[int] = None) -> int:
        """Undoes this client's own last change, not another client's (published to watchers with cause
        ``"undo"``); returns the new version. ConflictError (field ``"history"``) when there is nothing to
        undo, or when a later change of another client touched one of its surfels (the message names that
        change's version and client); nothing changes then."""
        return int(self._request(proto.Op.OP_UNDO, expect_version).version)

    def redo(self, expect_version: Optional[int] = None) -> int:
        """Redoes this client's last undone change (cause ``"redo"``); returns the new version.
        ConflictError when there is nothing to redo or another client's later change is in the way."""
        return int(self._request(proto.Op.OP_REDO, expect_version).version)

    def history(self) -> List[HistoryEntry]:
        """The session's history entries, oldest first (``client`` is the client id that made each)."""
        reply = self._request(proto.Op.OP_HISTORY)
        return [HistoryEntry(version=int(h.version), op=str(h.op), client=str(h.client_id),
                             touched=np.asarray(h.touched, np.uint64), undone=bool(h.undone))
                for h in reply.history]

    # -- merge -------------------------------------------------------------------------------
    def merge(self, crease: bool = True, expect_version: Optional[int] = None) -> MergeResult:
        """Merges the regions now (see :meth:`surfeledit.session_api.EditingSession.merge`); watchers
        get cause ``"merge"`` with the clip lines."""
        reply = self._request(proto.Op.OP_MERGE, expect_version, merge=proto.Merge(crease=bool(crease)))
        return self._merge_result(reply, "MERGE")

    def _merge_result(self, reply: "proto.Reply", op: str) -> MergeResult:
        """The :class:`MergeResult` a MERGE / BOOLEAN reply carries."""
        if not reply.merge:
            raise errors.InternalServerError(f"{op} reply without a merge result", "merge")
        m = reply.merge[0]
        ids = [np.asarray(a, np.uint64) for a in (m.removed, m.features, m.moved, m.inserted)]
        readonly(ids)
        return MergeResult(*ids, curves=_curves(m.curves), version=int(reply.version),
                           timings={"merge": float(m.merge_ms), "crease": float(m.crease_ms),
                                    "curves": float(m.curves_ms)})

    def intersection_curves(self, refine_angle: float = 0.5) -> List[Curve]:
        """Curves through the last merge's crease (see :meth:`surfeledit.session_api.EditingSession.intersection_curves`)."""
        refine = as_float(refine_angle, "refine_angle")
        reply = self._request(proto.Op.OP_CURVES, curves=proto.Curves(refine_angle=refine))
        return _curves(reply.curves)

    # -- updates -----------------------------------------------------------------------------
    def watch(self, on_presence: Optional[PresenceCallback] = None, encoding: str = "full") -> Watcher:
        """Starts receiving this session's Update samples (from now on; fetch ``state()`` for the past);
        presence changes go to ``watcher.presence()`` and ``on_presence``, not into the model updates.
        ``encoding``: ``"full"`` (exact doubles) or ``"compact"`` (see :class:`~surfeledit.watcher.Watcher`)."""
        return Watcher(self.client, self.name, on_presence=on_presence, encoding=encoding)


Session.configure.__doc__ = (Session.configure.__doc__ or "") + settings_doc()
