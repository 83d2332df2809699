"""Collision responses and the edit history on the piercing scene (surfeledit.scenes.piercing), in-process,
one thread (issue 9 §4):

1. history overhead: wall time of a step beside the core's own apply + detect time (the difference is
   the before-image the history records, plus the binding's call overhead, ~0.05 ms);
2. per colliding step: response report / cancel / backoff / merge (iterations, kept fraction, ms) beside
   the step time; target: back-off <= 2 step times;
3. merge (§7 d) at the first colliding step and at the first with >= --merge-at colliding surfels: merge_regions + crease + intersection curves, and the whole
   session merge (model changes, detector reset, history), median of repeats (undo, merge again).

    .venv/bin/python bench/core/bench_response.py [--scale 1] [--colliding 5] [--merge-at 6500]
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402

from surfeledit import core  # noqa: E402
from surfeledit import scenario as S  # noqa: E402


def open_session(sc: "S.Scenario", **settings: object) -> "core.EditSession":
    s = sc.scene
    es = core.EditSession("bench", threads=1)
    es.load_points(s.positions, s.normals, s.radii)
    es.set_regions(zero=s.zero, one=s.one)
    es.configure(threads=1, **settings)
    return es


def run(sc: "S.Scenario", response: str, colliding_steps: int) -> dict:
    """Steps until `colliding_steps` steps collided; the core's own timings (the machine is shared, so
    wall times of the whole call are noisier)."""
    es = open_session(sc, response=response)
    params = sc.step_params()
    step_ms, history_ms, hit = [], [], []
    for _ in range(sc.steps):
        o = es.deform(**params)
        history_ms.append(o.history_ms)
        if o.response in ("none", "reported"):
            step_ms.append(o.deform_ms + o.stats["detect_ms"])
        if o.response != "none":
            hit.append(o)
        if len(hit) >= colliding_steps:
            break
    return dict(step_ms=step_ms, history_ms=history_ms, hit=hit, history=es.report()["structures"]["history"])


def merge_times(sc: "S.Scenario", at_least: int = 1, repeats: int = 5) -> dict:
    """The session's merge at the first step of a report run with at least `at_least` colliding surfels (or
    the step with the most), `repeats` times (undone between)."""
    es = open_session(sc, response="report")
    params = sc.step_params()
    colliding = 0
    for _ in range(sc.steps):
        colliding = es.deform(**params).colliding.size
        if colliding >= at_least:
            break
    runs = []
    for k in range(repeats):
        m = es.merge(crease=True)
        runs.append(m)
        if k + 1 < repeats:
            es.undo()
    med = {key: statistics.median([m[key] for m in runs]) for key in ("merge_ms", "crease_ms", "curves_ms", "total_ms")}
    last = runs[-1]
    med.update(colliding=colliding, removed=len(last["removed"]), features=len(last["features"]), moved=len(last["moved"]),
               inserted=len(last["inserted"]), curves=len(last["curves"]))
    return med


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scale", type=float, default=1.0)
    ap.add_argument("--colliding", type=int, default=5, help="colliding steps measured per response")
    ap.add_argument("--merge-at", type=int, default=6500,
                    help="also merge at the first step with at least this many colliding surfels (issue 9's ~6,500)")
    args = ap.parse_args()
    sc = S.make_scenario("piercing", scale=args.scale)
    s = sc.scene
    print(benchlib.machine_line())
    print(f"\nPiercing scene: {s.size} surfels, {len(s.deformable)} deformable, step "
          f"{sc.step_params()['translation']}, one thread\n")
    rows = []
    step = 0.0  # the reference: median apply + detect of the report run's steps
    for response in ("report", "cancel", "backoff", "merge"):
        res = run(sc, response, args.colliding)
        hit = res["hit"]
        if response == "report":
            step = statistics.median(res["step_ms"])
            print(f"History: before-image recorded per step, median {statistics.median(res['history_ms']):.2f} ms "
                  f"(max {max(res['history_ms']):.2f}) beside a step (apply + detect) of median {step:.2f} ms; "
                  f"{res['history'] / 2**20:.1f} MiB held after {len(res['history_ms'])} steps + load, regions, "
                  f"configure\n")
        resp = statistics.median([o.response_ms for o in hit])
        backoff = response == "backoff"
        its = [o.backoff["iterations"] for o in hit]
        kept = [o.backoff["kept"] for o in hit]
        rows.append([response, len(hit), f"{statistics.median(res['step_ms'] or [0.0]):.2f}", f"{resp:.2f}", f"{(step + resp) / step:.2f}", f"{statistics.median(its):.0f}" if backoff else "-",
                     f"{min(kept):.3f}..{max(kept):.3f}" if backoff else "-"])
    print(benchlib.table(["response", "colliding steps", "step ms (report run, median)",
                          "response ms (median; back-off: its re-steps)", "(step + response) / step",
                          "back-off iterations (median)", "kept fraction"], rows))
    for at_least in (1, args.merge_at):
        m = merge_times(sc, at_least)
        geometry = m["merge_ms"] + m["crease_ms"] + m["curves_ms"]
        print(f"\nMerge at the first step with >= {at_least} colliding ({m['colliding']} colliding; median of 5, "
              f"undone between): merge_regions {m['merge_ms']:.2f} ms + crease {m['crease_ms']:.2f} ms + curves "
              f"{m['curves_ms']:.2f} ms = {geometry:.2f} ms (target <= 50); whole session merge "
              f"{m['total_ms']:.2f} ms = {m['total_ms'] / step:.1f} step times. Removed {m['removed']}, "
              f"features {m['features']}, moved onto the curve {m['moved']}, gap copies {m['inserted']}, "
              f"{m['curves']} curve(s).")


if __name__ == "__main__":
    main()
