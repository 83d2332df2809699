"""Scenario runner: the thesis's collision test application (§10.2.1), scripted.

A :class:`Scenario` is a generated scene (:mod:`surfeledit.scenes`: surfels, zero / one regions and
the rigid solid's exact signed distance) plus a motion (total translation and/or rotation) split
into ``steps`` equal static steps. :func:`run` replays it from the same stored start state with any
collision algorithm and settings, in-process (:class:`LocalBackend`, a :class:`~surfeledit.local.LocalSession`)
or on a server over DDS (:class:`RemoteBackend`, a :class:`~surfeledit.Session`) — one code path
through :class:`~surfeledit.session_api.EditingSession` — and returns one :class:`StepRecord` per step.

Accuracy per step (docs/algorithms.md §4.4, "Ground truth for tests"): a deformable surfel (any surfel
not in the zero region, inserted ones included) truly collides iff its *current* position is inside
the rigid solid, ``truth_sdf(p) < 0``. Deformable surfels within two sample spacings of the
zero/deformable seam are left out (there truth is ambiguous). Over the rest::

    precision = TP / (TP + FP)   (1.0 when nothing is reported: 0/0 = 1)
    recall    = TP / (TP + FN)   (1.0 when nothing truly collides: 0/0 = 1)

Times are milliseconds: ``detect_ms`` is the detector's own time for the step, ``step_ms`` the
whole step as the caller sees it (deformation + resampling + detection; over DDS the round trip).

Command line (also the ``surfeledit-scenario`` script)::

    python -m surfeledit.scenario piercing --algorithms simple,improved,temporal,robust --out DIR \\
        [--remote] [--steps N] [--scale S] [--threads T] [--set name=value ...]

writes ``DIR/<scene>.csv`` (one row per algorithm and step) and ``DIR/<scene>.png`` (per-step time
and colliding count of every algorithm, like the thesis's Figs. 6.9, 6.10 and 10.3).
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import sys
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np
from scipy.spatial import cKDTree

from . import scenes as _scenes
from .scenario_backends import Backend, LocalBackend, ModelState, RemoteBackend, StepOutput
from .scenes import Motion, SceneSetup

ALGORITHMS = ("none", "simple", "improved", "temporal", "robust")


# -- the scenario ------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class Scenario:
    """A scene plus a motion split into ``steps`` static steps (each step = total / steps)."""

    scene: SceneSetup
    steps: int
    motion: Motion

    @property
    def name(self) -> str:
        return self.scene.name

    def step_params(self) -> Dict[str, Any]:
        """Keyword arguments of one ``deform`` call (translation (3,), axis (3,), angle rad, center, blend)."""
        m = self.motion
        out: Dict[str, Any] = dict(translation=tuple(float(x) / self.steps for x in m.translation),
                                   axis=tuple(float(x) for x in m.axis), angle=float(m.angle) / self.steps,
                                   blend=m.blend)
        if m.center is not None:
            out["center"] = tuple(float(x) for x in m.center)
        return out


def make_scenario(name: str, scale: float = 1.0, steps: Optional[int] = None, seed: int = 1,
                  **scene_kwargs: Any) -> Scenario:
    """Builds a named scenario (``piercing``, ``cup``, ``concave``, ``bunny``, ``thinwall``); ``scale`` multiplies
    the surfel count (not for ``bunny``), ``steps`` overrides the scene's default step count."""
    if name not in _scenes.SCENES:
        raise ValueError(f"unknown scene {name!r} (expected one of {', '.join(_scenes.SCENES)})")
    if name == "bunny":
        scene = _scenes.bunny(**scene_kwargs)
    else:
        scene = _scenes.SCENES[name](scale=scale, seed=seed, **scene_kwargs)
    n = int(steps) if steps is not None else scene.steps
    if n < 1:
        raise ValueError(f"steps must be >= 1, got {n}")
    return Scenario(scene=scene, steps=n, motion=scene.motion)


