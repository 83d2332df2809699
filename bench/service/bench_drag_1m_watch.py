#!/usr/bin/env python3
"""The ~1M-surfel drag through a real server with a watcher attached (issue 14: "whole step (deform + detect +
update written)"): piercing at scale 4.8, Temporal with exact queries (the GUI setting of bench/core/bench_drag_1m.py),
the server with `--threads 2`, one client deforming and one watcher of the session (full encoding) in this
process. Per step (milliseconds, client side, time.perf_counter):

  rtt    Session.deform(...) until its reply (the server writes the reply before it prepares the update);
  seen   from the deform call until the watcher has the step's whole update (every part decoded to numpy);
  total  the reply's server-side step time (timings["total"]).

    .venv/bin/python bench/service/bench_drag_1m_watch.py [--server EXE[,EXE2...]] [--rounds 1] [--scale 4.8]

With several servers (e.g. a copy of main's build and this one) their runs alternate, --rounds times each, in one
period; every run loads the scene anew and runs the scenario's steps, without and then with the watcher.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path
from typing import Dict, List

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parents[1] / "tests" / "python"))
sys.path.insert(0, str(HERE))
import benchlib  # noqa: E402
from common import served_client  # noqa: E402

from surfeledit import scenario as S  # noqa: E402


def run(exe: str, sc: S.Scenario, watch: bool) -> Dict[str, List[float]]:
    out: Dict[str, List[float]] = {"rtt": [], "seen": [], "total": []}
    with served_client(Path(exe), "bench-drag-1m-watch-") as client:
        backend = S.RemoteBackend(client, "drag1m")
        backend.start(sc.scene)
        backend.configure(algorithm="temporal", threads=2, knn_eps=0.0)
        params = sc.step_params()
        watcher = backend.session.watch() if watch else None
        try:
            for _ in range(sc.steps):
                t0 = time.perf_counter()
                r = backend.session.deform(**params)
                t1 = time.perf_counter()
                if watcher is not None:
                    while True:
                        ev = watcher.get(timeout=60.0)
                        if ev is None:
                            raise RuntimeError(f"no update for v{r.version}")
                        if ev.version == r.version:
                            break
                out["rtt"].append((t1 - t0) * 1e3)
                out["seen"].append((time.perf_counter() - t0) * 1e3)
                out["total"].append(float(r.timings["total"]))
        finally:
            if watcher is not None:
                watcher.close()
        backend.close()
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    default = benchlib.build_dir(None) / "server" / "app" / "surfeledit-server"
    ap.add_argument("--server", default=str(default), help="comma-separated server executables (alternated)")
    ap.add_argument("--rounds", type=int, default=1)
    ap.add_argument("--scale", type=float, default=4.8)
    args = ap.parse_args()
    print(f"# {benchlib.machine_line()}", flush=True)
    sc = S.make_scenario("piercing", scale=args.scale, seed=1)
    print(f"piercing scale {args.scale}: {len(sc.scene.positions):,} surfels, {sc.steps} steps; temporal knn_eps 0 (exact), "
          f"server --threads 2", flush=True)
    for rnd in range(args.rounds):
        for exe in args.server.split(","):
            for watch in (False, True):
                t = run(exe, sc, watch)
                med = {k: statistics.median(v) for k, v in t.items()}
                p90 = {k: benchlib.percentile(v, 0.9) for k, v in t.items()}
                print(f"round {rnd + 1} {exe} watcher {'yes' if watch else 'no '}: server total {med['total']:.2f} "
                      f"(p90 {p90['total']:.2f}) ms, rtt {med['rtt']:.2f} (p90 {p90['rtt']:.2f}) ms, update seen "
                      f"{med['seen']:.2f} (p90 {p90['seen']:.2f}) ms; load {benchlib.load_average()}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
