"""Interleaved A/B of per-step detection time between two builds of the surfeledit package.

Each round runs the piercing scene at full size (one thread, 50 steps, Robust and Temporal, twice each)
once with package A and once with package B, alternating, so both see the same machine load. Prints,
per algorithm, the median over runs of each run's median step time and the median over steps of each
step's fastest time over all runs (the figure least sensitive to load), with the ratio B / A.

    .venv/bin/python bench/core/ab_collision.py --a OLD/client_py --b NEW/client_py --rounds 5

A and B are folders that hold a built ``surfeledit`` package (its compiled ``core`` module included),
e.g. ``client_py`` of two checkouts.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics as st
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402

ALGS = ("robust", "temporal")

# One run in a child process (so each side imports its own compiled module): JSON {alg: [[ms per step], ...]}.
CHILD = """
import json
from surfeledit import scenario as S
sc = S.make_scenario("piercing", scale=1.0)
out = {}
for rep in range(2):
    for alg in %r:
        res = S.run(sc, alg, backend=S.LocalBackend(1), settings={"threads": 1}, measure=False)
        out.setdefault(alg, []).append([r.detect_ms for r in res.records])
print(json.dumps(out))
""" % (ALGS,)


def one_run(package_dir: str) -> dict:
    env = dict(os.environ, PYTHONPATH=package_dir)
    out = subprocess.run([sys.executable, "-c", CHILD], env=env, check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def summary(runs: list) -> tuple:
    """(median of the runs' medians, median over steps of the fastest time of each step)."""
    medians = st.median(st.median(r) for r in runs)
    fastest = st.median(min(r[i] for r in runs) for i in range(len(runs[0])))
    return medians, fastest


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--a", required=True, help="folder holding package A (before)")
    ap.add_argument("--b", required=True, help="folder holding package B (after)")
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    print(benchlib.machine_line())
    runs = {(alg, side): [] for alg in ALGS for side in "ab"}
    for k in range(args.rounds):
        for side, folder in (("b", args.b), ("a", args.a)) if k % 2 == 0 else (("a", args.a), ("b", args.b)):
            for alg, reps in one_run(folder).items():
                runs[(alg, side)].extend(reps)
    print(f"\n({args.rounds} rounds; {benchlib.load_average()})\n")
    print("| algorithm | runs A + B | median of run medians A / B ms | ratio | fastest per step A / B ms | ratio |")
    print("|---|---|---|---|---|---|")
    for alg in ALGS:
        (ma, fa), (mb, fb) = summary(runs[(alg, "a")]), summary(runs[(alg, "b")])
        print(f"| {alg} | {len(runs[(alg, 'a')])} + {len(runs[(alg, 'b')])} | {ma:.3f} / {mb:.3f} | {mb / ma:.3f} | "
              f"{fa:.3f} / {fb:.3f} | {fb / fa:.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