# -- truth and metrics -------------------------------------------------------------------------------
@dataclasses.dataclass
class Truth:
    """Per-step ground truth of one scene: which deformable ids are judged and which truly collide."""

    scene: SceneSetup

    def __post_init__(self) -> None:
        self._zero = set(int(i) for i in self.scene.zero)
        self._seam = cKDTree(self.scene.seam) if len(self.scene.seam) else None

    def evaluate(self, state: ModelState) -> Tuple[np.ndarray, np.ndarray]:
        """(ids (E,) uint64 of the judged deformable surfels, truly_colliding (E,) bool)."""
        zero_ids = np.fromiter(self._zero, np.int64, len(self._zero))
        deformable = ~np.isin(state.ids.astype(np.int64), zero_ids)
        ids, pos = state.ids[deformable], state.positions[deformable]
        if self._seam is not None:
            d, _ = self._seam.query(pos, k=1, distance_upper_bound=2.0 * self.scene.spacing)
            keep = ~np.isfinite(d)  # no seam point within 2 h
            ids, pos = ids[keep], pos[keep]
        return ids, np.asarray(self.scene.truth_sdf(pos)) < 0.0


def precision_recall(reported: np.ndarray, ids: np.ndarray, truly: np.ndarray) -> Tuple[int, int, int, float, float]:
    """(TP, FP, FN, precision, recall) of ``reported`` ids over the judged ``ids`` with truth ``truly``.

    Reported ids outside ``ids`` (zero or seam-band surfels) are ignored; 0/0 counts as 1.0.
    """
    hit = np.isin(ids, np.asarray(reported, np.uint64))
    tp = int(np.count_nonzero(hit & truly))
    fp = int(np.count_nonzero(hit & ~truly))
    fn = int(np.count_nonzero(~hit & truly))
    precision = tp / (tp + fp) if tp + fp else 1.0
    recall = tp / (tp + fn) if tp + fn else 1.0
    return tp, fp, fn, precision, recall


# -- running -----------------------------------------------------------------------------------------
@dataclasses.dataclass
class StepRecord:
    """One step of one run. Times in ms; counts of surfels."""

    algorithm: str
    step: int               # 1-based
    step_ms: float          # the whole step (deform + resample + detect; remote: round trip)
    detect_ms: float        # the detector alone
    preprocess_ms: float    # the detector's last reset (same on every step of a run)
    colliding: int          # reported colliding surfels
    queries: int            # nearest-neighbour queries of the detector
    tested: int             # surfels the detector (re)evaluated
    surfels: int            # model size after the step
    truth: int              # judged surfels truly colliding
    judged: int             # deformable surfels outside the seam band
    tp: int
    fp: int
    fn: int
    precision: float
    recall: float


@dataclasses.dataclass
class RunResult:
    """A run: its records, and per step the reported colliding ids (uint64, ascending)."""

    scenario: str
    algorithm: str
    backend: str
    settings: Dict[str, Any]
    records: List[StepRecord]
    colliding: List[np.ndarray]

    def summary(self) -> Dict[str, float]:
        """median / max of detect_ms and step_ms, peak colliding, min precision and recall."""
        d = np.array([r.detect_ms for r in self.records])
        s = np.array([r.step_ms for r in self.records])
        return dict(median_detect_ms=float(np.median(d)), max_detect_ms=float(d.max()),
                    median_step_ms=float(np.median(s)), max_step_ms=float(s.max()),
                    preprocess_ms=self.records[0].preprocess_ms if self.records else 0.0,
                    peak_colliding=max(r.colliding for r in self.records),
                    peak_truth=max(r.truth for r in self.records),
                    min_precision=min(r.precision for r in self.records),
                    min_recall=min(r.recall for r in self.records),
                    # over the steps with at least 50 true collisions (1.0 when there are none)
                    min_precision_50=min([r.precision for r in self.records if r.truth >= 50], default=1.0),
                    min_recall_50=min([r.recall for r in self.records if r.truth >= 50], default=1.0))


#: Called after each step with (step, backend, output, state); may edit the session (e.g. remove).
StepHook = Callable[[int, Backend, StepOutput, ModelState], None]


