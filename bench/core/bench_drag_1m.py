#!/usr/bin/env python3
"""The ~1M-surfel drag (issue 14): piercing at scale 4.8, the GUI setting (Temporal, exact queries: knn_eps 0,
which since RESULTS §63 is faster than knn_eps 2), in-process,
at 1 and 2 threads. Per step: the whole call, the deformation share (the session's `apply` timing: the
step's apply_step and its bookkeeping) and the detector's share; medians over the scenario's steps. Also the
calling thread's CPU time per step (time.thread_time: the whole step's CPU at one thread, where it is the
figure to compare on a busy machine; at two threads it leaves out the worker's share).

    .venv/bin/python bench/core/bench_drag_1m.py [--scale 4.8] [--threads 1,2] [--rounds 1]
        [--package <dir holding another build's surfeledit package, for an A/B>] [--breakdown]

Each thread count's line ends with the sha1 of every step's colliding ids and depths (in step order), so
two builds' runs can be checked for identical results.

--breakdown calls the core session directly (no Python result objects) and adds the history's share (the
before-image and the entry, StepResult::history_ms) and the rest (whole call - apply - detect - history: the
step's bookkeeping, the response, the binding). It also splits the steps by the history's phase: while it grows
(each step's image is new memory, whose pages the kernel maps and zeroes on first touch: ~0.5 ms per MB here) and
once it is at its bound (setting history_mb; the oldest entry's buffers are reused), with the minor page faults per
step of each (RESULTS §85).

With --package, that directory goes first on sys.path, so an older build's package (e.g. a copy of main's
client_py in /tmp) runs the same script; interleave the two in one period for a fair comparison.
"""

from __future__ import annotations

import argparse
import hashlib
import resource
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scale", type=float, default=4.8, help="piercing scale (4.8: about 1M surfels)")
    ap.add_argument("--threads", default="1,2", help="comma-separated thread counts")
    ap.add_argument("--algorithm", default="temporal")
    ap.add_argument("--knn-eps", type=float, default=0.0, help="0: exact (the GUI setting); 2: the former one")
    ap.add_argument("--rounds", type=int, default=1, help="runs of the scenario per thread count")
    benchlib.add_package_arg(ap)
    ap.add_argument("--breakdown", action="store_true", help="also the history's share and the rest")
    args = ap.parse_args()
    surfeledit = benchlib.import_surfeledit(args.package)
    from surfeledit import scenario as S

    print(f"# surfeledit from {Path(surfeledit.__file__).parent}; {benchlib.load_average()}", flush=True)
    sc = S.make_scenario("piercing", scale=args.scale, seed=1)
    print(f"piercing scale {args.scale}: {len(sc.scene.positions):,} surfels, {sc.steps} steps; "
          f"{args.algorithm} knn_eps {args.knn_eps}", flush=True)
    params = sc.step_params()
    for threads in (int(t) for t in args.threads.split(",")):
        total, apply, detect, history, cpu, asleep = [], [], [], [], [], []
        phase: dict = {"growing": ([], []), "bounded": ([], [])}  # per phase: step ms, minor page faults
        digest = hashlib.sha1()
        for _ in range(args.rounds):
            backend = S.LocalBackend(threads)
            backend.start(sc.scene)
            backend.configure(algorithm=args.algorithm, threads=threads, knn_eps=args.knn_eps)
            for _ in range(sc.steps):
                if args.breakdown:
                    entries = backend.session.core.report()["history_kinds"]["rows"]["entries"]
                    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
                    c0 = time.thread_time()
                    t0 = time.perf_counter()
                    o = backend.session.core.deform(**params)
                    total.append((time.perf_counter() - t0) * 1e3)
                    cpu.append((time.thread_time() - c0) * 1e3)  # the step's alone, not the reports around it
                    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults
                    grew = backend.session.core.report()["history_kinds"]["rows"]["entries"] > entries
                    phase["growing" if grew else "bounded"][0].append(total[-1])
                    phase["growing" if grew else "bounded"][1].append(faults)
                    apply.append(float(o.deform_ms))
                    detect.append(float(o.stats["detect_ms"]) if o.detected else float("nan"))
                    history.append(float(o.history_ms))
                    if o.detected and o.stats["deformable"]:
                        asleep.append(100.0 * o.stats.get("asleep", 0) / o.stats["deformable"])
                    digest.update(np.asarray(o.colliding, np.uint64).tobytes())
                    digest.update(np.asarray(o.depths, np.float64).tobytes())
                    continue
                c0 = time.thread_time()
                r = backend.session.deform(**params)
                cpu.append((time.thread_time() - c0) * 1e3)
                digest.update(np.asarray(r.colliding, np.uint64).tobytes())
                digest.update(np.asarray(r.depths, np.float64).tobytes())
                total.append(r.timings["total"])
                apply.append(r.timings["apply"])
                detect.append(r.timings.get("detect", float("nan")))
            backend.close()
        extra = ""
        if history:
            rest = [t - a - d - h for t, a, d, h in zip(total, apply, detect, history)]
            extra = f", history {statistics.median(history):.2f} ms, rest {statistics.median(rest):.2f} ms"
        if asleep:
            extra += f"; rows asleep {statistics.median(asleep):.0f} %"
        for name, (ms, faults) in phase.items() if history else ():
            if ms:
                extra += (f"; history {name}: {len(ms)} steps, median {statistics.median(ms):.2f} ms, "
                          f"{statistics.median(faults):.0f} page faults")
        print(f"threads {threads}: step median {statistics.median(total):.2f} ms "
              f"(deformation {statistics.median(apply):.2f} ms, detect {statistics.median(detect):.2f} ms{extra}), "
              f"calling thread's CPU {statistics.median(cpu):.2f} ms, {len(total)} steps; results sha1 {digest.hexdigest()[:12]}; {benchlib.load_average()}", flush=True)
    return 0


if __name__ == "__main__":
    t0 = time.perf_counter()
    rc = main()
    print(f"total {time.perf_counter() - t0:.0f} s")
    sys.exit(rc)
