"""The client's former single module, kept so ``from surfeledit.client import ...`` goes on working.

The client is split by concept: :mod:`surfeledit.connection` (``Client``, ``connect``),
:mod:`surfeledit.server_process`, :mod:`surfeledit.session` (``Session``), :mod:`surfeledit.watcher`,
:mod:`surfeledit.results` and :mod:`surfeledit.arrays`; import from there (or from ``surfeledit``).
"""

from __future__ import annotations

from .connection import Client, connect
from .results import Changes, CollisionStats, State, StepResult, UpdateEvent
from .server_process import find_server_executable
from .session import Session
from .watcher import Watcher

__all__ = ["connect", "Client", "Session", "StepResult", "CollisionStats", "State", "Changes", "UpdateEvent",
           "Watcher", "find_server_executable"]
