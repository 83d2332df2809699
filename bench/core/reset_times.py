#!/usr/bin/env python3
"""A detector's reset as a session pays it: the wall time of `configure(algorithm=..., zero_hierarchy=...,
deformable_hierarchy=...)` on the piercing scene (surfeledit.scenario, in-process), each time on a fresh session
right after its set_regions (whose reset is Robust's, the default), so that every case resets from the same state;
median over --repeats sessions per case. With --set-regions also the time of set_regions itself (the deformation
fields and the default Robust reset).

    .venv/bin/python bench/core/reset_times.py [--scale 1.0] [--algorithms simple,improved,temporal,robust]
        [--hierarchies none,aabb/none,obb/none,aabb/aabb] [--simplify none] [--threads 1] [--set-regions]
        [--repeats 3] [--package <dir holding another build's surfeledit package, for an A/B>]

--hierarchies: zero/deformable hierarchy pairs (settings zero_hierarchy, deformable_hierarchy), each timed with
every algorithm. --simplify: the approximate detectors' clustering (setting simplify: region_growing or hierarchical,
clusters of the default cluster_size). --threads: the session's threads (0 = all); a reset's independent parts run at
once when it is above one (server/core/src/at_once.hpp). bench_robust_step's BM_Preprocess / BM_PreprocessTemporal
(and their *Threads variants) time Robust's and Temporal's resets alone in C++; this covers every algorithm and
hierarchy. Interleave two builds' runs (--package) for an A/B.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path
from typing import Callable, List

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402


def median_line(label: str, ms: List[float]) -> str:
    return (f"{label}: median {statistics.median(ms):.1f} ms over {len(ms)} "
            f"(runs {', '.join(f'{m:.1f}' for m in ms)})")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scale", type=float, default=1.0, help="piercing scale (1: about 210k surfels)")
    ap.add_argument("--algorithms", default="simple,improved,temporal,robust", help="comma-separated")
    ap.add_argument("--hierarchies", default="none/none",
                    help="comma-separated zero/deformable hierarchy pairs, e.g. none/none,obb/none,aabb/aabb")
    ap.add_argument("--simplify", default="none", help="none, region_growing or hierarchical (setting simplify)")
    ap.add_argument("--threads", type=int, default=1, help="the session's threads (0 = all)")
    ap.add_argument("--set-regions", action="store_true", help="also time set_regions (fields + Robust reset)")
    ap.add_argument("--repeats", type=int, default=3, help="fresh sessions per case")
    benchlib.add_package_arg(ap)
    args = ap.parse_args()
    if args.repeats < 1 or args.threads < 0:
        ap.error("--repeats must be >= 1 and --threads >= 0")
    pairs = []
    for pair in args.hierarchies.split(","):
        zero, _, deformable = pair.partition("/")
        if not deformable:
            ap.error(f"--hierarchies: {pair!r} is not zero/deformable")
        pairs.append((zero, deformable))
    surfeledit = benchlib.import_surfeledit(args.package)
    from surfeledit import scenario as S
    from surfeledit.local import LocalSession

    print(f"# surfeledit from {Path(surfeledit.__file__).parent}; threads {args.threads}; "
          f"{benchlib.load_average()}", flush=True)
    sc = S.make_scenario("piercing", scale=args.scale, seed=1)

    def sessions(prepare: Callable[[LocalSession], None], timed: Callable[[LocalSession], None]) -> List[float]:
        """The wall ms of timed(session) after prepare(session), on --repeats fresh sessions holding the scene."""
        ms = []
        for _ in range(args.repeats):
            with LocalSession("reset-times", threads=args.threads) as session:
                session.load_points(sc.scene.positions, sc.scene.normals, sc.scene.radii)
                prepare(session)
                start = time.perf_counter()
                timed(session)
                ms.append(1e3 * (time.perf_counter() - start))
        return ms

    def set_regions(session: LocalSession) -> None:
        session.set_regions(zero=sc.scene.zero, one=sc.scene.one)

    if args.set_regions:
        print(median_line("set_regions", sessions(lambda session: None, set_regions)), flush=True)
    for zero, deformable in pairs:
        for algorithm in args.algorithms.split(","):
            ms = sessions(set_regions, lambda session: session.configure(
                algorithm=algorithm, zero_hierarchy=zero, deformable_hierarchy=deformable, simplify=args.simplify))
            print(median_line(f"{algorithm} {zero}/{deformable}: configure", ms), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