def run(scenario: Scenario, algorithm: str = "robust", backend: Optional[Backend] = None,
        settings: Optional[Mapping[str, Any]] = None, removals: Optional[Mapping[int, Sequence[int]]] = None,
        after_step: Optional[StepHook] = None, measure: bool = True) -> RunResult:
    """Runs ``scenario`` with ``algorithm`` from its stored start state.

    Args:
        backend: a :class:`LocalBackend` (default, all threads) or :class:`RemoteBackend`.
        settings: more session settings (``threshold``, ``boundary``, ``boundary_n``, ``boundary_i``,
            ``step_bound``, ``threads``, ``resample``, ``split_threshold``).
        removals: {step k: ids} removes those surfels just before step k (1-based).
        after_step: called after every step (see :data:`StepHook`); the state it gets is fresh.
        measure: compute truth / precision / recall (needs the model state every step).

    Returns a :class:`RunResult`. Raises the backend's typed errors (e.g. InvalidArgumentError for a
    bad setting) before any step is made.
    """
    backend = backend if backend is not None else LocalBackend()
    cfg = dict(settings or {})
    backend.start(scenario.scene)
    backend.configure(algorithm=algorithm, **cfg)
    truth = Truth(scenario.scene) if measure else None
    params = scenario.step_params()
    records: List[StepRecord] = []
    colliding: List[np.ndarray] = []
    for k in range(1, scenario.steps + 1):
        if removals and k in removals:
            backend.remove(removals[k])
        out = backend.deform(**params)
        state = backend.state() if (measure or after_step is not None) else None
        if truth is not None and state is not None:
            ids, truly = truth.evaluate(state)
            tp, fp, fn, precision, recall = precision_recall(out.colliding, ids, truly)
            judged, n_truth, surfels = len(ids), int(truly.sum()), len(state.ids)
        else:
            tp = fp = fn = judged = n_truth = 0
            precision = recall = float("nan")
            surfels = int(out.stats.get("deformable", 0))
        st = out.stats
        records.append(StepRecord(algorithm=algorithm, step=k, step_ms=out.step_ms,
                                  detect_ms=float(st.get("detect_ms", float("nan"))),
                                  preprocess_ms=float(st.get("preprocess_ms", float("nan"))),
                                  colliding=len(out.colliding), queries=int(st.get("queries", 0)),
                                  tested=int(st.get("tested", 0)), surfels=surfels, truth=n_truth, judged=judged,
                                  tp=tp, fp=fp, fn=fn, precision=precision, recall=recall))
        colliding.append(np.sort(out.colliding))
        if after_step is not None:
            assert state is not None
            after_step(k, backend, out, state)
    return RunResult(scenario=scenario.name, algorithm=algorithm, backend=getattr(backend, "kind", "?"),
                     settings=cfg, records=records, colliding=colliding)


# -- output ------------------------------------------------------------------------------------------
CSV_FIELDS = [f.name for f in dataclasses.fields(StepRecord)]


