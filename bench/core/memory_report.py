#!/usr/bin/env python3
"""Memory per surfel of an editing session: every structure's share (EditSession.report()) for each
collision algorithm and hierarchy, on the piercing scene (surfeledit.scenes.piercing, scale 1, seed 1),
after two deformation steps (so per-step structures exist), in-process, one thread.

    .venv/bin/python bench/core/memory_report.py [--scale 1.0] [--steps 2]

Prints one markdown table per configuration (structure, bytes, bytes per surfel, share; the history
split by image kind -- rows: steps, tool: set_regions / configure / release, whole: every other op -- as
"history[kind] (entries)" rows under it, not counted twice) and a summary table (total bytes per
surfel per configuration). Bytes are what the structures report (capacities of
their arrays), not the process's resident set.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Dict, List

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402

from surfeledit import scenario as S  # noqa: E402

CONFIGS = [
    ("simple", {}), ("improved", {}), ("temporal", {}), ("robust", {}),
    ("robust", {"zero_hierarchy": "aabb"}), ("robust", {"zero_hierarchy": "obb"}),
    ("robust", {"zero_hierarchy": "aabb", "deformable_hierarchy": "aabb"}),
    ("robust", {"zero_hierarchy": "sphere"}),
]


def measure(sc: S.Scenario, algorithm: str, extra: Dict[str, str], steps: int) -> Dict:
    backend = S.LocalBackend(1)
    backend.start(sc.scene)
    backend.configure(algorithm=algorithm, threads=1, **extra)
    for _ in range(steps):
        backend.deform(**sc.step_params())
    rep = backend.session.report()
    backend.close()
    return rep


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scale", type=float, default=1.0)
    ap.add_argument("--steps", type=int, default=2)
    args = ap.parse_args()
    print(benchlib.machine_line())
    sc = S.make_scenario("piercing", scale=args.scale)
    summary: List[list] = []
    for algorithm, extra in CONFIGS:
        label = algorithm + "".join(f", {k}={v}" for k, v in extra.items())
        rep = measure(sc, algorithm, extra, args.steps)
        n = rep["surfels"]
        total = rep["total_bytes"]
        rows = [[name, f"{b:,}", f"{b / n:.1f}", f"{100.0 * b / total:.1f}%"]
                for name, b in sorted(rep["structures"].items(), key=lambda kv: -kv[1])]
        for kind, k in rep.get("history_kinds", {}).items():
            if k["entries"]:
                b = k["bytes"]
                rows.append([f"  history[{kind}] ({k['entries']})", f"{b:,}", f"{b / n:.1f}", f"{100.0 * b / total:.1f}%"])
        print(f"\n## {label}: {n:,} surfels, {rep['bytes_per_surfel']:.1f} bytes per surfel")
        print(benchlib.table(["structure", "bytes", "bytes/surfel", "share"], rows))
        summary.append([label, f"{rep['bytes_per_surfel']:.1f}"])
    print("\n## summary (bytes per surfel)")
    print(benchlib.table(["configuration", "bytes/surfel"], summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
