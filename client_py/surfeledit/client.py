"""The surfeledit client: request/reply over Cyclone DDS, sessions, state fetching and watching.

Conventions: arrays are numpy, row-major, in the server's id order. Positions and normals are
``(P, 3) float64`` in model units (normals unit length), radii ``(P,) float64`` in model units, ids
``(P,) uint64``. Angles are radians, times milliseconds unless a name says ``_s`` (seconds).
"""

from __future__ import annotations

import dataclasses
import logging
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import threading
import time
import uuid
from pathlib import Path
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import numpy as np
from cyclonedds.core import DDSStatus, InstanceState, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.domain import DomainParticipant
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from . import errors
from ._protocol import (REPO_ROOT, TOPIC_REPLY, TOPIC_REQUEST, TOPIC_UPDATE, proto, reply_qos, request_qos,
                        update_qos)

__all__ = ["connect", "Client", "Session", "StepResult", "CollisionStats", "State", "Changes", "UpdateEvent",
           "Watcher", "find_server_executable"]

_log = logging.getLogger("surfeledit")

ArrayLike = Union[np.ndarray, Sequence[Any]]
Vec3Like = Union[Sequence[float], np.ndarray]
#: A sphere selector ``(center (3,), radius)`` or a box selector ``(center (3,), half_extents (3,))``.
SelectorLike = Tuple[Vec3Like, Any]

_ANY_NEW = SampleState.NotRead | ViewState.Any | InstanceState.Any
_PROBE_S = 1.5  # how long connect() looks for an already running server before spawning one


def _ns(seconds: float) -> int:
    return max(0, int(seconds * 1e9))


def _delete(*entities: Any) -> None:
    """Deletes DDS entities now instead of at garbage collection (Entity.__del__ is idempotent)."""
    for e in entities:
        if e is not None:
            try:
                e.__del__()
            except Exception:  # pragma: no cover - best effort at teardown
                _log.debug("deleting %r failed", e, exc_info=True)


def _vec3(v: Vec3Like, name: str) -> "proto.Vec3":
    a = np.asarray(v, dtype=np.float64)
    if a.shape != (3,):
        raise errors.InvalidArgumentError(f"{name} must have shape (3,), got {a.shape}", name)
    return proto.Vec3(float(a[0]), float(a[1]), float(a[2]))


def _as_points(a: ArrayLike, name: str, n: Optional[int] = None) -> np.ndarray:
    """Checks an (n, 3) float array (client-side shape check; values are validated by the server)."""
    try:
        arr = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise errors.InvalidArgumentError(f"{name} must be a numeric (P, 3) array: {e}", name) from None
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise errors.InvalidArgumentError(f"{name} must have shape (P, 3), got {arr.shape}", name)
    if n is not None and arr.shape[0] != n:
        raise errors.InvalidArgumentError(f"{name} has {arr.shape[0]} rows, positions has {n}", name)
    return np.ascontiguousarray(arr)


def _as_ids(a: Optional[ArrayLike], name: str) -> List[int]:
    if a is None:
        return []
    arr = np.asarray(a)
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise errors.InvalidArgumentError(f"{name} must be a 1-D array of ids, got shape {arr.shape}", name)
    if arr.size == 0:
        return []
    if not np.issubdtype(arr.dtype, np.integer):
        raise errors.InvalidArgumentError(f"{name} must hold integer ids, got dtype {arr.dtype}", name)
    if np.issubdtype(arr.dtype, np.signedinteger) and (arr < 0).any():
        raise errors.InvalidArgumentError(f"{name} holds a negative id", name)
    return arr.astype(np.uint64).tolist()


def _timings(reply: "proto.Reply") -> Dict[str, float]:
    return {t.name: float(t.ms) for t in reply.timings}


def find_server_executable() -> Optional[str]:
    """The surfeledit-server to spawn: env ``SURFELEDIT_SERVER``, then ``PATH``, then the build tree."""
    env = os.environ.get("SURFELEDIT_SERVER")
    if env:
        return env
    found = shutil.which("surfeledit-server")
    if found:
        return found
    local = REPO_ROOT / "build" / "server" / "app" / "surfeledit-server"
    return str(local) if local.is_file() else None


# ---------------------------------------------------------------------------------------------
# Results
# ---------------------------------------------------------------------------------------------


_NO_IDS = np.zeros(0, np.uint64)
_NO_IDS.setflags(write=False)


@dataclasses.dataclass(frozen=True)
class CollisionStats:
    """The collision detector's counters of one step (all zero when no detector ran).

    Attributes:
        deformable: deformable surfels considered. tested: surfels (re)evaluated this step.
        queries: nearest-neighbour queries made this step. colliding: surfels reported colliding.
        detect_ms: this step's detection time. preprocess_ms: the detector's last (re)initialisation.
    """

    deformable: int = 0
    tested: int = 0
    queries: int = 0
    colliding: int = 0
    detect_ms: float = 0.0
    preprocess_ms: float = 0.0


