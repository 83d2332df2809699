"""Cost of the edit history per step, interleaved A/B (issue 9 §1): two in-process sessions of the
piercing scene take the same steps, one recording its history (default history_mb), one not
(history_mb=0 with response report: no before-image at all); the steps alternate between them (order
swapped every step) and the wall time of each deform() call is compared. One thread.

    .venv/bin/python bench/core/bench_history.py [--scale 1] [--steps 12] [--rounds 3]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))
import benchlib  # noqa: E402
from bench_response import open_session  # noqa: E402

from surfeledit import scenario as S  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scale", type=float, default=1.0)
    ap.add_argument("--steps", type=int, default=12, help="steps per round (the piercing scene's first ones)")
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    sc = S.make_scenario("piercing", scale=args.scale)
    print(benchlib.machine_line())
    print(f"\nPiercing scene: {sc.scene.size} surfels, {len(sc.scene.deformable)} deformable, one thread, "
          f"{args.rounds} rounds x {args.steps} steps\n")
    params = sc.step_params()
    on_ms, off_ms, core_ms, hist_ms, diffs = [], [], [], [], []
    held = 0
    for _ in range(args.rounds):
        a = open_session(sc)                # history on (default history_mb)
        b = open_session(sc, history_mb=0)  # no history
        for k in range(min(args.steps, sc.steps)):
            order = (a, b) if k % 2 == 0 else (b, a)
            t = {}
            for es in order:
                t0 = time.perf_counter()
                o = es.deform(**params)
                t[id(es)] = (time.perf_counter() - t0) * 1e3
                if es is a:
                    core_ms.append(o.deform_ms + o.stats["detect_ms"])
                    hist_ms.append(o.history_ms)
            on_ms.append(t[id(a)])
            off_ms.append(t[id(b)])
            diffs.append(t[id(a)] - t[id(b)])
        held = a.report()["structures"]["history"]
    med_off = statistics.median(off_ms)
    rows = [["history on", f"{statistics.median(on_ms):.2f}", f"{statistics.median(hist_ms):.3f}"],
            ["history off (history_mb=0)", f"{med_off:.2f}", "-"]]
    print(benchlib.table(["session", "deform() wall ms (median)", "history_ms reported (median)"], rows))
    d = statistics.median(diffs)
    print(f"\nPaired difference on - off: median {d:.3f} ms = {100 * d / med_off:.1f}% of the step without history "
          f"(step apply + detect, core: median {statistics.median(core_ms):.2f} ms); "
          f"history held after {args.steps} steps: {held / 2**20:.1f} MiB")


if __name__ == "__main__":
    main()
