#!/usr/bin/env python3
"""A detector's reset as a session pays it: the wall time of `configure(algorithm=...)` on the piercing scene
(surfeledit.scenario, in-process, one thread), each time right after a Robust configure of a fresh session, so that
every algorithm resets from the same state; median over --repeats sessions per algorithm.

    .venv/bin/python bench/core/reset_times.py [--scale 1.0] [--algorithms simple,improved,temporal,robust]
        [--repeats 3] [--package <dir holding another build's surfeledit package, for an A/B>]

bench_robust_step's BM_Preprocess / BM_PreprocessTemporal time Robust's and Temporal's resets alone in C++; this
covers every algorithm. Interleave two builds' runs (--package) for an A/B.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scale", type=float, default=1.0, help="piercing scale (1: about 210k surfels)")
    ap.add_argument("--algorithms", default="simple,improved,temporal,robust", help="comma-separated")
    ap.add_argument("--repeats", type=int, default=3, help="fresh sessions per algorithm")
    benchlib.add_package_arg(ap)
    args = ap.parse_args()
    surfeledit = benchlib.import_surfeledit(args.package)
    from surfeledit import scenario as S

    print(f"# surfeledit from {Path(surfeledit.__file__).parent}; {benchlib.load_average()}", flush=True)
    sc = S.make_scenario("piercing", scale=args.scale, seed=1)
    for algorithm in args.algorithms.split(","):
        ms = []
        for _ in range(args.repeats):
            backend = S.LocalBackend(1)
            try:
                backend.start(sc.scene)
                backend.configure(algorithm="robust", threads=1)
                start = time.perf_counter()
                backend.configure(algorithm=algorithm, threads=1)
                ms.append(1e3 * (time.perf_counter() - start))
            finally:
                backend.close()
        print(f"{algorithm}: configure median {statistics.median(ms):.1f} ms over {args.repeats} "
              f"(runs {', '.join(f'{m:.1f}' for m in ms)})", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
