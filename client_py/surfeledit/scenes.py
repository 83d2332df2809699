"""Generated test scenes for the scenario runner (:mod:`surfeledit.scenario`), each with exact truth.

A :class:`SceneSetup` is a surfel model (rows = the ids the model gets when loaded: 0..P-1), its
regions (zero = rigid, one = fully displaced, the rest blends), the motion that drives it (a total
translation and/or rotation, split into static steps by the scenario) and the ground truth: the
signed distance of the rigid (zero) solid, ``truth_sdf(points) < 0`` inside. A deformable surfel
truly collides iff its *current* position is inside that solid (docs/algorithms.md §4.4, "Ground
truth for tests"). ``seam`` holds the zero surfels next to the deformable part (empty when the deformable
part is a separate body); the metrics leave out deformable surfels within two sample spacings of
them, where truth is ambiguous.

Scenes (all dimensions in model units; ``scale`` multiplies the surfel count, spacing / sqrt(scale)):

- :func:`piercing` — the analogue of the thesis's "ball joint piercing santa" (§10.2.1): a rigid plate
  (about 150k surfels) and a separate ball (about 60k, all of it the one region) pushed through it
  in 50 steps; collisions rise to about 6.5k and fall back to none.
- :func:`cup` — a cup whose handle (far end = one region, the rest of the handle blends) is rotated
  about its upper root into the cup wall; the zero region and the truth are the cup body alone.
- :func:`concave` — a capsule standing on a slab, bent over (rotation about its root) until its end
  sweeps back into the slab: the concave collision of the thesis's Fig. 6.4.
- :func:`thinwall` — a ball pushed through a wall 2.5 spacings thick in few steps (tunnelling).
- :func:`bunny` — the watertight Stanford bunny with one ear pushed into its head; truth by a
  generalized winding number of the mesh (needs the mesh file and ``libigl``; tests only).
"""

from __future__ import annotations

import dataclasses
import math
import os
from pathlib import Path
from typing import Callable, Optional, Tuple

import numpy as np
from scipy.spatial import cKDTree

from . import core
from ._protocol import REPO_ROOT

SdfFn = Callable[[np.ndarray], np.ndarray]


def models_dir() -> Path:
    """Where the shared test models live: env ``SURFELEDIT_MODELS`` if set, else
    ``<repo>/../shared/data/models`` next to the source checkout this package is in (it may be absent:
    callers skip with a reason)."""
    env = os.environ.get("SURFELEDIT_MODELS")
    return Path(env) if env else REPO_ROOT.parent / "shared" / "data" / "models"


#: The shared test models' directory at import (the bunny scene needs ``bunny_watertight.obj`` there).
MODELS_DIR = models_dir()


@dataclasses.dataclass(frozen=True)
class Motion:
    """The whole motion of a scenario, split into ``steps`` equal static steps by the runner.

    translation: (3,) total translation of the one region, model units.
    axis: (3,) rotation axis (any length > 0 when ``angle != 0``).
    angle: total rotation angle of the one region, radians.
    center: (3,) rotation centre, fixed for every step (None: the server's default, the one
        region's centroid at each step — only sensible without rotation).
    blend: ``"smooth"`` | ``"quadratic"`` | ``"linear"``.
    """

    translation: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis: Tuple[float, float, float] = (0.0, 0.0, 1.0)
    angle: float = 0.0
    center: Optional[Tuple[float, float, float]] = None
    blend: str = "smooth"


@dataclasses.dataclass(frozen=True)
class SceneSetup:
    """A generated start state with its truth (see the module docstring).

    positions, normals: (P, 3) float64 (normals unit, outward); radii: (P,) float64, model units.
    zero, one: (K,) int64 row indices (= ids after loading) of the two regions, disjoint.
    spacing: sample spacing h, model units (the seam band is 2 h).
    truth_sdf: (Q, 3) -> (Q,) signed distance of the rigid solid, < 0 inside.
    seam: (S, 3) positions of the zero surfels adjacent to the deformable part (S may be 0).
    motion: the default motion; steps: the default number of steps.
    """

    name: str
    positions: np.ndarray
    normals: np.ndarray
    radii: np.ndarray
    zero: np.ndarray
    one: np.ndarray
    spacing: float
    truth_sdf: SdfFn
    seam: np.ndarray
    motion: Motion
    steps: int
    description: str = ""

    @property
    def size(self) -> int:
        return int(self.positions.shape[0])

    @property
    def deformable(self) -> np.ndarray:
        """(D,) int64 rows not in the zero region, ascending."""
        mask = np.ones(self.size, bool)
        mask[self.zero] = False
        return np.flatnonzero(mask).astype(np.int64)


