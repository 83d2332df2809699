"""Backends of the scenario runner (:mod:`surfeledit.scenario`): one code path through an
:class:`~surfeledit.session_api.EditingSession`, in-process (:class:`LocalBackend`) or on a server over
DDS (:class:`RemoteBackend`)."""

from __future__ import annotations

import dataclasses
from typing import Any, Callable, Dict, Sequence

import numpy as np

from .local import LocalSession
from .results import State
from .scenes import SceneSetup
from .session_api import EditingSession


@dataclasses.dataclass
class StepOutput:
    """What a backend returns for one step.

    colliding: (C,) uint64 ids, ascending; depths: (C,) float64 model units; stats: the detector's
    counters (deformable, tested, queries, colliding, detect_ms, preprocess_ms, and in-process the
    hierarchies' nv, np, nu); inserted: (I,) uint64 ids added by resampling this step; step_ms: the
    whole call as the caller measured it (over DDS: the round trip).
    """

    colliding: np.ndarray
    depths: np.ndarray
    stats: Dict[str, float]
    inserted: np.ndarray
    step_ms: float


#: The model after a step: ids (P,) uint64 ascending, positions / normals (P, 3), radii (P,).
ModelState = State


class Backend:
    """Runs scenarios on an :class:`~surfeledit.session_api.EditingSession` — one code path in-process
    and over DDS. ``open_session(scene)`` makes the session; ``reopen``: a fresh one at each
    :meth:`start` (else the first is reloaded). Use :class:`LocalBackend` or :class:`RemoteBackend`.
    """

    kind = "?"

    def __init__(self, open_session: Callable[[SceneSetup], EditingSession], reopen: bool) -> None:
        self._open = open_session
        self._reopen = reopen
        # The EditingSession of the current run (a LocalSession's in-process extras, e.g. hierarchy(),
        # are reached through it); None before start() and after close().
        self.session: Any = None

    def start(self, scene: SceneSetup) -> None:
        """Loads the scene's start state and its regions (settings of a reloaded session persist)."""
        if self.session is None or self._reopen:
            self.close()
            self.session = self._open(scene)
        self.session.load_points(scene.positions, scene.normals, scene.radii)
        self.session.set_regions(zero=scene.zero, one=scene.one)

    def configure(self, **settings: Any) -> None:
        self.session.configure(**settings)

    def deform(self, **params: Any) -> StepOutput:
        r = self.session.deform(**params)
        return StepOutput(colliding=r.colliding, depths=r.depths, stats=r.stats.as_dict(), inserted=r.inserted,
                          step_ms=r.round_trip_ms)

    def state(self) -> ModelState:
        return self.session.state()

    def remove(self, ids: Sequence[int]) -> None:
        self.session.remove(np.asarray(ids, np.int64))

    def close(self) -> None:
        if self.session is not None:
            self.session.close()
            self.session = None


class LocalBackend(Backend):
    """In-process: a fresh :class:`~surfeledit.local.LocalSession` per run (``threads``: 0 = all)."""

    kind = "local"

    def __init__(self, threads: int = 0) -> None:
        self.threads = int(threads)
        super().__init__(lambda scene: LocalSession(f"scenario-{scene.name}", threads=self.threads), reopen=True)


class RemoteBackend(Backend):
    """On a server over DDS: one session ``name`` of ``client`` (a :class:`surfeledit.Client`),
    reloaded from the stored start state at each run."""

    kind = "remote"

    def __init__(self, client: Any, name: str = "scenario") -> None:
        self.client = client
        self.name = name
        super().__init__(lambda scene: client.open_session(name), reopen=False)