@dataclasses.dataclass(frozen=True)
class StepResult:
    """The outcome of one deformation step.

    Attributes:
        seq: 1-based step number in the session.
        version: session version after the step.
        moved: number of surfels displaced.
        center: rotation centre used, (3,) float64, model units.
        timings: server timings in ms (at least ``total``; deform adds ``apply``, and ``detect`` when a
            detector ran, ``resample`` when surfels were split).
        round_trip_ms: client-measured time from sending the request to receiving the reply.
        detected: a collision detector ran (the session's algorithm is not ``"none"``).
        colliding: (C,) uint64 ids of the surfels colliding after the step, ascending.
        depths: (C,) float64 penetration depth estimate per colliding id, model units.
        stats: the detector's :class:`CollisionStats` for this step.
        inserted: (I,) uint64 ids of surfels inserted by dynamic resampling in this step.
    """

    seq: int
    version: int
    moved: int
    center: np.ndarray
    timings: Dict[str, float]
    round_trip_ms: float
    detected: bool = False
    colliding: np.ndarray = dataclasses.field(default_factory=lambda: _NO_IDS)
    depths: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, np.float64))
    stats: CollisionStats = dataclasses.field(default_factory=CollisionStats)
    inserted: np.ndarray = dataclasses.field(default_factory=lambda: _NO_IDS)


@dataclasses.dataclass(frozen=True)
class State:
    """The whole model at ``version``; arrays are read-only views of the client's cache (copy to edit).

    Attributes:
        version: session version.
        ids: (P,) uint64, ascending.
        positions: (P, 3) float64, model units.
        normals: (P, 3) float64, unit length.
        radii: (P,) float64, model units.
    """

    version: int
    ids: np.ndarray
    positions: np.ndarray
    normals: np.ndarray
    radii: np.ndarray

    def __len__(self) -> int:
        return int(self.ids.shape[0])


@dataclasses.dataclass(frozen=True)
class Changes:
    """What changed since a version (the answer of ``changes_only`` GET_STATE, all pages joined).

    Attributes:
        version: session version the changes lead to.
        full: True when the model was replaced since then: the arrays are then the whole model.
        ids: (C,) uint64 changed or inserted ids, ascending; positions (C, 3), normals (C, 3), radii (C,).
        removed: (R,) uint64 ids removed since then.
    """

    version: int
    full: bool
    ids: np.ndarray
    positions: np.ndarray
    normals: np.ndarray
    radii: np.ndarray
    removed: np.ndarray


