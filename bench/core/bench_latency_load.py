#!/usr/bin/env python3
"""Step latency with and without a concurrent load (issue 14, "latency under load"): the piercing scene at
full size, Robust, in-process, at 1 and 2 threads; p50 / p99 / max of the whole step (`timings["total"]`)
and of detection, for

- the drag: the scenario's 50 steps, the ball pushed into the body (collisions from about step 10);
- idle steps: the ball moved back and forth by 1e-4 of the spacing (nothing leaves its sphere, nothing
  collides: the cheapest step a GUI sends while the user holds the mouse still).

Each configuration runs once with nothing else started and once beside `--load N` busy processes (one
Python loop each, default N = the number of cores), so the scheduler has to share the cores. Configurations
are interleaved over `--rounds`. With `--package DIR` an older build's surfeledit package (a copy of
another checkout's client_py) runs the same script, for an A/B in one period.

    .venv/bin/python bench/core/bench_latency_load.py [--rounds 2] [--load 2] [--idle-steps 200]
        [--package DIR] [--scale 1.0] [--algorithm robust] [--knn-eps 0]

--scale 4.8 --algorithm temporal --knn-eps 2 is the ~1M-surfel drag of bench_drag_1m.py (the GUI setting).
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import sys
import time
from pathlib import Path
from typing import Dict, List, Tuple

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402


def spin(stop: "mp.synchronize.Event") -> None:
    """A busy loop until `stop` is set (one process of the concurrent load)."""
    x = 0
    while not stop.is_set():
        for _ in range(100000):
            x += 1


def percentiles(v: List[float]) -> Tuple[float, float, float]:
    a = np.asarray(v)
    return float(np.percentile(a, 50)), float(np.percentile(a, 99)), float(a.max())


def run_once(S, sc, threads: int, idle_steps: int, algorithm: str, knn_eps: float) -> Dict[str, List[float]]:
    """One session: the drag's steps, then idle steps from the drag's start. Returns per-step ms lists."""
    out: Dict[str, List[float]] = {"drag": [], "drag_detect": [], "idle": [], "idle_detect": []}
    backend = S.LocalBackend(threads)
    backend.start(sc.scene)
    backend.configure(algorithm=algorithm, threads=threads, knn_eps=knn_eps)
    tiny = 1e-4 * sc.scene.spacing
    for k in range(idle_steps):
        r = backend.session.deform(translation=(tiny if k % 2 == 0 else -tiny, 0.0, 0.0))
        out["idle"].append(r.timings["total"])
        out["idle_detect"].append(r.timings.get("detect", float("nan")))
    params = sc.step_params()
    for _ in range(sc.steps):
        r = backend.session.deform(**params)
        out["drag"].append(r.timings["total"])
        out["drag_detect"].append(r.timings.get("detect", float("nan")))
    backend.close()
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=2, help="interleaved rounds of every configuration")
    ap.add_argument("--load", type=int, default=os.cpu_count() or 2, help="busy processes of the loaded runs")
    ap.add_argument("--idle-steps", type=int, default=200)
    ap.add_argument("--threads", default="1,2", help="comma-separated thread counts")
    ap.add_argument("--scale", type=float, default=1.0, help="piercing scale (4.8: about 1M surfels)")
    ap.add_argument("--algorithm", default="robust")
    ap.add_argument("--knn-eps", type=float, default=0.0)
    benchlib.add_package_arg(ap)
    args = ap.parse_args()
    surfeledit = benchlib.import_surfeledit(args.package)
    from surfeledit import scenario as S

    print(f"# surfeledit from {Path(surfeledit.__file__).parent}; {benchlib.machine_line()}", flush=True)
    sc = S.make_scenario("piercing", scale=args.scale, seed=1)
    print(f"piercing: {len(sc.scene.positions):,} surfels, {len(sc.scene.deformable):,} deformable, {sc.steps} "
          f"steps; {args.algorithm} knn_eps {args.knn_eps}; {args.idle_steps} idle steps; loaded runs beside {args.load} busy processes", flush=True)
    results: Dict[Tuple[int, int], Dict[str, List[float]]] = {}
    thread_counts = [int(t) for t in args.threads.split(",")]
    for rnd in range(args.rounds):
        for load in (0, args.load):
            stop = mp.Event()
            spinners = [mp.Process(target=spin, args=(stop,), daemon=True) for _ in range(load)]
            for p in spinners:
                p.start()
            try:
                for threads in thread_counts:
                    one = run_once(S, sc, threads, args.idle_steps, args.algorithm, args.knn_eps)
                    acc = results.setdefault((threads, load), {k: [] for k in one})
                    for k, v in one.items():
                        acc[k].extend(v)
                    print(f"round {rnd + 1}, load {load}, threads {threads}: idle p50 "
                          f"{np.median(one['idle']):.3f} ms, drag p50 {np.median(one['drag']):.2f} ms; "
                          f"load average {benchlib.load_average()}", flush=True)
            finally:
                stop.set()
                for p in spinners:
                    p.join()
    print("\n| threads | concurrent load | step | p50 ms | p99 ms | max ms | detect p50 ms | detect p99 ms |")
    print("|---|---|---|---|---|---|---|---|")
    for (threads, load), acc in sorted(results.items()):
        for kind in ("idle", "drag"):
            p50, p99, mx = percentiles(acc[kind])
            d50, d99, _ = percentiles(acc[f"{kind}_detect"])
            print(f"| {threads} | {load} busy | {kind} | {p50:.3f} | {p99:.3f} | {mx:.3f} | {d50:.3f} | {d99:.3f} |")
    return 0


if __name__ == "__main__":
    t0 = time.perf_counter()
    rc = main()
    print(f"total {time.perf_counter() - t0:.0f} s")
    sys.exit(rc)
