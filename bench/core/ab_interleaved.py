#!/usr/bin/env python3
# Interleaved A/B of two Google Benchmark binaries (e.g. a kept copy of the old bench and the new one):
#   python3 bench/core/ab_interleaved.py OLD NEW [runs=5] [filter]
# Alternates the binaries run by run; per run the CPU time of each median aggregate, then the median over runs.
import json, subprocess, sys, statistics, os
old, new = sys.argv[1], sys.argv[2]
runs = int(sys.argv[3]) if len(sys.argv) > 3 else 5
flt = sys.argv[4] if len(sys.argv) > 4 else "cached|grid"
res = {old: {}, new: {}}
for r in range(runs):
    for b in (old, new) if r % 2 == 0 else (new, old):
        out = subprocess.run([b, f"--benchmark_filter={flt}", "--benchmark_format=json"], capture_output=True, text=True).stdout
        for x in json.loads(out)["benchmarks"]:
            if x.get("aggregate_name") == "median":
                res[b].setdefault(x["run_name"], []).append(x["cpu_time"])
print("load", os.getloadavg())
for name in res[old]:
    a, b = statistics.median(res[old][name]), statistics.median(res[new][name])
    print(f"{name}: old {a:.1f} ms, new {b:.1f} ms, ratio {a/b:.2f}  (old runs {[round(v) for v in res[old][name]]}, new {[round(v) for v in res[new][name]]})")