@dataclasses.dataclass(frozen=True)
class UpdateEvent:
    """One change published by the server, all ``parts`` reassembled.

    Attributes:
        session: session name. version: version after the change.
        cause: ``"load"``, ``"regions"``, ``"deform"``, ``"remove"`` or ``"close"``.
        full: a new model (replaces everything the watcher had). step: deform step number (0 otherwise).
        ids (N,) uint64, positions (N, 3), normals (N, 3), radii (N,) float64 of the changed surfels
        (for a deform: moved surfels and those inserted by resampling); removed (R,) uint64.
        detected: deform: a collision detector ran, and ``colliding`` (K,) uint64 holds every id
        colliding after the step, ascending (empty otherwise).

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
    colliding: np.ndarray = dataclasses.field(default_factory=lambda: _NO_IDS)


SettingValue = Union[bool, int, float, str]


def _setting(name: str, value: Any) -> "proto.Setting":
    """One named setting by the Python type of its value (bool, int/float, str)."""
    if not isinstance(name, str) or not name:
        raise errors.InvalidArgumentError(f"setting names must be non-empty strings, got {name!r}", str(name))
    if isinstance(value, (bool, np.bool_)):
        return proto.Setting(name=name, kind=proto.SettingKind.SETTING_BOOL, flag=bool(value))
    if isinstance(value, (int, float, np.integer, np.floating)):
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
    return float(s.number)


def _readonly(*arrays: np.ndarray) -> None:
    for a in arrays:
        a.setflags(write=False)


# ---------------------------------------------------------------------------------------------
# Client
# ---------------------------------------------------------------------------------------------


class Client:
    """A connection to a surfeledit server on one DDS domain (use :func:`connect`).

    Thread-safe for requests (one request is in flight at a time). Close it (or use ``with``) to
    release the DDS entities and stop a server it spawned.
    """

    def __init__(self, domain: int, timeout: float = 10.0, _server: Optional[subprocess.Popen] = None) -> None:
        self.domain = int(domain)
        self.timeout = float(timeout)
        self.client_id = f"{socket.gethostname()}-{os.getpid()}-{uuid.uuid4().hex[:12]}"
        self._next_id = 1
        self._lock = threading.RLock()
        self._server = _server
        self._server_log: Optional[Path] = None
        self._server_info: Optional["proto.ServerInfo"] = None
        self._closed = False
        self._watchers: List["Watcher"] = []
        self._sessions: List["Session"] = []

        self._participant = DomainParticipant(self.domain)
        self._req_topic = Topic(self._participant, TOPIC_REQUEST, proto.Request)
        self._rep_topic = Topic(self._participant, TOPIC_REPLY, proto.Reply)
        self._upd_topic: Optional[Topic] = None
        self._writer = DataWriter(self._participant, self._req_topic, qos=request_qos())
        self._reader = DataReader(self._participant, self._rep_topic, qos=reply_qos())
        self._cond = ReadCondition(self._reader, _ANY_NEW)
        self._waitset = WaitSet(self._participant)
        self._waitset.attach(self._cond)

    # -- lifecycle -------------------------------------------------------------------------------
    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def close(self) -> None:
        """Closes watchers and DDS entities, then stops the server if this client spawned it."""
        if self._closed:
            return
        # Detach so the server can drop sessions nobody uses; skip it when no server is matched any
        # more (it exited), which would only wait for request timeouts.
        server_present = self._writer.get_publication_matched_status().current_count > 0
        for sess in list(self._sessions):
            try:
                if server_present:
                    sess.close()
                else:
                    sess._closed = True
                    self._sessions.remove(sess)
            except errors.SurfelEditError:
                _log.warning("closing session %r failed", sess.name, exc_info=True)
        self._closed = True
        for w in list(self._watchers):
            w.close()
        _delete(self._waitset, self._cond, self._reader, self._writer, self._rep_topic, self._req_topic,
                self._upd_topic, self._participant)
        if self._server is not None:
            _stop_process(self._server)
            self._server = None

    @property
    def closed(self) -> bool:
        return self._closed

    # -- matching ------------------------------------------------------------------------------
    def wait_for_server(self, timeout: float) -> bool:
        """Waits until a server's request reader and reply writer are discovered; True if so."""
        deadline = time.monotonic() + timeout
        ws = WaitSet(self._participant)
        try:
            self._writer.set_status_mask(DDSStatus.PublicationMatched)
            self._reader.set_status_mask(DDSStatus.SubscriptionMatched)
            ws.attach(self._writer)
            ws.attach(self._reader)
            while True:
                if (self._writer.get_publication_matched_status().current_count > 0
                        and self._reader.get_subscription_matched_status().current_count > 0):
                    return True
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return False
                ws.wait(_ns(min(remaining, 0.05)))
        finally:
            for e in (self._writer, self._reader):
                try:
                    ws.detach(e)
                    e.set_status_mask(0)
                except Exception:  # pragma: no cover
                    pass
            _delete(ws)

    # -- low-level request API -----------------------------------------------------------------
    def new_request(self, op: "proto.Op", session: str = "", **args: Any) -> "proto.Request":
        """Builds a request with the next request id; ``args`` are the IDL argument fields, e.g.
        ``deform=proto.Deform(...)`` (wrapped into the 0-or-1 element sequence)."""
        with self._lock:
            rid = self._next_id
            self._next_id += 1
        req = proto.Request(client_id=self.client_id, request_id=rid, session=session, op=op)
        for name, value in args.items():
            if not hasattr(req, name) or name in ("client_id", "request_id", "session", "op"):
                raise TypeError(f"unknown request argument {name!r}")
            setattr(req, name, list(value) if isinstance(value, (list, tuple)) else [value])
        return req

    def call(self, request: "proto.Request", check: bool = True, timeout: Optional[float] = None,
             retries: int = 1) -> "proto.Reply":
        """Sends ``request`` and returns its reply (matched on client id and request id).

        On timeout the same request (same id) is sent again up to ``retries`` times — the server
        answers a repeat from its reply cache — then :class:`~surfeledit.errors.RequestTimeoutError`
        is raised. With ``check`` a non-OK status raises the typed error of ``surfeledit.errors``.
        """
        if self._closed:
            raise errors.SurfelEditError("client is closed")
        timeout = self.timeout if timeout is None else timeout
        with self._lock:
            for attempt in range(retries + 1):
                self._writer.write(request)
                reply = self._wait_reply(request.request_id, time.monotonic() + timeout)
                if reply is not None:
                    break
                _log.warning("no reply to request %d (%s) within %.1f s%s", request.request_id,
                             request.op.name, timeout, "; retrying" if attempt < retries else "")
            else:
                raise errors.RequestTimeoutError(
                    f"no reply to request {request.request_id} ({request.op.name}) on domain {self.domain} "
                    f"within {timeout:.1f} s (tried {retries + 1} times)")
        if check and reply.status != proto.Status.STATUS_OK:
            raise errors.error_for_status(int(reply.status.value), reply.message, reply.field)
        return reply

    def request(self, op: "proto.Op", session: str = "", check: bool = True, **args: Any) -> "proto.Reply":
        """``call(new_request(op, session, **args))``."""
        return self.call(self.new_request(op, session, **args), check=check)

    def _wait_reply(self, request_id: int, deadline: float) -> Optional["proto.Reply"]:
        while True:
            # Drain everything new; replies for other clients (same topic) and stale repeats are dropped.
            while True:
                samples = self._reader.take(N=64, condition=self._cond)
                if not samples:
                    break
                for s in samples:
                    if not isinstance(s, proto.Reply):
                        continue  # instance-state change without data
                    if s.client_id == self.client_id and s.request_id == request_id:
                        return s
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return None
            self._waitset.wait(_ns(remaining))

    # -- high-level API -------------------------------------------------------------------------
    def info(self, session: str = "") -> "proto.ServerInfo":
        """Server info (``version``, ``uptime_s``, ``sessions``, ``max_chunk_surfels``, ``max_model_surfels``)."""
        reply = self.request(proto.Op.OP_INFO, session)
        if not reply.server_info:
            raise errors.InternalServerError("OP_INFO reply without server_info", "server_info")
        self._server_info = reply.server_info[0]
        return self._server_info

    @property
    def max_chunk_surfels(self) -> int:
        """The server's per-chunk/page limit (from the last info; fetched if unknown)."""
        info = self._server_info or self.info()
        return int(info.max_chunk_surfels) or 65536

    def open_session(self, name: str) -> "Session":
        """Creates the named session (or attaches if it exists)."""
        reply = self.request(proto.Op.OP_OPEN_SESSION, name)
        return Session(self, name, reply)

    def join_session(self, name: str) -> "Session":
        """Attaches to an existing session (:class:`~surfeledit.errors.NotFoundError` otherwise)."""
        reply = self.request(proto.Op.OP_JOIN_SESSION, name)
        return Session(self, name, reply)

    def _update_topic(self) -> Topic:
        if self._upd_topic is None:
            self._upd_topic = Topic(self._participant, TOPIC_UPDATE, proto.Update)
        return self._upd_topic


