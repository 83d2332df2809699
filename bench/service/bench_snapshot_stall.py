#!/usr/bin/env python3
"""How long a journal snapshot stalls the request loop, and where its time goes (docs/journal.md "Snapshots:
the writer thread"; bench/RESULTS.md §48).

Run (after scripts/setup.sh):
    .venv/bin/python bench/service/bench_snapshot_stall.py [--build-dir build] [--baseline-exe OLD_SERVER]
        [--steps 2000] [--snapshot-records 500] [--history-mb 16,default] [--rounds 2] [--journal-root DIR]

For each round, each --history-mb value and each server (this build's, then --baseline-exe when given:
interleaved, the same period on a shared machine), a fresh server with `--threads 1 --journal-sync group
--journal-group-ms 1 --journal-snapshot-records N` gets one session of the small scene (~9.9k surfels,
collision "none") and --steps OP_DEFORM back to back from one client. Reported per run, from the server's
log lines: the snapshots taken, how long each held the request loop (median / max; for a server with the
writer thread its "started" line, else its "taken" line), of which `Handler::save` (encoding, CPU on the
loop; since §67 `Handler::snapshot`: the history's images shared, the rest copied), and, with the writer
thread, the thread's encoding (since §67), write and fdatasync + rename + directory fsync times (off the loop). From the client: the step round trip's median and maximum (a snapshot's stall shows in the step
that follows its point). Journals on the build disk unless --journal-root says otherwise.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Dict, List, Optional

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))
import benchlib  # noqa: E402
from bench_journal import Server, deform_args, open_session_named, small_scene  # noqa: E402

import surfeledit  # noqa: E402

STARTED = re.compile(r"snapshot \d+ started after \d+ record\(s\): the request loop waited ([\d.]+) ms, of which "
                     r"([\d.]+) ms saving the state and ([\d.]+) ms starting")
TAKEN = re.compile(r"snapshot \d+ taken after \d+ record\(s\): ([\d.]+) MB, the request loop waited ([\d.]+) ms, of "
                   r"which ([\d.]+) ms saving the state(?:; the writer thread wrote it in ([\d.]+) ms and synced it in "
                   r"([\d.]+) ms)?")
ENCODED = re.compile(r"snapshot \d+ taken after .* the writer thread encoded it in ([\d.]+) ms first")


def run_once(exe: Path, domain: int, jdir: Path, log: Path, steps: int, every: int,
             history_mb: Optional[float], scene: Dict) -> Dict[str, object]:
    extra = ["--journal", str(jdir), "--journal-sync", "group", "--journal-group-ms", "1",
             "--journal-snapshot-records", str(every)]
    srv = Server(exe, domain, log, extra)
    try:
        srv.wait_ready()
        s = open_session_named(domain, scene, "stall")
        if history_mb is not None:
            s.configure(history_mb=history_mb)
        rtt = []
        for i in range(steps):
            t0 = time.perf_counter()
            s.deform(**deform_args(i))
            rtt.append((time.perf_counter() - t0) * 1e3)
        time.sleep(1.0)  # the last snapshot's writer finishes (its line is logged when the loop wakes)
        s.deform(**deform_args(steps))
        text = srv.text()
        s.client.reconnect = 0.0
        s.client.close()
    finally:
        srv.stop()
        shutil.rmtree(jdir, ignore_errors=True)
    taken = [tuple(float(x) if x else None for x in m) for m in TAKEN.findall(text)]
    started = [tuple(float(x) for x in m) for m in STARTED.findall(text)]
    loop = [t[0] for t in started] if started else [t[1] for t in taken]
    save = [t[1] for t in started] if started else [t[2] for t in taken]
    return {"snapshots": len(taken), "mb": taken[-1][0] if taken else 0.0, "loop": loop, "save": save,
            "segment": [t[2] for t in started],
            "encode": [float(x) for x in ENCODED.findall(text)],
            "write": [t[3] for t in taken if t[3] is not None], "sync": [t[4] for t in taken if t[4] is not None],
            "rtt_median": benchlib.median(rtt), "rtt_max": max(rtt)}


def fmt(values: List[float], how: str = "median") -> str:
    if not values:
        return "-"
    return f"{benchlib.median(values) if how == 'median' else max(values):.1f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build-dir")
    ap.add_argument("--baseline-exe", help="another surfeledit-server build (e.g. main's) run interleaved")
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--snapshot-records", type=int, default=500)
    ap.add_argument("--history-mb", default="16,default", help="comma-separated history_mb values ('default')")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--journal-root")
    ap.add_argument("--domain", type=int, default=190 + (hash(time.time()) % 20))
    args = ap.parse_args()
    build = benchlib.build_dir(args.build_dir)
    exes = {"new": build / "server" / "app" / "surfeledit-server"}
    if args.baseline_exe:
        exes["baseline"] = Path(args.baseline_exe)
    root = Path(args.journal_root) if args.journal_root else Path(tempfile.mkdtemp(prefix="bench-stall-", dir=build))
    root.mkdir(parents=True, exist_ok=True)
    scene = small_scene()
    histories = [None if h.strip() == "default" else float(h) for h in args.history_mb.split(",") if h.strip()]
    print(benchlib.machine_line())
    print(f"journals below {root}; {args.steps} steps, a snapshot every {args.snapshot_records} records")
    rows = []
    n = 0
    for r in range(args.rounds):
        for h in histories:
            for name, exe in exes.items():
                n += 1
                load = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip().split("load average:")[-1]
                res = run_once(exe, args.domain + n % 7, root / f"j-{n}", root / f"s-{n}.log", args.steps,
                               args.snapshot_records, h, scene)
                rows.append([r + 1, "default" if h is None else h, name, res["snapshots"], f"{res['mb']:.1f}",
                             fmt(res["loop"]), fmt(res["loop"], "max"), fmt(res["save"]), fmt(res["segment"]),
                             fmt(res["encode"]), fmt(res["write"]),
                             fmt(res["sync"]), f"{res['rtt_median']:.2f}", f"{res['rtt_max']:.1f}", load.strip()])
                print(benchlib.table(["round", "history_mb", "server", "snapshots", "MB", "loop stall ms (median)",
                                      "(max)", "of which save", "new segment", "writer: encode ms", "writer: write ms",
                                      "writer: sync ms",
                                      "step rtt median ms", "step rtt max ms", "load"], rows[-1:]), flush=True)
    if not args.journal_root:
        shutil.rmtree(root, ignore_errors=True)
    print()
    print(benchlib.table(["round", "history_mb", "server", "snapshots", "MB", "loop stall ms (median)", "(max)",
                          "of which save", "new segment", "writer: encode ms", "writer: write ms", "writer: sync ms",
                          "step rtt median ms", "step rtt max ms", "load (1, 5, 15 min)"], rows))
    print(benchlib.machine_line())


if __name__ == "__main__":
    main()