def _spacing(base: float, scale: float) -> float:
    if not (scale > 0 and math.isfinite(scale)):
        raise ValueError(f"scale must be finite and > 0, got {scale}")
    return base / math.sqrt(scale)


def rotation_matrix(axis: Tuple[float, float, float], angle: float) -> np.ndarray:
    """(3, 3) rotation by ``angle`` radians about ``axis`` (right-handed, Rodrigues)."""
    a = np.asarray(axis, np.float64)
    a = a / np.linalg.norm(a)
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)


def seam_points(positions: np.ndarray, zero: np.ndarray, spacing: float) -> np.ndarray:
    """Zero surfels whose nearest deformable surfel (at rest) is closer than 1.5 spacings, (S, 3)."""
    mask = np.zeros(positions.shape[0], bool)
    mask[zero] = True
    if mask.all():
        return np.zeros((0, 3))
    # The bound prunes each search at 1.5 spacings (d = inf beyond it): without it a zero surfel far from every
    # deformable one searched much of the tree (45 s for the 1M piercing scene, 0.16 s with it).
    reach = 1.5 * spacing
    d, _ = cKDTree(positions[~mask]).query(positions[mask], k=1, distance_upper_bound=reach)
    return positions[mask][d < reach]


def _setup(name: str, s: "core.SampledSurfels", zero: np.ndarray, one: np.ndarray, spacing: float,
           truth: SdfFn, motion: Motion, steps: int, description: str) -> SceneSetup:
    pos = np.ascontiguousarray(s.positions, dtype=np.float64)
    zero = np.asarray(zero, np.int64)
    one = np.asarray(one, np.int64)
    return SceneSetup(name=name, positions=pos, normals=np.ascontiguousarray(s.normals, dtype=np.float64),
                      radii=np.ascontiguousarray(s.radii, dtype=np.float64), zero=zero, one=one,
                      spacing=spacing, truth_sdf=truth, seam=seam_points(pos, zero, spacing), motion=motion,
                      steps=steps, description=description)


# -- 1. piercing -------------------------------------------------------------------------------------
def piercing(scale: float = 1.0, seed: int = 1, steps: int = 50) -> SceneSetup:
    """A rigid plate and a ball pushed straight down through it (see the module docstring).

    Full size (scale 1): spacing 0.01; plate 2.59 x 2.59 x 0.15 (~150k surfels), ball radius 0.691
    (~60k surfels) starting two spacings above the plate and ending two spacings below it.
    """
    return _ball_through_plate("piercing", _spacing(0.01, scale), 1.296, 0.075, 0.691, seed, steps,
                               "ball (one region) pushed down through a rigid plate")


def _ball_through_plate(name: str, h: float, half_w: float, half_t: float, r: float, seed: int, steps: int,
                        description: str) -> SceneSetup:
    """A square plate (half width ``half_w``, half thickness ``half_t``) about the origin, the zero
    region, and a ball of radius ``r`` (the one region) moved from two spacings above it to two below."""
    plate = core.make_box([half_w, half_w, half_t])
    z0 = half_t + r + 2.0 * h
    scene = core.Scene()
    scene.add(plate)
    # A generic orientation: the sphere is sampled in rings of constant latitude, and a ring parallel
    # to the plate would cross it all at once (every step hitting the same offset from the face).
    scene.add(core.make_sphere(r, center=[0.0, 0.0, z0], rotation=rotation_matrix((1.0, 2.0, 3.0), 0.7)))
    s = scene.sample(spacing=h, seed=seed)
    part = np.asarray(s.part)
    return _setup(name, s, np.flatnonzero(part == 0), np.flatnonzero(part == 1), h, plate.sdf,
                  Motion(translation=(0.0, 0.0, -2.0 * z0)), steps, description)