def _stop_process(proc: subprocess.Popen, grace: float = 5.0) -> None:
    """SIGTERM, wait up to ``grace`` seconds, then SIGKILL."""
    if proc.poll() is not None:
        return
    try:
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=grace)
    except subprocess.TimeoutExpired:
        _log.warning("surfeledit-server (pid %d) ignored SIGTERM for %.0f s; killing it", proc.pid, grace)
        proc.kill()
        proc.wait()


def _probe(client: Client, timeout: float) -> bool:
    """True if a server answers OP_INFO within ``timeout`` seconds."""
    if not client.wait_for_server(timeout):
        return False
    try:
        reply = client.call(client.new_request(proto.Op.OP_INFO), timeout=max(0.5, timeout), retries=1)
    except errors.RequestTimeoutError:
        return False
    client._server_info = reply.server_info[0] if reply.server_info else None
    return True


def connect(domain: Optional[int] = None, spawn: bool = True, timeout: float = 10.0) -> Client:
    """Connects to the surfeledit server on a DDS domain.

    Args:
        domain: DDS domain id; None -> env ``SURFELEDIT_DOMAIN`` or 0.
        spawn: when no server answers ``OP_INFO`` within a short probe, start
            ``surfeledit-server --domain D`` (see :func:`find_server_executable`), wait until it
            answers, and stop it when the client closes.
        timeout: seconds to wait for each reply (a request is retried once) and for a spawned
            server to come up.

    Raises:
        ServerStartError: no server answered (spawn=False), or one could not be found/started.
    """
    if domain is None:
        domain = int(os.environ.get("SURFELEDIT_DOMAIN", "0"))
    client = Client(domain, timeout)
    try:
        if _probe(client, min(_PROBE_S, timeout)):
            return client
        if not spawn:
            raise errors.ServerStartError(f"no surfeledit server answers on DDS domain {domain}")
        exe = find_server_executable()
        if exe is None:
            raise errors.ServerStartError(
                "no surfeledit server answers on DDS domain %d and surfeledit-server was not found "
                "(set SURFELEDIT_SERVER, put it on PATH, or build it into build/server/app)" % domain)
        log = tempfile.NamedTemporaryFile(prefix=f"surfeledit-server-{domain}-", suffix=".log", delete=False)
        _log.info("starting %s --domain %d (log: %s)", exe, domain, log.name)
        try:
            proc = subprocess.Popen([exe, "--domain", str(domain)], stdin=subprocess.DEVNULL, stdout=log,
                                    stderr=subprocess.STDOUT, start_new_session=True)
        except OSError as e:
            raise errors.ServerStartError(f"cannot start {exe}: {e}") from e
        finally:
            log.close()
        client._server = proc
        client._server_log = Path(log.name)
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if proc.poll() is not None:
                tail = Path(log.name).read_text(errors="replace")[-2000:]
                raise errors.ServerStartError(f"{exe} exited with code {proc.returncode} before answering:\n{tail}")
            if _probe(client, min(1.0, max(0.1, deadline - time.monotonic()))):
                return client
        raise errors.ServerStartError(f"{exe} (pid {proc.pid}) did not answer OP_INFO within {timeout:.1f} s "
                                      f"(log: {log.name})")
    except BaseException:
        client.close()
        raise


