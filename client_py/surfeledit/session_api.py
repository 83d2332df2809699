"""The editing-session contract: what every session offers, in-process or over DDS.

:class:`EditingSession` is satisfied by the remote :class:`surfeledit.Session` and the in-process
:class:`surfeledit.local.LocalSession`, both returning the result types of :mod:`surfeledit.results`.
Code written against it (the scenario runner, tests, a GUI) runs either way with one code path.
A new session operation is added here, then to both sessions.

Conventions: positions / normals ``(P, 3) float64`` (model units; normals unit length), radii
``(P,) float64`` (model units), ids ``(P,) uint64`` ascending, angles radians, times ms. Failures
are the typed errors of :mod:`surfeledit.errors` (same class for the same mistake either way).
"""

from __future__ import annotations

from typing import Any, Dict, List, Optional, Protocol, runtime_checkable

import numpy as np

from .arrays import ArrayLike, Vec3Like
from .results import BlendResult, Changes, Curve, FillResult, HistoryEntry, MergeResult, SettingValue, State, StepResult

__all__ = ["EditingSession", "StateArrays", "settings_doc"]


@runtime_checkable
class EditingSession(Protocol):
    """One editing session: a surfel model, its zero / one regions, deformation steps and collision detection.

    Attributes:
        name: the session's name.
        version: the session version (bumped by every change of the model or the regions).

    The methods returning ``object`` return something informative in each implementation (the
    remote one its ``proto.SessionInfo``); code written against this contract must not use it.
    """

    name: str
    version: int

    def load_points(self, positions: ArrayLike, normals: ArrayLike, radii: Optional[ArrayLike] = None) -> object:
        """Replaces the model: positions (P, 3), normals (P, 3) non-zero, radii (P,) > 0 or None
        (estimated from the spacing). Ids become 0..P-1 in row order. InvalidArgumentError on bad input."""
        ...

    def set_regions(self, zero: Optional[ArrayLike] = None, one: Optional[ArrayLike] = None) -> object:
        """Sets the zero region (never moves) and the one region (moves fully) by (K,) integer ids;
        both non-empty and disjoint (ConflictError), every id known (NotFoundError)."""
        ...

    def deform(self, translation: Vec3Like = (0.0, 0.0, 0.0), axis: Vec3Like = (0.0, 0.0, 1.0),
               angle: float = 0.0, center: Optional[Vec3Like] = None, blend: str = "smooth") -> StepResult:
        """One deformation step: translation (3,) model units, rotation ``angle`` radians about ``axis``
        (3,) through ``center`` (3,) (None: the one region's centroid), blend ``"smooth"`` |
        ``"quadratic"`` | ``"linear"``; then resampling and collision detection as configured."""
        ...

    def configure(self, **settings: SettingValue) -> object:
        """Changes settings by name, all or none (InvalidArgumentError naming the setting in ``.field``)."""
        ...

    def settings(self) -> Dict[str, SettingValue]:
        """Every setting with its current value (numbers may come back as float)."""
        ...

    def remove(self, ids: ArrayLike) -> object:
        """Removes surfels by (K,) id; the other ids stay (NotFoundError, ConflictError: nothing removed)."""
        ...

    def undo(self) -> int:
        """Undoes this client's own last change (in-process: the session's last change); returns the new
        version. The surfels it touched are then bit for bit as before it (alone in the session: the whole
        state). ConflictError when there is nothing to undo or another client's later change touched
        them."""
        ...

    def redo(self) -> int:
        """Redoes this client's last undone change; returns the new version. ConflictError when there is
        none (a change of the client after an undo drops what it could redo)."""
        ...

    def release(self) -> bool:
        """Frees this client's tool: its regions, detector and lock (one history entry, a new version);
        False, and no change, when it has no regions."""
        ...

    def history(self) -> List[HistoryEntry]:
        """The session's history, oldest first (in the order first applied; undone entries flagged)."""
        ...

    def merge(self, crease: bool = True) -> MergeResult:
        """Merges the deformed region with the zero region now (docs/algorithms.md §7 d): removes the
        surfels that collided in the last step and the zero surfels inside the deformed region;
        ``crease``: moves the feature surfels onto the intersection and clips them (``State.clips``).
        One history entry (undo restores everything). Nothing colliding: an empty result, no change.
        ConflictError without regions (nothing changes). The setting ``response="merge"`` does this
        after every colliding step (``StepResult.response == "merged"``)."""
        ...

    def intersection_curves(self, refine_angle: float = 0.5) -> List[Curve]:
        """The intersection curves of the last merge with a crease, refined where an edge bends more
        than ``refine_angle`` radians (> 0; InvalidArgumentError otherwise); ConflictError before one."""
        ...

    def blend(self, iterations: int = 50, range_factor: float = 4.0, dt: float = 0.1, repulsion: str = "weight",
              weight: str = "compact", only_grow: bool = False, adaptive: bool = False,
              neighbourhood: str = "cached", features: Optional[ArrayLike] = None,
              projection: str = "mls") -> BlendResult:
        """Blend tool (thesis §12.3, docs/particles.md): the surfels within ``range_factor`` x mean radius of
        the feature surfels (``features`` ids, or those of the last merge / boolean) become oriented particles
        (the crease undone there), run ``iterations`` steps of ``dt`` and become surfels again. ``repulsion``:
        none | spring | gaussian | weight; ``weight``: compact | gaussian; ``neighbourhood``: cached | grid |
        kdtree; ``only_grow``: move along +n only; ``adaptive``: split / kill by neighbour count;
        ``projection``: mls (at the end, onto the moving-least-squares surface of the particles and the rigid
        surfels around them) | tangent (no final projection). Calling it again continues. One history entry. InvalidArgumentError / NotFoundError naming the argument,
        ConflictError before any merge or boolean (nothing changes)."""
        ...

    def boolean(self, op: str, positions: ArrayLike, normals: ArrayLike,
                radii: Optional[ArrayLike] = None) -> MergeResult:
        """Boolean ``op`` (union | intersection | difference) of the model (A) with the closed model B
        (positions / normals (Q, 3), radii (Q,) or None to estimate) (thesis §12.4.1): ``removed`` A's dropped
        ids, ``inserted`` B's kept surfels' new ids (normals flipped for difference), ``features`` for blend().
        The regions are cleared. One history entry; ConflictError when the result would be empty."""
        ...

    def fill_holes(self, max_diameter: float, iterations: int = 10,
                   boundary: Optional[ArrayLike] = None, projection: str = "mls") -> FillResult:
        """Fills every hole (a loop of boundary surfels, detected or the ``boundary`` ids) no wider than
        ``max_diameter`` (model units) with surfels on the surface around it (thesis §12.4.2); wider loops
        (a scan's border) are left alone. ``projection``: mls (the filling ends on the moving-least-squares
        surface of the surfels around the hole and itself) | tangent (it stays on the quadric fitted around
        the hole). One history entry when it inserted surfels."""
        ...

    def report(self) -> Dict[str, Any]:
        """What the session holds: ``surfels``, ``structures`` {name: bytes}, ``total_bytes``, ``bytes_per_surfel``."""
        ...

    def state(self) -> State:
        """The whole model at the current version, ids ascending (arrays read-only)."""
        ...

    def changes_since(self, version: int) -> Changes:
        """Surfels changed or inserted since ``version`` and ids removed (``full``: the whole model)."""
        ...

    def ids(self) -> np.ndarray:
        """(P,) uint64 ids, ascending."""
        ...

    def positions(self) -> np.ndarray:
        """(P, 3) float64, model units, in id order."""
        ...

    def normals(self) -> np.ndarray:
        """(P, 3) float64 unit normals, in id order."""
        ...

    def radii(self) -> np.ndarray:
        """(P,) float64, model units, in id order."""
        ...

    def close(self) -> None:
        """Ends this use of the session (idempotent)."""
        ...


def settings_doc() -> str:
    """Every session setting, one line each (name: meaning; accepted values, default), from the settings
    table the compiled core exposes (``surfeledit.core.setting_specs()``); empty without the module."""
    try:
        from . import core
    except ImportError:
        return ""
    lines = ["", "        Settings:"]
    for spec in core.setting_specs():
        lines.append(f"            ``{spec['name']}``: {spec['doc']}; {spec['expects']}, default {spec['default']!r}")
    return "\n".join(lines) + "\n"


class StateArrays:
    """The per-array accessors of :class:`EditingSession`, written once on top of ``state()``
    (a base of both sessions)."""

    def state(self) -> State:
        raise NotImplementedError

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