# -- 2. cup ------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class CupShape:
    """The cup of ``core.make_cup`` at the identity pose, with its body and handle apart.

    Body: the solid of revolution of the U-shaped profile (outer radius R, height H, wall w, base at
    z = 0, open top); handle: points within ``hr`` of the half circle of radius ``hR`` about
    (R, 0, H/2) in the x-z plane on the +x side (a half tube with ball ends in the wall).
    """

    R: float = 0.5
    H: float = 1.0
    w: float = 0.08
    hR: float = 0.3
    hr: float = 0.07

    def body_sdf(self, q: np.ndarray) -> np.ndarray:
        """(Q,) exact signed distance to the body (distance to the revolved profile's 5 edges)."""
        q = np.atleast_2d(np.asarray(q, np.float64))
        rho = np.hypot(q[:, 0], q[:, 1])
        z = q[:, 2]
        R, H, w = self.R, self.H, self.w
        ri = R - w
        edges = [((0.0, 0.0), (R, 0.0)), ((R, 0.0), (R, H)), ((R, H), (ri, H)), ((ri, H), (ri, w)),
                 ((ri, w), (0.0, w))]
        d = np.full(rho.shape, np.inf)
        for (ax, az), (bx, bz) in edges:
            ex, ez = bx - ax, bz - az
            t = np.clip(((rho - ax) * ex + (z - az) * ez) / (ex * ex + ez * ez), 0.0, 1.0)
            d = np.minimum(d, np.hypot(rho - (ax + t * ex), z - (az + t * ez)))
        inside = (z > 0) & (z < H) & (rho < R) & ~((rho < ri) & (z > w))
        return np.where(inside, -d, d)

    def handle_sdf(self, q: np.ndarray) -> np.ndarray:
        """(Q,) exact signed distance to the handle (half tube with ball ends)."""
        q = np.atleast_2d(np.asarray(q, np.float64))
        a, b, c = q[:, 0] - self.R, q[:, 2] - 0.5 * self.H, q[:, 1]
        on_arc = np.hypot(np.hypot(a, b) - self.hR, c)
        to_end = np.sqrt(a * a + (b - np.copysign(self.hR, b)) ** 2 + c * c)
        return np.where(a >= 0.0, on_arc, to_end) - self.hr

    def solid(self) -> "core.Solid":
        return core.make_cup(radius=self.R, height=self.H, wall=self.w, handle_major=self.hR,
                             handle_minor=self.hr)


def cup(scale: float = 1.0, seed: int = 1, steps: int = 40, angle_deg: float = 100.0) -> SceneSetup:
    """A cup whose handle is rotated into the cup wall (see the module docstring).

    Full size: spacing 0.008 (~115k surfels, ~6.4k on the handle). The handle's far end (the arc
    within 35 degrees of its apex) is the one region; the motion rotates it about the y axis through
    the handle's upper root by ``angle_deg`` in total, which swings the far end through the wall into
    the cup.
    """
    h = _spacing(0.008, scale)
    shape = CupShape()
    s = shape.solid().sample(spacing=h, seed=seed)
    p = np.asarray(s.positions)
    on_handle = np.abs(shape.handle_sdf(p)) < np.abs(shape.body_sdf(p))
    a, b = p[:, 0] - shape.R, p[:, 2] - 0.5 * shape.H
    far = on_handle & (a > 0) & (np.abs(np.arctan2(b, a)) < math.radians(35.0))
    center = (shape.R, 0.0, 0.5 * shape.H + shape.hR)
    return _setup("cup", s, np.flatnonzero(~on_handle), np.flatnonzero(far), h, shape.body_sdf,
                  Motion(axis=(0.0, 1.0, 0.0), angle=math.radians(angle_deg), center=center), steps,
                  "cup handle rotated about its upper root into the cup wall")


# -- 3. concave --------------------------------------------------------------------------------------
def concave(scale: float = 1.0, seed: int = 1, steps: int = 40, angle_deg: float = 115.0) -> SceneSetup:
    """A capsule on a slab bent back into the slab (thesis Fig. 6.4; see the module docstring).

    Slab: half extents (1.5, 0.5, 0.3), top face at z = 0 (the zero region and the truth). Capsule:
    radius 0.12, axis from z = 0 to z = 1.2 (its lower cap sunk into the slab); its top (z > 1.0) is
    the one region, the rest blends. The motion rotates about +y through the capsule's root by
    ``angle_deg`` in total, so the end comes down into the slab's top face.
    Full size: spacing 0.01 (~108k slab + ~11k capsule surfels).
    """
    h = _spacing(0.01, scale)
    slab = core.make_box([1.5, 0.5, 0.3], center=[0.0, 0.0, -0.3])
    scene = core.Scene()
    scene.add(slab)
    scene.add(core.make_capsule(0.12, 0.6, center=[0.0, 0.0, 0.6]))
    s = scene.sample(spacing=h, seed=seed)
    part = np.asarray(s.part)
    z = np.asarray(s.positions)[:, 2]
    return _setup("concave", s, np.flatnonzero(part == 0), np.flatnonzero((part == 1) & (z > 1.0)), h, slab.sdf,
                  Motion(axis=(0.0, 1.0, 0.0), angle=math.radians(angle_deg), center=(0.0, 0.0, 0.0)), steps,
                  "capsule on a slab bent over until its end sweeps back into the slab")