# ---------------------------------------------------------------------------------------------
# Session
# ---------------------------------------------------------------------------------------------


class Session:
    """An opened or joined editing session; close it (or use ``with``) to detach."""

    def __init__(self, client: Client, name: str, reply: "proto.Reply") -> None:
        self.client = client
        self.name = name
        self.version = int(reply.version)
        self._info = reply.session_info[0] if reply.session_info else None
        self._cache: Optional[State] = None
        self._closed = False
        client._sessions.append(self)

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
        if self in self.client._sessions:
            self.client._sessions.remove(self)
        if self._closed or self.client.closed:
            self._closed = True
            return
        self._closed = True
        self._request(proto.Op.OP_CLOSE_SESSION)

    def _request(self, op: "proto.Op", **args: Any) -> "proto.Reply":
        reply = self.client.request(op, self.name, **args)
        if reply.version:
            self.version = int(reply.version)
        return reply

    # -- info --------------------------------------------------------------------------------
    def info(self) -> "proto.SessionInfo":
        """Session info: ``surfels``, ``has_regions``, ``state_hash``, ``clients``, ``bytes_per_surfel``,
        ``structures`` (name, bytes), ``settings`` (every setting; :meth:`settings` as a dict)."""
        reply = self.client.request(proto.Op.OP_INFO, self.name)
        if not reply.session_info:
            raise errors.NotFoundError(f"session {self.name!r} not reported by the server", "session")
        self._info = reply.session_info[0]
        self.version = int(reply.version) or self.version
        return self._info

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
        """
        pos = _as_points(positions, "positions")
        nrm = _as_points(normals, "normals", pos.shape[0])
        rad: Optional[np.ndarray] = None
        if radii is not None:
            rad = np.asarray(radii, dtype=np.float64)
            if rad.ndim != 1 or rad.shape[0] != pos.shape[0]:
                raise errors.InvalidArgumentError(f"radii must have shape ({pos.shape[0]},), got {rad.shape}",
                                                  "radii")
        total = pos.shape[0]
        chunk = self.client.max_chunk_surfels
        self._request(proto.Op.OP_LOAD_BEGIN, load_begin=proto.LoadBegin(total=total, has_radii=rad is not None))
        for off in range(0, total, chunk):
            end = min(total, off + chunk)
            self._request(proto.Op.OP_LOAD_CHUNK, load_chunk=proto.LoadChunk(
                offset=off,
                positions=pos[off:end].ravel().tolist(),
                normals=nrm[off:end].ravel().tolist(),
                radii=rad[off:end].tolist() if rad is not None else []))
        reply = self._request(proto.Op.OP_LOAD_COMMIT)
        self._cache = None
        if reply.session_info:
            self._info = reply.session_info[0]
        return self._info

    def load_file(self, path: Union[str, Path]) -> "proto.SessionInfo":
        """Loads a file on the server's file system (.ply, .pcd, .obj) as the new model."""
        reply = self._request(proto.Op.OP_LOAD_FILE, load_file=proto.LoadFile(path=str(path)))
        self._cache = None
        if reply.session_info:
            self._info = reply.session_info[0]
        return self._info

    # -- regions and deformation -------------------------------------------------------------
    def set_regions(self, zero: Optional[ArrayLike] = None, one: Optional[ArrayLike] = None,
                    zero_sphere: Optional[SelectorLike] = None, one_sphere: Optional[SelectorLike] = None,
                    zero_box: Optional[SelectorLike] = None, one_box: Optional[SelectorLike] = None
                    ) -> "proto.SessionInfo":
        """Sets the zero region (never moves) and the one region (moves fully).

        Each region is the union of its ids ((K,) integer) and selectors, applied to the current
        positions: ``*_sphere = (center (3,), radius)``, ``*_box = (center (3,), half_extents (3,))``,
        model units. Both regions must end up non-empty and disjoint (server-checked).
        """
        def spec(ids: Optional[ArrayLike], sphere: Optional[SelectorLike], box: Optional[SelectorLike],
                 name: str) -> "proto.RegionSpec":
            selectors = []
            if sphere is not None:
                center, radius = sphere
                selectors.append(proto.Selector(kind=proto.SelectorKind.SELECTOR_SPHERE,
                                                center=_vec3(center, f"{name}_sphere.center"),
                                                radius=float(radius)))
            if box is not None:
                center, half = box
                selectors.append(proto.Selector(kind=proto.SelectorKind.SELECTOR_BOX,
                                                center=_vec3(center, f"{name}_box.center"),
                                                half_extents=_vec3(half, f"{name}_box.half_extents")))
            return proto.RegionSpec(ids=_as_ids(ids, name), selectors=selectors)

        arg = proto.SetRegions(zero=spec(zero, zero_sphere, zero_box, "zero"),
                               one=spec(one, one_sphere, one_box, "one"))
        reply = self._request(proto.Op.OP_SET_REGIONS, set_regions=arg)
        if reply.session_info:
            self._info = reply.session_info[0]
        return self._info

    def deform(self, translation: Vec3Like = (0.0, 0.0, 0.0), axis: Vec3Like = (0.0, 0.0, 1.0),
               angle: float = 0.0, center: Optional[Vec3Like] = None, blend: str = "smooth") -> StepResult:
        """Applies one deformation step.

        Args:
            translation: (3,) model units, applied fully to the one region.
            axis: (3,) rotation axis (normalised by the server; non-zero when ``angle != 0``).
            angle: radians.
            center: (3,) rotation centre; None -> centroid of the one region.
            blend: ``"smooth"``, ``"quadratic"`` or ``"linear"``.
        """
        arg = proto.Deform(translation=_vec3(translation, "translation"), axis=_vec3(axis, "axis"),
                           angle=float(angle), has_center=center is not None,
                           center=_vec3(center, "center") if center is not None else proto.Vec3(),
                           blend=str(blend))
        t0 = time.perf_counter()
        reply = self._request(proto.Op.OP_DEFORM, deform=arg)
        rt = (time.perf_counter() - t0) * 1e3
        step = reply.step[0] if reply.step else proto.StepInfo()
        colliding = np.asarray(step.colliding, dtype=np.uint64)
        depths = np.asarray(step.depths, dtype=np.float64)
        if depths.shape != colliding.shape:
            raise errors.InternalServerError(
                f"step reply has {depths.size} depths for {colliding.size} colliding ids", "step.depths")
        inserted = np.asarray(step.inserted, dtype=np.uint64)
        _readonly(colliding, depths, inserted)
        st = step.stats
        stats = CollisionStats(deformable=int(st.deformable), tested=int(st.tested), queries=int(st.queries),
                               colliding=int(st.colliding), detect_ms=float(st.detect_ms),
                               preprocess_ms=float(st.preprocess_ms))
        return StepResult(seq=int(step.seq), version=int(reply.version), moved=int(step.moved),
                          center=np.array([step.center.x, step.center.y, step.center.z]),
                          timings=_timings(reply), round_trip_ms=rt, detected=bool(step.detected),
                          colliding=colliding, depths=depths, stats=stats, inserted=inserted)

    # -- settings and removal ----------------------------------------------------------------
    def configure(self, **settings: SettingValue) -> "proto.SessionInfo":
        """Changes session settings, all or none, e.g. ``configure(algorithm="temporal", boundary_n=8)``.

        Names and meanings: ``algorithm`` (``"none"``, ``"simple"``, ``"improved"``, ``"temporal"``,
        ``"robust"``), ``threshold``, ``boundary``, ``boundary_n``, ``boundary_i``, ``step_bound``,
        ``threads``, ``resample``, ``split_threshold`` (see :meth:`settings`). A bool is sent as a flag,
        an int or float as a number, a str as text. The collision detector is re-initialised from the
        current model; the model and the version do not change.

        Returns the session info (its ``settings`` list every setting). Raises
        :class:`~surfeledit.errors.InvalidArgumentError` naming the setting (``.field``) for an unknown
        name, a value of the wrong kind or a bad value (nothing changes); a value of another Python
        type is refused before sending.
        """
        arg = proto.Configure(settings=[_setting(name, value) for name, value in settings.items()])
        reply = self._request(proto.Op.OP_CONFIGURE, configure=arg)
        if reply.session_info:
            self._info = reply.session_info[0]
        return self._info

    def settings(self) -> Dict[str, SettingValue]:
        """Every session setting with its current value: ``{name: bool | float | str}`` (integers as float)."""
        info = self.info()
        return {s.name: _setting_value(s) for s in info.settings}

    def remove(self, ids: ArrayLike) -> "proto.SessionInfo":
        """Removes surfels by id ((K,) integer); the other ids stay as they are.

        Raises :class:`~surfeledit.errors.NotFoundError` for an unknown id and
        :class:`~surfeledit.errors.ConflictError` when the zero or the one region would be left empty
        (nothing is removed then). Returns the session info.
        """
        id_list = _as_ids(ids, "ids")
        if not id_list:
            raise errors.InvalidArgumentError("remove needs at least one id", "ids")
        reply = self._request(proto.Op.OP_REMOVE, remove=proto.Remove(ids=id_list))
        if reply.session_info:
            self._info = reply.session_info[0]
        return self._info

    # -- state -------------------------------------------------------------------------------
    def _fetch(self, changes_only: bool, since: int) -> Changes:
        """Reads all pages of one GET_STATE answer; restarts if the version moves between pages."""
        for _attempt in range(8):
            pages: List["proto.StatePage"] = []
            version: Optional[int] = None
            offset = 0
            restart = False
            while True:
                reply = self._request(proto.Op.OP_GET_STATE, get_state=proto.GetState(
                    changes_only=changes_only, since_version=since, offset=offset, max_count=0))
                if not reply.state:
                    raise errors.InternalServerError("GET_STATE reply without a state page", "state")
                page = reply.state[0]
                if version is None:
                    version = int(reply.version)
                elif int(reply.version) != version:
                    restart = True
                    break
                pages.append(page)
                offset = int(page.offset) + len(page.ids)
                if offset >= int(page.total):
                    break
                if not page.ids:
                    raise errors.InternalServerError(f"empty state page at offset {offset} of {page.total}",
                                                     "state")
            if restart:
                _log.debug("session %r changed while paging; restarting the fetch", self.name)
                continue
            assert version is not None
            ids = np.concatenate([np.asarray(p.ids, dtype=np.uint64) for p in pages]) if pages else \
                np.zeros(0, np.uint64)
            pos = np.concatenate([np.asarray(p.positions, dtype=np.float64) for p in pages]).reshape(-1, 3)
            nrm = np.concatenate([np.asarray(p.normals, dtype=np.float64) for p in pages]).reshape(-1, 3)
            rad = np.concatenate([np.asarray(p.radii, dtype=np.float64) for p in pages])
            removed = np.asarray(pages[0].removed, dtype=np.uint64) if pages else np.zeros(0, np.uint64)
            return Changes(version=version, full=bool(pages[0].full) if pages else not changes_only,
                           ids=ids, positions=pos, normals=nrm, radii=rad, removed=removed)
        raise errors.ConflictError(f"session {self.name!r} kept changing while its state was fetched", "version")

    def changes_since(self, version: int) -> Changes:
        """Surfels changed or inserted since ``version`` plus removed ids (whole model if replaced)."""
        return self._fetch(True, int(version))

    def state(self) -> State:
        """The whole model at the current version.

        The last full fetch is cached by version; later calls fetch only the changes since then.
        """
        cache = self._cache
        if cache is None:
            ch = self._fetch(False, 0)
            new = State(ch.version, ch.ids, ch.positions, ch.normals, ch.radii)
        else:
            ch = self._fetch(True, cache.version)
            if ch.version == cache.version and ch.ids.size == 0 and ch.removed.size == 0:
                return cache
            new = State(ch.version, ch.ids, ch.positions, ch.normals, ch.radii) if ch.full else _merge(cache, ch)
        _readonly(new.ids, new.positions, new.normals, new.radii)
        self._cache = new
        self.version = new.version
        return new

    def ids(self) -> np.ndarray:
        """(P,) uint64 ids, ascending (the order of every other array)."""
        return self.state().ids

    def positions(self) -> np.ndarray:
        """(P, 3) float64 positions, model units, in id order."""
        return self.state().positions

    def normals(self) -> np.ndarray:
        """(P, 3) float64 unit normals, in id order."""
        return self.state().normals

    def radii(self) -> np.ndarray:
        """(P,) float64 radii, model units, in id order."""
        return self.state().radii

    # -- updates -----------------------------------------------------------------------------
    def watch(self) -> "Watcher":
        """Starts receiving this session's Update samples (from now on; fetch ``state()`` for the past)."""
        return Watcher(self.client, self.name)


