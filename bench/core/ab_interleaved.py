#!/usr/bin/env python3
# Interleaved A/B of two Google Benchmark binaries (e.g. a kept copy of the old bench and the new one):
#   python3 bench/core/ab_interleaved.py OLD NEW [runs=5] [filter] [counters]
# Alternates the binaries run by run; per run the CPU time of each median aggregate, then the median over runs.
# With `counters` (comma-separated user counters, e.g. detect_cpu_median_ms,detect_cpu_max_ms; cpu_time and
# real_time count too, in the benchmark's unit) those counters of every benchmark run instead (ms when the name
# ends in _ms or is a time). Pin it with `taskset -c 1 python3 ...` (the binaries inherit the mask).
# "paired" is the median of the per-run ratios old/new (run k of each binary back to back): on a host whose speed
# drifts between runs it is steadier than the ratio of the two medians; "min" is the ratio of the fastest runs (the
# host's fast mode, when it switches between two speeds).
import json, subprocess, sys, statistics, os
old, new = sys.argv[1], sys.argv[2]
runs = int(sys.argv[3]) if len(sys.argv) > 3 else 5
flt = sys.argv[4] if len(sys.argv) > 4 else "cached|grid"
counters = sys.argv[5].split(",") if len(sys.argv) > 5 else []
res = {old: {}, new: {}}
loads = []
for r in range(runs):
    for b in (old, new) if r % 2 == 0 else (new, old):
        out = subprocess.run([b, f"--benchmark_filter={flt}", "--benchmark_format=json"], capture_output=True, text=True).stdout
        for x in json.loads(out)["benchmarks"]:
            if counters:
                for c in counters:
                    if c in x:
                        res[b].setdefault(f"{x['run_name']} {c}", []).append(x[c])
            elif x.get("aggregate_name") == "median":
                res[b].setdefault(x["run_name"], []).append(x["cpu_time"])
        loads.append(os.getloadavg()[0])
print("load", os.getloadavg(), "1-min load during the runs %.1f-%.1f" % (min(loads), max(loads)))
digits = 3 if counters else 1
rnd = (lambda v: round(v, 3)) if counters else round
for name in res[old]:
    a, b = statistics.median(res[old][name]), statistics.median(res[new][name])
    unit = " ms" if not counters or name.endswith(("_ms", "cpu_time", "real_time")) else ""
    paired = statistics.median(x / y for x, y in zip(res[old][name], res[new][name]))
    print(f"{name}: old {a:.{digits}f}{unit}, new {b:.{digits}f}{unit}, ratio {a/b:.2f}, paired {paired:.2f}, "
          f"min {min(res[old][name]) / min(res[new][name]):.2f}  "
          f"(old runs {[rnd(v) for v in res[old][name]]}, new {[rnd(v) for v in res[new][name]]})")
