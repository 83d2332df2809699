"""Collision detection per step on the piercing scene (the thesis's "ball joint piercing santa"
analogue, surfeledit.scenes.piercing), in-process (surfeledit.core.EditSession):

1. the four algorithms at full size (~210k surfels, ~60k deformable, 50 steps), one thread and all
   threads: detect time per step (median, max, curve as PNG), preprocessing, peak colliding;
2. growth with the number of deformable surfels (piercing at several scales, 15k..500k deformable);
3. growth with the number near contact: per-step time against the surfels re-tested that step
   (those that left their spheres) from part 1.

    .venv/bin/python bench/core/bench_collision.py --out bench/out/collision [--quick]

Prints markdown tables; writes piercing_t1.png / piercing_tall.png / CSVs into --out.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402

from surfeledit import scenario as S  # noqa: E402

ALGS = ["simple", "improved", "temporal", "robust"]


def part1(out: Path, scale: float) -> dict:
    sc = S.make_scenario("piercing", scale=scale)
    s = sc.scene
    print(f"\n### Piercing scene: {s.size} surfels, {len(s.zero)} zero, {len(s.deformable)} deformable, "
          f"{sc.steps} steps (scale {scale})\n")
    print("| threads | algorithm | detect median ms | detect max ms | step median ms | preprocessing ms | "
          "peak colliding (truth) | min precision | min recall |")
    print("|---|---|---|---|---|---|---|---|---|")
    all_results = {}
    for threads in (1, 0):
        results = []
        for alg in ALGS:
            res = S.run(sc, alg, backend=S.LocalBackend(threads), settings={"threads": threads})
            sm = res.summary()
            results.append(res)
            print(f"| {threads or os.cpu_count()} | {alg} | {sm['median_detect_ms']:.3f} | {sm['max_detect_ms']:.3f} | "
                  f"{sm['median_step_ms']:.3f} | {sm['preprocess_ms']:.2f} | {sm['peak_colliding']} ({sm['peak_truth']}) | "
                  f"{sm['min_precision']:.3f} | {sm['min_recall']:.3f} |", flush=True)
        tag = "t1" if threads == 1 else "tall"
        S.write_csv(out / f"piercing_{tag}.csv", results)
        S.plot(out / f"piercing_{tag}.png", results,
               title=f"piercing, {len(s.deformable)} deformable, threads {threads or os.cpu_count()}: detect time / colliding")
        all_results[threads] = results
    return all_results


def part2(scales) -> None:
    print("\n### Growth with the deformable count (piercing at several scales, 1 thread)\n")
    print("| deformable | total | algorithm | detect median ms | detect max ms | preprocessing ms | "
          "median re-tested per step |")
    print("|---|---|---|---|---|---|---|")
    for scale in scales:
        sc = S.make_scenario("piercing", scale=scale)
        for alg in ("temporal", "robust"):
            res = S.run(sc, alg, backend=S.LocalBackend(1), settings={"threads": 1}, measure=False)
            d = np.array([r.detect_ms for r in res.records])
            tested = np.median([r.tested for r in res.records])
            print(f"| {len(sc.scene.deformable)} | {sc.scene.size} | {alg} | {np.median(d):.3f} | {d.max():.3f} | "
                  f"{res.records[0].preprocess_ms:.2f} | {tested:.0f} |", flush=True)


def part3(results) -> None:
    print("\n### Step time against the surfels re-tested that step (full size, 1 thread)\n")
    print("| algorithm | fit: detect ms = a + b * re-tested | r | steps with 0 re-tested: median ms |")
    print("|---|---|---|---|")
    for res in results:
        t = np.array([r.tested for r in res.records], float)
        d = np.array([r.detect_ms for r in res.records])
        b, a = np.polyfit(t, d, 1)
        r = np.corrcoef(t, d)[0, 1] if t.std() > 0 else float("nan")
        idle = d[t == 0]
        print(f"| {res.algorithm} | {a:.3f} + {b * 1000:.3f} us x tested | {r:.3f} | "
              f"{np.median(idle) if len(idle) else float('nan'):.3f} |")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=benchlib.REPO / "bench" / "out" / "collision")
    ap.add_argument("--quick", action="store_true", help="scale 0.1 and small growth series (smoke test)")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    print(benchlib.machine_line())
    t0 = time.time()
    res = part1(args.out, 0.1 if args.quick else 1.0)
    part3(res[1])
    part2([0.05, 0.1] if args.quick else [0.25, 0.5, 1.0, 2.0, 4.0, 8.35])
    print(f"\n({time.time() - t0:.0f} s; figures in {args.out})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