def _merge(cache: State, ch: Changes) -> State:
    """Applies incremental changes to a cached state (ids stay ascending)."""
    ids, pos, nrm, rad = cache.ids, cache.positions, cache.normals, cache.radii
    if ch.removed.size:
        keep = ~np.isin(ids, ch.removed)
        ids, pos, nrm, rad = ids[keep], pos[keep], nrm[keep], rad[keep]
    ids, pos, nrm, rad = ids.copy(), pos.copy(), nrm.copy(), rad.copy()
    if ch.ids.size:
        idx = np.searchsorted(ids, ch.ids)
        found = idx < ids.size
        found[found] = ids[idx[found]] == ch.ids[found]
        rows = idx[found]
        pos[rows], nrm[rows], rad[rows] = ch.positions[found], ch.normals[found], ch.radii[found]
        if not found.all():
            new = ~found
            ids = np.concatenate([ids, ch.ids[new]])
            pos = np.concatenate([pos, ch.positions[new]])
            nrm = np.concatenate([nrm, ch.normals[new]])
            rad = np.concatenate([rad, ch.radii[new]])
            order = np.argsort(ids, kind="stable")
            ids, pos, nrm, rad = ids[order], pos[order], nrm[order], rad[order]
    return State(ch.version, ids, pos, nrm, rad)