def write_csv(path: Path, results: Sequence[RunResult]) -> None:
    """One row per algorithm and step (columns: :data:`CSV_FIELDS`)."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["scenario", "backend"] + CSV_FIELDS)
        for res in results:
            for r in res.records:
                row = dataclasses.asdict(r)
                w.writerow([res.scenario, res.backend] + [
                    f"{row[k]:.4f}" if isinstance(row[k], float) else row[k] for k in CSV_FIELDS])


def plot(path: Path, results: Sequence[RunResult], title: str = "", time_field: str = "detect_ms") -> None:
    """Per-step time (``time_field``) and colliding count of every run on one figure (PNG)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_t, ax_c) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    for res in results:
        steps = [r.step for r in res.records]
        ax_t.plot(steps, [getattr(r, time_field) for r in res.records], marker=".", label=res.algorithm)
        ax_c.plot(steps, [r.colliding for r in res.records], marker=".", label=res.algorithm)
    if results and results[0].records and results[0].records[0].judged:
        ax_c.plot([r.step for r in results[0].records], [r.truth for r in results[0].records], "k--", lw=1,
                  label="truth (judged)")
    ax_t.set_ylabel(f"{time_field} per step (ms)")
    ax_t.set_yscale("log")
    ax_t.grid(True, which="both", alpha=0.3)
    ax_t.legend()
    ax_c.set_ylabel("colliding surfels")
    ax_c.set_xlabel("step")
    ax_c.grid(True, alpha=0.3)
    ax_c.legend()
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# -- command line ------------------------------------------------------------------------------------
def _parse_value(text: str) -> Any:
    low = text.lower()
    if low in ("true", "false"):
        return low == "true"
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="surfeledit-scenario", description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", choices=sorted(_scenes.SCENES))
    ap.add_argument("--algorithms", default="simple,improved,temporal,robust",
                    help="comma-separated: none, simple, improved, temporal, robust")
    ap.add_argument("--out", type=Path, required=True, help="directory for <scene>.csv and <scene>.png")
    ap.add_argument("--remote", action="store_true", help="run on a server over DDS (spawned if none answers)")
    ap.add_argument("--domain", type=int, default=None, help="DDS domain (remote)")
    ap.add_argument("--steps", type=int, default=None, help="number of steps (default: the scene's)")
    ap.add_argument("--scale", type=float, default=1.0, help="surfel count multiplier (0.1 -> ~10x fewer)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--threads", type=int, default=0, help="detector threads (0 = all)")
    ap.add_argument("--inside", default=None,
                    help="comma-separated inside modes (nearest, winding, vote): temporal and robust run once per "
                         "mode, labelled e.g. robust/winding (docs/algorithms.md §4.6)")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                    help="another session setting, e.g. --set boundary_n=12 --set resample=true")
    args = ap.parse_args(argv)

    algorithms = [a.strip() for a in args.algorithms.split(",") if a.strip()]
    settings: Dict[str, Any] = {"threads": args.threads}
    for item in args.set:
        if "=" not in item:
            ap.error(f"--set expects NAME=VALUE, got {item!r}")
        k, v = item.split("=", 1)
        settings[k.strip()] = _parse_value(v.strip())
    scenario = make_scenario(args.scene, scale=args.scale, steps=args.steps, seed=args.seed)
    sc = scenario.scene
    print(f"scene {sc.name}: {sc.size} surfels, zero {len(sc.zero)}, deformable {len(sc.deformable)}, "
          f"one {len(sc.one)}, spacing {sc.spacing:.4g}, {scenario.steps} steps; settings {settings}")
    args.out.mkdir(parents=True, exist_ok=True)

    client = None
    if args.remote:
        from .connection import connect
        client = connect(domain=args.domain, spawn=True)
    runs: List[Tuple[str, str, Dict[str, Any]]] = []  # (label, algorithm, settings)
    modes = [m.strip() for m in args.inside.split(",") if m.strip()] if args.inside else []
    for alg in algorithms:
        if modes and alg in ("temporal", "robust"):
            runs += [(f"{alg}/{m}", alg, dict(settings, inside=m)) for m in modes]
        else:
            runs.append((alg, alg, settings))
    results: List[RunResult] = []
    try:
        for label, alg, run_settings in runs:
            backend: Backend = (RemoteBackend(client, f"scenario-{alg}") if client is not None
                                else LocalBackend(args.threads))

            def show(k: int, _b: Any, out: StepOutput, _s: ModelState, alg: str = label) -> None:
                print(f"{alg:9s} step {k:3d}  detect {out.stats.get('detect_ms', float('nan')):9.3f} ms  "
                      f"step {out.step_ms:9.3f} ms  colliding {len(out.colliding):6d}  "
                      f"queries {int(out.stats.get('queries', 0)):7d}", flush=True)

            res = run(scenario, alg, backend=backend, settings=run_settings, after_step=show)
            backend.close()
            res.algorithm = label
            for r in res.records:
                r.algorithm = label
                print(f"{label:9s} step {r.step:3d}  truth {r.truth:6d}  precision {r.precision:.4f}  "
                      f"recall {r.recall:.4f}")
            results.append(res)
    finally:
        if client is not None:
            client.close()
    write_csv(args.out / f"{sc.name}.csv", results)
    plot(args.out / f"{sc.name}.png", results,
         title=f"{sc.name}: {sc.size} surfels, {len(sc.deformable)} deformable, {scenario.steps} steps "
               f"({'DDS' if args.remote else 'in-process'})")
    print("summary:")
    for res in results:
        s = res.summary()
        print(f"  {res.algorithm:9s} detect median {s['median_detect_ms']:.3f} ms max {s['max_detect_ms']:.3f} ms; "
              f"step median {s['median_step_ms']:.3f} ms; preprocessing {s['preprocess_ms']:.3f} ms; "
              f"peak colliding {s['peak_colliding']} (truth {s['peak_truth']}); "
              f"min precision {s['min_precision']:.4f}, min recall {s['min_recall']:.4f} "
              f"(steps with >= 50 true: {s['min_precision_50']:.4f}, {s['min_recall_50']:.4f})")
    print(f"wrote {args.out / (sc.name + '.csv')} and {args.out / (sc.name + '.png')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
