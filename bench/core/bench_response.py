"""Collision responses and the edit history on the piercing scene (surfeledit.scenes.piercing), in-process,
one thread (issue 9 §4):

1. history overhead: wall time of a step beside the core's own apply + detect time (the difference is
   the before-image the history records, plus the binding's call overhead, ~0.05 ms);
2. per colliding step: response report / cancel / backoff (iterations, kept fraction, ms) beside the
   step time; target: back-off <= 2 step times.

    .venv/bin/python bench/core/bench_response.py [--scale 1] [--colliding 5]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402

from surfeledit import LocalSession  # noqa: E402
from surfeledit import scenario as S  # noqa: E402


def open_session(sc: "S.Scenario", **settings: object) -> LocalSession:
    s = sc.scene
    ls = LocalSession("bench", threads=1)
    ls.load_points(s.positions, s.normals, s.radii)
    ls.set_regions(zero=s.zero, one=s.one)
    ls.configure(threads=1, **settings)
    return ls


def run(sc: "S.Scenario", response: str, colliding_steps: int) -> dict:
    """Steps until `colliding_steps` steps collided: per step wall ms, core apply + detect ms."""
    ls = open_session(sc, response=response)
    params = sc.step_params()
    walls, cores, hit = [], [], []
    for _ in range(sc.steps):
        t0 = time.perf_counter()
        r = ls.deform(**params)
        wall = (time.perf_counter() - t0) * 1e3
        if r.response in ("none", "reported") or not hit:
            walls.append(wall)
            cores.append(r.timings["apply"] + r.timings.get("detect", 0.0))
        if r.response != "none":
            hit.append((wall, r))
        if len(hit) >= colliding_steps:
            break
    return dict(walls=walls, cores=cores, hit=hit, history=ls.report()["structures"].get("history", 0))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scale", type=float, default=1.0)
    ap.add_argument("--colliding", type=int, default=5, help="colliding steps measured per response")
    args = ap.parse_args()
    sc = S.make_scenario("piercing", scale=args.scale)
    s = sc.scene
    print(benchlib.machine_line())
    print(f"\nPiercing scene: {s.size} surfels, {len(s.deformable)} deformable, step {sc.step_params()['translation']}"
          f", one thread\n")
    rows = []
    base = None
    for response in ("report", "cancel", "backoff"):
        res = run(sc, response, args.colliding)
        step = statistics.median(res["walls"])
        if base is None:
            base = res
            over = statistics.median(np.subtract(res["walls"], res["cores"]))
            print(f"History: step wall median {step:.2f} ms, core apply+detect median "
                  f"{statistics.median(res['cores']):.2f} ms -> before-image + call overhead {over:.2f} ms "
                  f"per step; history holds {res['history'] / 2**20:.1f} MiB after {len(res['walls'])} steps\n")
        hit = res["hit"]
        ms = [w for w, _ in hit]
        its = [r.backoff.iterations for _, r in hit]
        kept = [r.backoff.kept for _, r in hit]
        rows.append([response, len(hit), f"{statistics.median(res['walls']):.2f}", f"{statistics.median(ms):.2f}",
                     f"{statistics.median(ms) / step:.2f}", f"{statistics.median(its):.0f}" if response == "backoff" else "-",
                     f"{min(kept):.3f}..{max(kept):.3f}" if response == "backoff" else "-"])
    print(benchlib.table(["response", "colliding steps", "step median ms (no collision)", "colliding step median ms",
                          "x step", "back-off iterations (median)", "kept fraction"], rows))


if __name__ == "__main__":
    main()
