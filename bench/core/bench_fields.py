#!/usr/bin/env python3
"""What selecting regions costs: the blend fields (`compute_fields`, the core of every `set_regions`) on the
generated scenes, upright and turned as a whole (a model tilted against the axes), one thread, CPU seconds
(median of --repeats), through the in-process `core.DeformationTool`. With --threads N > 1 the seconds are wall
seconds instead (the two regions' trees are built at once on a large model; the CPU time would count both threads).

    .venv/bin/python bench/core/bench_fields.py [--scenes piercing,cup,concave,thinwall,two_arms,bunny] [--repeats 3]
        [--threads 1] [--package <dir holding another build's surfeledit package, for an A/B>]

Each line ends with the sha1 of the fields (lambda and its gradient, as float64 bytes), so two builds' runs can be
checked for identical results. The bunny needs the shared test models (SURFELEDIT_MODELS or ../shared); it is
left out with a note when they are absent.
"""

from __future__ import annotations

import argparse
import hashlib
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402

# The turn of the "tilted" rows: about an axis that is along none of the world's, so that no flat part stays
# axis-aligned.
TILT_AXIS = (1.0, 0.7, 0.3)
TILT_ANGLE = 0.6  # radians


class TwoArms:
    """The two-arm scene of server/core/include/surfeledit/core/two_arms.hpp at spacing 0.004 (~210k surfels): a box
    body with two capsule arms standing on it; tool "a"'s regions (zero: the body and arm B, one: arm A, whose
    surfels stand up to 0.67 away from their zero region)."""

    def __init__(self, core) -> None:
        arm_z = 0.2 + 0.25 + 0.1 - 0.03
        scene = core.Scene()
        scene.add(core.make_box(np.array([0.7, 0.2, 0.2])))
        scene.add(core.make_capsule(0.1, 0.25, center=np.array([-0.4, 0.0, arm_z])))
        scene.add(core.make_capsule(0.1, 0.25, center=np.array([0.4, 0.0, arm_z])))
        s = scene.sample(spacing=0.004, seed=1, jitter=0.25)
        part = np.asarray(s.part)
        self.positions, self.normals = np.asarray(s.positions), np.asarray(s.normals)
        self.zero, self.one = np.flatnonzero(part != 1), np.flatnonzero(part == 1)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", default="piercing,cup,concave,thinwall,two_arms,bunny", help="comma-separated")
    ap.add_argument("--repeats", type=int, default=3, help="fields computed per scene and pose")
    ap.add_argument("--threads", type=int, default=1, help="the tool's threads (> 1: wall seconds)")
    benchlib.add_package_arg(ap)
    args = ap.parse_args()
    surfeledit = benchlib.import_surfeledit(args.package)
    from surfeledit import core, scenes

    print(f"# surfeledit from {Path(surfeledit.__file__).parent}; {benchlib.machine_line()}", flush=True)
    rows = []
    for name in args.scenes.split(","):
        try:
            sc = TwoArms(core) if name == "two_arms" else getattr(scenes, name)()
        except FileNotFoundError as e:
            print(f"# {name}: left out ({e})", flush=True)
            continue
        turn = scenes.rotation_matrix(TILT_AXIS, TILT_ANGLE)
        for pose, rot in (("upright", np.eye(3)), ("tilted", turn)):
            positions = np.ascontiguousarray(sc.positions @ rot.T)
            normals = np.ascontiguousarray(sc.normals @ rot.T)
            seconds, digest = [], ""
            clock = time.process_time if args.threads == 1 else time.perf_counter
            for _ in range(args.repeats):
                t = clock()
                tool = core.DeformationTool(positions, normals, zero=sc.zero, one=sc.one, threads=args.threads)
                seconds.append(clock() - t)
                h = hashlib.sha1(np.ascontiguousarray(tool.lam, dtype=np.float64).tobytes())
                h.update(np.ascontiguousarray(tool.grad_lam, dtype=np.float64).tobytes())
                digest = h.hexdigest()[:12]
            blend = len(positions) - len(sc.zero) - len(sc.one)
            rows.append((name, pose, f"{len(positions):,}", f"{blend:,}", f"{statistics.median(seconds):.3f}",
                         " ".join(f"{s:.3f}" for s in seconds), digest))
            print(f"{name} {pose}: {statistics.median(seconds):.3f} s; fields sha1 {digest}", flush=True)
    print()
    what = "median CPU s" if args.threads == 1 else f"median wall s, {args.threads} threads"
    print(benchlib.table(("scene", "pose", "surfels", "blend rows", what, "runs", "fields sha1"), rows))
    print(f"\n{benchlib.machine_line()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
