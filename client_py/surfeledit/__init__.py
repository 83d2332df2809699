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

The library logs to ``logging.getLogger("surfeledit")`` and never prints.
"""

from __future__ import annotations

import logging

from . import errors
from ._protocol import proto
from .client import (Changes, Client, CollisionStats, Session, State, StepResult, UpdateEvent, Watcher, connect,
                     find_server_executable)
from .errors import (ConflictError, InternalServerError, InvalidArgumentError, NotFoundError, RequestTimeoutError,
                     ServerIOError, ServerStartError, SurfelEditError, TooLargeError)

logging.getLogger("surfeledit").addHandler(logging.NullHandler())

__version__ = "0.1.0"

__all__ = [
    "connect", "Client", "Session", "StepResult", "CollisionStats", "State", "Changes", "UpdateEvent", "Watcher", "proto",
    "errors", "find_server_executable", "SurfelEditError", "InvalidArgumentError", "NotFoundError",
    "ConflictError", "TooLargeError", "ServerIOError", "InternalServerError", "RequestTimeoutError",
    "ServerStartError",
]