# ---------------------------------------------------------------------------------------------
# Watching updates
# ---------------------------------------------------------------------------------------------


class Watcher:
    """Receives a session's ``Update`` samples and reassembles multi-part changes.

    Use :meth:`get` (blocking with timeout), :meth:`poll` (non-blocking, e.g. from a GUI timer) or
    iterate (``for ev in watcher`` blocks; it ends after a ``close`` update or :meth:`close`).
    """

    def __init__(self, client: Client, session: str) -> None:
        self.client = client
        self.session = session
        self._reader = DataReader(client._participant, client._update_topic(), qos=update_qos())
        self._cond = ReadCondition(self._reader, _ANY_NEW)
        self._waitset = WaitSet(client._participant)
        self._waitset.attach(self._cond)
        self._pending: Dict[int, Dict[int, "proto.Update"]] = {}
        self._ready: List[UpdateEvent] = []
        self._closed = False
        self._lock = threading.Lock()
        client._watchers.append(self)
        self._wait_matched(2.0)

    def _wait_matched(self, timeout: float) -> None:
        """Waits (bounded) until the server's update writer is discovered: updates are volatile."""
        deadline = time.monotonic() + timeout
        ws = WaitSet(self.client._participant)
        try:
            self._reader.set_status_mask(DDSStatus.SubscriptionMatched)
            ws.attach(self._reader)
            while self._reader.get_subscription_matched_status().current_count == 0:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    _log.warning("watcher of %r: no update writer discovered within %.1f s", self.session, timeout)
                    return
                ws.wait(_ns(min(remaining, 0.05)))
        finally:
            try:
                ws.detach(self._reader)
                self._reader.set_status_mask(0)
            except Exception:  # pragma: no cover
                pass
            _delete(ws)

    def __enter__(self) -> "Watcher":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        if self in self.client._watchers:
            self.client._watchers.remove(self)
        _delete(self._waitset, self._cond, self._reader)

    def _drain(self) -> None:
        while True:
            samples = self._reader.take(N=64, condition=self._cond)
            if not samples:
                return
            for s in samples:
                if isinstance(s, proto.Update) and s.session == self.session:
                    self._add(s)

    def _add(self, s: "proto.Update") -> None:
        parts = max(1, int(s.parts))
        got = self._pending.setdefault(int(s.version), {})
        got[int(s.part)] = s
        if len(got) < parts:
            return
        del self._pending[int(s.version)]
        ordered = [got[i] for i in sorted(got)]
        first = ordered[0]

        def cat(name: str, dtype: Any) -> np.ndarray:
            arrays = [np.asarray(getattr(p, name), dtype=dtype) for p in ordered]
            return np.concatenate(arrays) if arrays else np.zeros(0, dtype)

        self._ready.append(UpdateEvent(
            session=first.session, version=int(first.version), cause=first.cause, full=bool(first.full),
            step=int(first.step), ids=cat("ids", np.uint64), positions=cat("positions", np.float64).reshape(-1, 3),
            normals=cat("normals", np.float64).reshape(-1, 3), radii=cat("radii", np.float64),
            removed=cat("removed", np.uint64), detected=bool(first.detected),
            colliding=np.asarray(first.colliding, dtype=np.uint64)))
        self._ready.sort(key=lambda e: e.version)

    def poll(self) -> List[UpdateEvent]:
        """All complete updates received so far (non-blocking), oldest first."""
        with self._lock:
            if self._closed:
                return []
            self._drain()
            out, self._ready = self._ready, []
            return out

    def get(self, timeout: Optional[float] = None) -> Optional[UpdateEvent]:
        """The next complete update, waiting up to ``timeout`` seconds (None: forever); None on timeout."""
        deadline = None if timeout is None else time.monotonic() + timeout
        with self._lock:
            while not self._closed:
                self._drain()
                if self._ready:
                    return self._ready.pop(0)
                if deadline is None:
                    self._waitset.wait(_ns(1.0))
                else:
                    remaining = deadline - time.monotonic()
                    if remaining <= 0:
                        return None
                    self._waitset.wait(_ns(remaining))
        return None

    def __iter__(self) -> Iterator[UpdateEvent]:
        while not self._closed:
            ev = self.get(timeout=None)
            if ev is None:
                return
            yield ev
            if ev.cause == "close":
                return
