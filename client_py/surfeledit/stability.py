"""The stability matrix (issue 13 §3): every algorithm under extreme conditions, one table.

Rows: the detectors with every inside mode, the hierarchies, simplification, resampling and the
responses (:data:`ALGORITHMS`). Columns: conditions (:data:`CONDITIONS`). Every cell runs the concave
scene (:func:`surfeledit.scenes.concave`, small scale, ``STEPS`` steps, in-process) under the condition
and compares it with the reference run (the untouched scene):

- ``t1e3`` ... ``t1e8``: the scene and the motion translated by 1e3 / 1e6 / 1e8 on every axis;
  ``s1e-6`` ... ``s1e6``: scaled by that factor (model units and spacing alike);
  ``f32``: positions, normals and radii rounded to float32 before loading.
  Cell = max position deviation from the reference (transformed back) in spacings, and the colliding
  sets' mismatch (ids in one and not the other, summed over steps, over the reference's total).
  Pass: deviation <= ``POS_TOL`` spacings (``F32_TOL`` for f32) and mismatch <= ``SET_TOL``.
- ``tiny``: after the reference run, 10 steps of 1e-12 x model size; pass: no colliding set changes
  (compared with the first of them).
- ``huge``: one step of 10 x model size; pass: a typed error, or finite positions and a colliding
  set that agrees with the exact truth (the scene's signed distance) within ``SET_TOL`` (with ``swept``
  only misses count: surfels carried through the slab are rightly reported too).
- ``degen``: degenerate sets (duplicate surfels, a one-surfel zero region, radii near 0 and near the
  model size, an open zero region): pass: each either runs with finite results or raises a typed error.
- ``long``: ``long_steps`` steps back and forth (+t, -t) into and out of contact; pass: positions
  return to the start within ``DRIFT_TOL`` spacings, normals unit within 1e-9, and the colliding set
  at every step equals the one of the first two steps (the same pose, the same answer). Rows with a
  response go back and forth out of contact (a response changes the motion it is given).

Command line::

    python -m surfeledit.stability [--long-steps 100000] [--rows robust/winding,...] [--columns t1e6,...]

prints the table (cells ``value PASS|FAIL``) and exits 1 when a cell fails.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

from . import scenario as S
from . import scenes as _scenes
from .errors import SurfelEditError
from .local import LocalSession

STEPS = 12          # steps of the concave motion (115 degrees in total)
SCALE = 0.05        # surfel count multiplier of the concave scene (~6k surfels)
POS_TOL = 1e-3      # spacings: translated / scaled runs
F32_TOL = 1e-3      # spacings: float32 input (rounding of ~1e-7 of the model size)
SET_TOL = 0.01      # fraction of the reference's colliding ids that may differ
DRIFT_TOL = 1e-6    # spacings: long back-and-forth sessions

#: Row label -> session settings.
ALGORITHMS: Dict[str, Dict[str, Any]] = {
    "simple": dict(algorithm="simple"),
    "improved": dict(algorithm="improved"),
    "temporal/nearest": dict(algorithm="temporal"),
    "temporal/winding": dict(algorithm="temporal", inside="winding"),
    "temporal/vote": dict(algorithm="temporal", inside="vote"),
    "robust/nearest": dict(algorithm="robust"),
    "robust/winding": dict(algorithm="robust", inside="winding"),
    "robust/vote": dict(algorithm="robust", inside="vote"),
    "robust/winding+swept": dict(algorithm="robust", inside="winding", swept=True),
    "robust+aabb": dict(algorithm="robust", zero_hierarchy="aabb", deformable_hierarchy="aabb"),
    "robust+obb": dict(algorithm="robust", zero_hierarchy="obb"),
    "robust+sphere": dict(algorithm="robust", zero_hierarchy="sphere"),
    "temporal+simplify": dict(algorithm="temporal", simplify="region_growing"),
    "robust+resample": dict(algorithm="robust", resample=True),
    "robust+cancel": dict(algorithm="robust", response="cancel"),
    "robust+backoff": dict(algorithm="robust", response="backoff"),
    "robust+merge": dict(algorithm="robust", response="merge"),
}

CONDITIONS = ("t1e3", "t1e6", "t1e8", "s1e-6", "s1e-4", "s1e4", "s1e6", "f32", "tiny", "huge", "degen", "long")


# -- runs ---------------------------------------------------------------------------------------------
class Run:
    """One session over the (transformed) scene: the states and colliding sets after each step."""

    def __init__(self, scene: _scenes.SceneSetup, settings: Dict[str, Any], offset: float = 0.0, scale: float = 1.0,
                 dtype: Any = np.float64) -> None:
        self.scene, self.offset, self.scale = scene, offset, scale
        self.session = LocalSession("stability", threads=1)
        pos = (scene.positions * scale + offset).astype(dtype)
        self.session.load_points(pos, scene.normals.astype(dtype), (scene.radii * scale).astype(dtype))
        self.session.set_regions(zero=scene.zero, one=scene.one)
        self.session.configure(threads=1, **settings)
        self.colliding: List[np.ndarray] = []

    def step(self, translation: Sequence[float] = (0.0, 0.0, 0.0), angle: float = 0.0) -> np.ndarray:
        m = self.scene.motion
        center = np.asarray(m.center if m.center is not None else (0.0, 0.0, 0.0)) * self.scale + self.offset
        r = self.session.deform(translation=tuple(float(x) * self.scale for x in translation), axis=m.axis,
                                angle=angle, center=tuple(float(x) for x in center), blend=m.blend)
        c = np.sort(np.asarray(r.colliding, np.int64))
        self.colliding.append(c)
        return c

    def motion(self, steps: int = STEPS) -> "Run":
        for _ in range(steps):
            self.step(angle=self.scene.motion.angle / steps)
        return self

    def positions(self) -> Tuple[np.ndarray, np.ndarray]:
        """(ids (P,) ascending, positions (P, 3) back in the reference frame)."""
        st = self.session.state()
        return st.ids.astype(np.int64), (st.positions - self.offset) / self.scale

    def close(self) -> None:
        self.session.close()


def _deviation(a: Tuple[np.ndarray, np.ndarray], b: Tuple[np.ndarray, np.ndarray]) -> float:
    """Max |position difference| over the ids both states have; inf when the id sets differ."""
    if len(a[0]) != len(b[0]) or not np.array_equal(a[0], b[0]):
        return math.inf
    return float(np.abs(a[1] - b[1]).max())


def _mismatch(a: List[np.ndarray], b: List[np.ndarray]) -> float:
    total = max(1, sum(len(x) for x in a))
    return sum(len(np.setxor1d(x, y)) for x, y in zip(a, b)) / total


# -- conditions ---------------------------------------------------------------------------------------
Cell = Tuple[str, bool]


def _transformed(scene, settings, ref: Run, offset: float = 0.0, scale: float = 1.0, dtype: Any = np.float64,
                 tol: float = POS_TOL) -> Cell:
    run = Run(scene, settings, offset, scale, dtype).motion()
    try:
        dev = _deviation(run.positions(), ref.positions()) / scene.spacing
        mis = _mismatch(ref.colliding, run.colliding)
        return f"{dev:.1e}/{mis:.3f}", bool(dev <= tol and mis <= SET_TOL)
    finally:
        run.close()


def _tiny(scene, settings, ref: Run) -> Cell:
    size = float(np.ptp(scene.positions, axis=0).max())
    # Compared with the first tiny step, not with the last motion step: a response (cancel, merge) may
    # have undone or rewritten that step after reporting it.
    before = ref.step(translation=(1e-12 * size, 0.0, 0.0))
    changed = 0
    for k in range(1, 10):
        c = ref.step(translation=(1e-12 * size * (-1) ** k, 0.0, 0.0))
        changed += len(np.setxor1d(c, before))
    return f"{changed} changed", changed == 0


def _huge(scene, settings, ref: Run) -> Cell:
    size = float(np.ptp(scene.positions, axis=0).max())
    run = Run(scene, settings)
    try:
        try:
            c = run.step(translation=(0.0, 0.0, -10.0 * size))
        except SurfelEditError as e:
            return type(e).__name__, True
        st = run.session.state()
        if not np.isfinite(st.positions).all():
            return "NaN", False
        ids, truly = S.Truth(scene).evaluate(st)
        _, fp, fn, _, _ = S.precision_recall(c.astype(np.uint64), ids, truly)
        # With swept, surfels the huge step carried through the slab are rightly reported as well.
        bad = (fn if settings.get("swept") else fp + fn) / max(1, int(truly.sum()))
        return f"{bad:.3f} wrong", bad <= SET_TOL or (fp + fn) <= 2
    finally:
        run.close()


def _degenerate_cases(scene) -> List[Tuple[str, _scenes.SceneSetup]]:
    rep = lambda **kw: _scenes.SceneSetup(**{**scene.__dict__, **kw})  # noqa: E731
    dup = np.concatenate([np.arange(scene.size), scene.zero[:50]])
    size = float(np.ptp(scene.positions, axis=0).max())
    half = scene.zero[scene.positions[scene.zero, 0] < 0.0]
    rest = np.setdiff1d(np.arange(scene.size), scene.zero[scene.positions[scene.zero, 0] >= 0.0])
    return [
        ("duplicates", rep(positions=scene.positions[dup], normals=scene.normals[dup], radii=scene.radii[dup],
                           zero=np.concatenate([scene.zero, np.arange(scene.size, len(dup))]))),
        ("one zero surfel", rep(zero=scene.zero[:1])),
        ("radius ~0", rep(radii=np.full(scene.size, 1e-12 * size))),
        ("radius ~size", rep(radii=np.full(scene.size, size))),
        ("open zero", rep(positions=scene.positions[rest], normals=scene.normals[rest], radii=scene.radii[rest],
                          zero=np.flatnonzero(np.isin(rest, half)), one=np.flatnonzero(np.isin(rest, scene.one)))),
    ]


def _degen(scene, settings, ref: Run) -> Cell:
    bad: List[str] = []
    for name, case in _degenerate_cases(scene):
        try:
            run = Run(case, settings)
            try:
                run.motion(3)
                if not np.isfinite(run.session.state().positions).all():
                    bad.append(name)
            finally:
                run.close()
        except SurfelEditError:
            pass  # a typed refusal is a correct answer
        except Exception as e:  # noqa: BLE001  (anything untyped is a failure of the cell)
            bad.append(f"{name}: {type(e).__name__}")
    return ("ok" if not bad else ",".join(bad)), not bad


def _long(scene, settings, ref: Run, steps: int) -> Cell:
    # At the end of the motion (in contact), so that the back-and-forth enters and leaves it; a response
    # changes the motion it is given
    # (cancel, back off, merge), so those rows go back and forth at the start pose, out of contact.
    responds = settings.get("response", "none") != "none"
    run = Run(scene, settings).motion(0 if responds else STEPS - 1)
    try:
        start = run.positions()
        t = np.array([0.0, 0.0, -0.5 * scene.spacing])
        first: List[np.ndarray] = []
        mismatches = 0
        for k in range(steps):
            c = run.step(translation=t if k % 2 == 0 else -t)
            if k < 2:
                first.append(c)
            else:
                mismatches += int(len(np.setxor1d(c, first[k % 2])) > 0)
        st = run.session.state()
        drift = _deviation(run.positions(), start) / scene.spacing
        unit = float(np.abs(np.linalg.norm(st.normals, axis=1) - 1.0).max())
        ok = drift <= DRIFT_TOL and unit <= 1e-9 and mismatches == 0
        return f"{drift:.1e}/{mismatches}", ok
    finally:
        run.close()


# -- the matrix ---------------------------------------------------------------------------------------
def cell(label: str, condition: str, long_steps: int = 2000, scene: Optional[_scenes.SceneSetup] = None) -> Cell:
    """Runs one cell: (text, passed)."""
    scene = scene if scene is not None else _scenes.concave(scale=SCALE, steps=STEPS)
    settings = ALGORITHMS[label]
    ref = Run(scene, settings).motion()
    try:
        if condition in ("t1e3", "t1e6", "t1e8"):
            return _transformed(scene, settings, ref, offset=float(condition[1:]))
        if condition in ("s1e-6", "s1e-4", "s1e4", "s1e6"):
            return _transformed(scene, settings, ref, scale=float(condition[1:]))
        if condition == "f32":
            return _transformed(scene, settings, ref, dtype=np.float32, tol=F32_TOL)
        table: Dict[str, Callable[..., Cell]] = {"tiny": _tiny, "huge": _huge, "degen": _degen}
        if condition == "long":
            return _long(scene, settings, ref, long_steps)
        return table[condition](scene, settings, ref)
    finally:
        ref.close()


def matrix(rows: Sequence[str], columns: Sequence[str], long_steps: int = 2000) -> Dict[Tuple[str, str], Cell]:
    scene = _scenes.concave(scale=SCALE, steps=STEPS)
    return {(r, c): cell(r, c, long_steps, scene) for r in rows for c in columns}


def format_table(result: Dict[Tuple[str, str], Cell], rows: Sequence[str], columns: Sequence[str]) -> str:
    width = max(16, max(len(t) for t, _ in result.values()) + 7)
    lines = ["algorithm".ljust(22) + "".join(c.ljust(width) for c in columns)]
    for r in rows:
        lines.append(r.ljust(22) + "".join(
            f"{result[r, c][0]} {'PASS' if result[r, c][1] else 'FAIL'}".ljust(width) for c in columns))
    return "\n".join(lines)


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="surfeledit-stability", description=__doc__.split("\n\n")[0])
    ap.add_argument("--rows", default=",".join(ALGORITHMS), help="comma-separated row labels")
    ap.add_argument("--columns", default=",".join(CONDITIONS), help="comma-separated conditions")
    ap.add_argument("--long-steps", type=int, default=100000, help="steps of the long session")
    args = ap.parse_args(argv)
    rows = [r for r in args.rows.split(",") if r]
    columns = [c for c in args.columns.split(",") if c]
    for r in rows:
        if r not in ALGORITHMS:
            ap.error(f"unknown row {r!r}")
    for c in columns:
        if c not in CONDITIONS:
            ap.error(f"unknown condition {c!r}")
    t0 = time.perf_counter()
    scene = _scenes.concave(scale=SCALE, steps=STEPS)
    result: Dict[Tuple[str, str], Cell] = {}
    for r in rows:  # one row at a time, so that a long run shows its progress
        t1 = time.perf_counter()
        result.update({(r, c): cell(r, c, args.long_steps, scene) for c in columns})
        print(format_table(result, [r], columns).splitlines()[1] + f"  ({time.perf_counter() - t1:.1f} s)",
              flush=True)
    print(format_table(result, rows, columns))
    print(f"tolerances: positions {POS_TOL:g} spacings (f32 {F32_TOL:g}), colliding sets {SET_TOL:g} of the "
          f"reference, long-session drift {DRIFT_TOL:g} spacings; {time.perf_counter() - t0:.1f} s")
    return 0 if all(ok for _, ok in result.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