# -- 4. bunny ----------------------------------------------------------------------------------------
BUNNY_FILE = MODELS_DIR / "bunny_watertight.obj"


def bunny(path: Optional[Path] = None, steps: int = 30, depth: float = 0.22) -> SceneSetup:
    """The watertight bunny (one surfel per mesh vertex) with its left ear pushed into its head.

    The ear is the part of the mesh above a cutting plane across its base (found from the model:
    the highest vertex's side of the bunny); its upper 45 % is the one region, the rest of the ear
    blends. The motion translates the ear tip down towards the head's centre by ``depth`` times the
    bunny's height. Truth: inside the watertight mesh (generalized winding number > 0.5, libigl)
    and not inside the ear's own rest volume (the rigid solid is the bunny minus the ear).

    Raises FileNotFoundError when the mesh is absent and ImportError without ``libigl``.
    """
    import igl  # noqa: F401  (tests-only dependency; fail early with a clear message)

    path = Path(path) if path is not None else BUNNY_FILE
    if not path.is_file():
        raise FileNotFoundError(f"bunny mesh not found: {path}")
    d = core.load_file(str(path))
    pos = np.ascontiguousarray(d["positions"], np.float64)
    V, F = igl.read_triangle_mesh(str(path))
    V = np.ascontiguousarray(V, np.float64)
    F = np.ascontiguousarray(F, np.int64)
    lo, hi = pos.min(0), pos.max(0)
    height = float(hi[2] - lo[2])
    # The ear: the highest vertex's neighbourhood above a plane 28 % of the height below it.
    top = pos[np.argmax(pos[:, 2])]
    cut_z = top[2] - 0.28 * height
    ear_ball = 0.3 * height
    in_ear_region = (pos[:, 2] > cut_z) & (np.linalg.norm(pos[:, :2] - top[:2], axis=1) < ear_ball)
    ear = np.flatnonzero(in_ear_region)
    tip = ear[pos[ear, 2] > cut_z + 0.55 * (top[2] - cut_z)]
    zero = np.flatnonzero(~in_ear_region)
    centroid = pos.mean(0)
    direction = centroid - top
    direction /= np.linalg.norm(direction)
    translation = tuple(float(x) for x in direction * depth * height)

    def truth(q: np.ndarray) -> np.ndarray:
        q = np.ascontiguousarray(np.atleast_2d(q), np.float64)
        w = igl.fast_winding_number(V, F, q)
        in_mesh = w > 0.5
        in_ear = (q[:, 2] > cut_z) & (np.linalg.norm(q[:, :2] - top[:2], axis=1) < ear_ball)
        # Not a distance: -1 inside the rigid solid, +1 outside (the runner uses the sign only).
        return np.where(in_mesh & ~in_ear, -1.0, 1.0)

    spacing = float(np.median(d["radii"]))

    class _S:  # the shape _setup expects
        positions = pos
        normals = d["normals"]
        radii = d["radii"]

    return _setup("bunny", _S, zero, tip, spacing, truth, Motion(translation=translation), steps,  # type: ignore[arg-type]
                  "bunny with one ear pushed into its head")


# -- 5. thin wall -----------------------------------------------------------------------------------
def thinwall(scale: float = 1.0, seed: int = 1, steps: int = 1, thickness: float = 2.5) -> SceneSetup:
    """A ball pushed straight through a thin rigid wall (no tunnelling, docs/algorithms.md §4.7).

    Wall: half extents (0.8, 0.8, thickness h / 2) about the origin (``thickness`` in spacings h);
    ball: radius 0.25, starting two spacings above the wall and ending two spacings below it, so
    every ball surfel passes through the wall during the motion. Full size: spacing 0.01 (~50k wall
    + ~8k ball surfels). With ``steps`` = 1 no surfel is ever inside the wall after a step.
    """
    h = _spacing(0.01, scale)
    return _ball_through_plate("thinwall", h, 0.8, 0.5 * thickness * h, 0.25, seed, steps,
                               "ball pushed through a thin rigid wall")


SCENES = {"piercing": piercing, "cup": cup, "concave": concave, "bunny": bunny, "thinwall": thinwall}
