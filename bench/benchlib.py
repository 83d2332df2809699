"""Helpers shared by the Python benchmark drivers in bench/ (machine info, load, tables, paths).

Not a benchmark itself; the drivers put bench/ on sys.path and import it.
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path
from types import ModuleType
from typing import Dict, List, Optional, Sequence

REPO = Path(__file__).resolve().parents[1]


def cpu_model() -> str:
    """The CPU's model name, with its family and model numbers and whether it has AVX-512 (/proc/cpuinfo's first
    processor): hosts of one model name have differed in these (bench/RESULTS.md §89)."""
    fields: dict = {}
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            key, _, value = line.partition(":")
            key = key.strip()
            if key in ("model name", "cpu family", "model", "flags") and key not in fields:
                fields[key] = value.strip()
            if key == "flags":
                break
    except OSError:
        pass
    if "model name" not in fields:
        return platform.processor() or "unknown"
    avx512 = "AVX-512" if "avx512f" in fields.get("flags", "").split() else "no AVX-512"
    return f"{fields['model name']} (family {fields.get('cpu family', '?')} model {fields.get('model', '?')}, {avx512})"


def load_average() -> str:
    one, five, fifteen = os.getloadavg()
    return f"{one:.2f}, {five:.2f}, {fifteen:.2f}"


def machine_line() -> str:
    """CPU model, logical cores and load average (1, 5, 15 min) right now."""
    return f"machine: {cpu_model()}, {os.cpu_count()} logical cores, load average {load_average()}"


def wait_for_low_load(max_load: float, timeout_s: float) -> None:
    """Waits (up to timeout_s) until the 1-minute load average is below max_load; prints what it did."""
    if max_load <= 0:
        return
    deadline = time.monotonic() + timeout_s
    while os.getloadavg()[0] >= max_load and time.monotonic() < deadline:
        time.sleep(5)
    print(f"load before start: {load_average()} (waited for 1-min load < {max_load} up to {timeout_s:.0f} s)")


def add_package_arg(ap: argparse.ArgumentParser) -> None:
    """--package DIR: import surfeledit from DIR (a copy of another build's package) for an A/B."""
    ap.add_argument("--package", default="", help="directory to import surfeledit from (A/B)")


def import_surfeledit(package: str) -> ModuleType:
    """Imports surfeledit, from `package` first when given (add_package_arg); interleave runs of two
    packages in one period for a fair comparison."""
    if package:
        sys.path.insert(0, str(Path(package).resolve()))
    return importlib.import_module("surfeledit")


def build_dir(explicit: Optional[str]) -> Path:
    """--build-dir, else env SURFELEDIT_BUILD_DIR, else <repo>/build."""
    return Path(explicit or os.environ.get("SURFELEDIT_BUILD_DIR") or REPO / "build").resolve()


def percentile(values: Sequence[float], q: float) -> float:
    """q in [0, 1], linear interpolation between closest ranks."""
    s = sorted(values)
    pos = q * (len(s) - 1)
    lo = int(pos)
    hi = min(lo + 1, len(s) - 1)
    return s[lo] + (pos - lo) * (s[hi] - s[lo])


def median(values: Sequence[float]) -> float:
    return statistics.median(values)


def latency_stats(values: Sequence[float]) -> Dict[str, float]:
    """Count, p50, p90, p99 and max of latencies (any unit; the benches' JSON and tables)."""
    return {"n": len(values), "p50": median(values), "p90": percentile(values, 0.9),
            "p99": percentile(values, 0.99), "max": max(values)}


def report_paired(samples: Dict[str, List[float]], on: str, off: str, title: str, context: str,
                  json_out: Optional[str] = None) -> Dict[str, Dict[str, float]]:
    """Prints the latency table of every sample list, the `on` / `off` ratio at p50 and the median of their
    paired differences (same index: the two were measured alternately), then the machine line; writes the
    statistics as JSON to `json_out` when given. Returns them."""
    results = {k: latency_stats(v) for k, v in samples.items()}
    print()
    print(table([title, "n", "p50 ms", "p90 ms", "p99 ms", "max ms"],
                [[k, st["n"], f"{st['p50']:.3f}", f"{st['p90']:.3f}", f"{st['p99']:.3f}", f"{st['max']:.3f}"]
                 for k, st in results.items()]))
    diffs = [a - b for a, b in zip(samples[on], samples[off])]
    results["paired difference"] = latency_stats(diffs)
    print(f"{on} / {off} at p50: {results[on]['p50'] / results[off]['p50']:.2f}x; median of the paired differences "
          f"({on} - {off}, same step index): {median(diffs):+.3f} ms; {context}")
    print(machine_line())
    if json_out:
        Path(json_out).write_text(json.dumps(results, indent=2))
    return results


def table(header: Sequence[str], rows: List[Sequence[object]]) -> str:
    """A Markdown table (also readable on a terminal)."""
    cells = [[str(c) for c in header]] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    fmt = lambda r: "| " + " | ".join(c.ljust(w) for c, w in zip(r, widths)) + " |"  # noqa: E731
    lines = [fmt(cells[0]), "|" + "|".join("-" * (w + 2) for w in widths) + "|"]
    lines += [fmt(r) for r in cells[1:]]
    return "\n".join(lines)


_domains: Dict[object, int] = {}


def take_domain(key: object = None) -> int:
    """A DDS domain this process holds until it exits (tests/python/service/domains.py: an exclusive lock
    per domain id, so no test run or other benchmark uses it meanwhile); the same one for the same ``key``."""
    if key not in _domains:
        sys.path.insert(0, str(REPO / "tests" / "python"))
        from service import domains  # the tests' allocator: one lock file per domain
        _domains[key] = domains.take()
    return _domains[key]
