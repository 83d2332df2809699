"""surfeledit: Python client for the surfeledit server (interactive editing of point-sampled surfaces).

Quick start::

    import surfeledit
    with surfeledit.connect() as client, client.open_session("demo") as s:
        s.load_points(positions, normals)            # (P, 3) float64 each
        s.set_regions(zero=slab_ids, one=sphere_ids)
        step = s.deform(translation=(0, 0, -0.05))
        print(step.seq, step.version, step.moved, s.positions().shape)
        s.configure(algorithm="temporal")            # collision detection: simple/improved/temporal/robust
        print(s.deform(translation=(0, 0, -0.05)).colliding)   # colliding ids after the step

``surfeledit.LocalSession()`` is the same session in-process (no server); both satisfy
:class:`surfeledit.EditingSession` and return the same result types.

The library logs to ``logging.getLogger("surfeledit")`` and never prints.
"""

from __future__ import annotations

import logging

from . import errors
from ._protocol import proto
from .connection import Client, connect
from .results import (Backoff, BlendResult, Changes, CollisionStats, Curve, FillResult, Hole, HistoryEntry, MergeResult,
                      State, StepResult, UpdateEvent)
from .server_process import find_server_executable
from .presence import Peer, PresenceEvent
from .session import Session
from .session_api import EditingSession
from .watcher import Watcher
from .errors import (ConflictError, InternalServerError, InvalidArgumentError, NotFoundError, RequestTimeoutError,
                     ServerIOError, ServerStartError, SurfelEditError, TooLargeError)

from .errors import AccessDeniedError, PermissionDeniedError, ReplyMismatchError, SecurityConfigError, ServerGoneError
from .security import SecurityConfig

logging.getLogger("surfeledit").addHandler(logging.NullHandler())


def __getattr__(name: str) -> object:
    # LocalSession needs the compiled surfeledit.core; import it only when asked for.
    if name == "LocalSession":
        from .local import LocalSession
        return LocalSession
    raise AttributeError(f"module 'surfeledit' has no attribute {name!r}")


__version__ = "0.1.0"

__all__ = [
    "connect", "Client", "Session", "EditingSession", "LocalSession", "StepResult", "CollisionStats", "State",
    "Backoff", "HistoryEntry",
    "Changes", "UpdateEvent", "MergeResult", "Curve", "Watcher", "proto", "BlendResult", "FillResult", "Hole",
    "errors", "find_server_executable", "SurfelEditError", "InvalidArgumentError", "NotFoundError",
    "ConflictError", "TooLargeError", "ServerIOError", "InternalServerError", "RequestTimeoutError",
    "ServerStartError", "PermissionDeniedError", "ServerGoneError", "ReplyMismatchError", "Peer", "PresenceEvent",
    "SecurityConfig", "SecurityConfigError", "AccessDeniedError",
]
