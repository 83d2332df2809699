#!/usr/bin/env python3
"""The journal's cost: step round trip without a journal, with group commit and with fsync per op
(same run, interleaved blocks), and recovery time against the journal's length.

Run (after scripts/setup.sh; needs build/server/app/surfeledit-server):
    .venv/bin/python bench/service/bench_journal.py [--build-dir build] [--steps 200] [--blocks 5]
        [--group-ms 2] [--clients 4] [--seconds 5] [--lengths 250,1000,4000] [--journal-root DIR]
        [--baseline-exe OLD_SERVER] [--json-out r.json]

Round trip: three servers (no journal; --journal-sync group --journal-group-ms G; --journal-sync op),
each on its own DDS domain with `--threads 1`, each with one session of the small scene
(make_default_scene() at spacing 0.05, ~9.9k surfels; collision algorithm "none", so the step is the
deformation alone). The client sends --steps OP_DEFORM back to back to one server, then to the next,
for --blocks rounds; Session.deform's round trip (client side, time.perf_counter) is recorded per op.
Medians and 90th percentiles per configuration (wall time: on a shared machine it carries the others'
load, and fdatasync's time carries their disk writes; --journal-root on a tmpfs such as /dev/shm takes
the disk out and leaves the code path). --baseline-exe adds a fourth server, another build
of surfeledit-server (e.g. a copy of the one before a change) with the same group commit settings, to
the same interleaved blocks: an A/B in the same period on a shared machine. Then throughput: --clients clients (threads of this
process, one connection and one session each) step back to back for --seconds against each server;
reported with the server's CPU time per step (user + system of all its threads, from /proc), which
the other processes' load disturbs far less than the rate.

Recovery: for each length L of --lengths, a fresh journal of L steps (plus the load and the regions)
is written by a server which is then SIGKILLed; a new server on the same directory recovers it
(--lengths "" skips this part). Reported:
the server's own replay time (its "recovered ... in X ms" log line), the wall time from starting the
process to its "ready" log line, and the journal's size. The journals live below --journal-root
(default: a temporary directory under build/, the same disk as the build: fsync costs what it costs there).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Dict, List

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402

import surfeledit  # noqa: E402
from surfeledit import core  # noqa: E402


def small_scene() -> Dict[str, np.ndarray]:
    s = core.make_default_scene().sample(spacing=0.05, seed=1)
    pos, nrm, part = np.asarray(s.positions), np.asarray(s.normals), np.asarray(s.part)
    return {"positions": pos, "normals": nrm, "zero": np.flatnonzero(part == 0),
            "one": np.flatnonzero((part == 1) & (pos[:, 2] > 1.25))}


def deform_args(i: int) -> dict:
    sign = 1.0 if i % 2 == 0 else -1.0  # oscillate in place
    return {"translation": (0.0, 0.01 * sign, 0.005 * sign), "axis": (1.0, 0.0, 0.0), "angle": 0.05 * sign}


class Server:
    def __init__(self, exe: Path, domain: int, log: Path, extra: List[str]) -> None:
        self.log = log
        self.started = time.perf_counter()
        with open(log, "wb") as out:
            self.proc = subprocess.Popen([str(exe), "--domain", str(domain), "--threads", "1"] + extra,
                                         stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT,
                                         start_new_session=True)
        self.domain = domain

    def cpu_s(self) -> float:
        """The server process's CPU time so far (user + system, all threads), seconds."""
        fields = Path(f"/proc/{self.proc.pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    def text(self) -> str:
        return self.log.read_text(errors="replace")

    def wait_ready(self, timeout: float = 600.0) -> float:
        """Seconds from the start of the process to its "ready" log line."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if "ready on domain" in self.text():
                return time.perf_counter() - self.started
            if self.proc.poll() is not None:
                raise RuntimeError(f"server exited with {self.proc.returncode}:\n{self.text()[-2000:]}")
            time.sleep(0.002)
        raise RuntimeError("server not ready")

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.kill()


def open_session(domain: int, scene: Dict[str, np.ndarray]) -> "surfeledit.Session":
    return open_session_named(domain, scene, "bench")


def open_session_named(domain: int, scene: Dict[str, np.ndarray], name: str,
                       algorithm: str = "none") -> "surfeledit.Session":
    client = surfeledit.connect(domain=domain, spawn=False, timeout=30.0)
    s = client.open_session(name)
    s.load_points(scene["positions"], scene["normals"])
    s.configure(algorithm=algorithm)
    s.set_regions(zero=scene["zero"], one=scene["one"])
    return s


def domain_of(args: argparse.Namespace, offset: int) -> int:
    """The domain of the server numbered ``offset``: --domain + offset, or one this process holds."""
    return args.domain + offset if args.domain is not None else benchlib.take_domain(offset)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build-dir")
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--blocks", type=int, default=5)
    ap.add_argument("--group-ms", type=int, default=2)
    ap.add_argument("--lengths", default="250,1000,4000")
    ap.add_argument("--journal-root")
    ap.add_argument("--domain", type=int, default=None,
                    help="first DDS domain; the servers use it + 0, 1, ... (default: domains held by this process)")
    ap.add_argument("--clients", type=int, default=4)
    ap.add_argument("--seconds", type=float, default=5.0)
    ap.add_argument("--baseline-exe", help="another surfeledit-server build, run with the group commit settings")
    ap.add_argument("--json-out")
    ap.add_argument("--recovery-only", action="store_true", help="skip the round trip and throughput parts")
    ap.add_argument("--snapshot-records", default="0",
                    help="recovery: comma-separated --journal-snapshot-records values to compare (0: no snapshots)")
    ap.add_argument("--algorithm", default="none", help="collision algorithm of the session (default: none)")
    ap.add_argument("--history-mb", type=float, help="recovery: the session's history_mb (default: the server's)")
    args = ap.parse_args()
    build = benchlib.build_dir(args.build_dir)
    exe = build / "server" / "app" / "surfeledit-server"
    root = Path(args.journal_root) if args.journal_root else Path(tempfile.mkdtemp(prefix="bench-journal-", dir=build))
    root.mkdir(parents=True, exist_ok=True)
    print(benchlib.machine_line())
    print(f"journal directories below {root}")
    scene = small_scene()
    group = ["--journal-sync", "group", "--journal-group-ms", str(args.group_ms)]
    configs = {
        "off": (exe, []),
        f"group {args.group_ms} ms": (exe, ["--journal", str(root / "group")] + group),
        "fsync per op": (exe, ["--journal", str(root / "op"), "--journal-sync", "op"]),
    }
    if args.baseline_exe:
        configs[f"group {args.group_ms} ms (baseline exe)"] = (Path(args.baseline_exe),
                                                             ["--journal", str(root / "group-baseline")] + group)
    servers: List[Server] = []
    results: Dict[str, object] = {"machine": benchlib.machine_line()}
    try:
        if not args.recovery_only:
            round_trip_and_throughput(args, configs, root, scene, servers, results)
        recovery(args, exe, root, scene, servers, results)
        print(benchlib.machine_line())
    finally:
        for srv in servers:
            srv.stop()
        if not args.journal_root:
            shutil.rmtree(root, ignore_errors=True)
    if args.json_out:
        Path(args.json_out).write_text(json.dumps(results, indent=2))


def round_trip_and_throughput(args: argparse.Namespace, configs: dict, root: Path, scene: Dict[str, np.ndarray],
                              servers: List[Server], results: Dict[str, object]) -> None:
    sessions = {}
    for k, (name, (server_exe, extra)) in enumerate(configs.items()):
        srv = Server(server_exe, domain_of(args, k), root / f"rtt-{k}.log", extra)
        servers.append(srv)
        srv.wait_ready()
        sessions[name] = open_session(srv.domain, scene)
    rtt: Dict[str, List[float]] = {name: [] for name in configs}
    for name, s in sessions.items():  # warm-up
        for i in range(20):
            s.deform(**deform_args(i))
    for _ in range(args.blocks):
        for name, s in sessions.items():
            for i in range(args.steps):
                rtt[name].append(s.deform(**deform_args(i)).round_trip_ms)
    rows = [[name, len(v), f"{benchlib.median(v):.2f}", f"{benchlib.percentile(v, 0.9):.2f}"]
            for name, v in rtt.items()]
    print("\nstep round trip (ms), interleaved blocks of", args.steps, "steps,", args.blocks, "rounds:")
    print(benchlib.table(["journal", "steps", "median", "p90"], rows))
    results["rtt"] = {name: {"median": benchlib.median(v), "p90": benchlib.percentile(v, 0.9)}
                      for name, v in rtt.items()}
    for s in sessions.values():
        s.client.close()

    # Throughput: --clients clients, each on its own session of the same server, steps back to back.
    tput_rows = []
    results["throughput"] = {}
    for k, name in enumerate(configs):
        many = [open_session_named(domain_of(args, k), scene, f"tput-{c}") for c in range(args.clients)]
        counts = [0] * len(many)
        stop_at = time.monotonic() + args.seconds

        def run(c: int) -> None:
            i = 0
            while time.monotonic() < stop_at:
                many[c].deform(**deform_args(i))
                i += 1
            counts[c] = i

        threads = [threading.Thread(target=run, args=(c,)) for c in range(len(many))]
        cpu0 = servers[k].cpu_s()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        cpu_ms = (servers[k].cpu_s() - cpu0) * 1e3 / max(sum(counts), 1)
        rate = sum(counts) / args.seconds
        tput_rows.append([name, args.clients, f"{rate:.0f}", f"{cpu_ms:.3f}"])
        results["throughput"][name] = rate
        results.setdefault("server_cpu_ms_per_step", {})[name] = cpu_ms
        for s in many:
            s.client.close()
    print(f"\nthroughput: {args.clients} clients (one session each) stepping back to back for {args.seconds} s:")
    print(benchlib.table(["journal", "clients", "steps/s (all clients)", "server CPU ms / step"], tput_rows))
    for srv in servers:
        srv.stop()
    servers.clear()


def recovery(args: argparse.Namespace, exe: Path, root: Path, scene: Dict[str, np.ndarray], servers: List[Server],
             results: Dict[str, object]) -> None:
    """For each length and --snapshot-records value: a fresh journal, SIGKILL, recovery; with snapshots also
    how long each snapshot blocked the request loop and the size of its file."""
    rec_rows = []
    results["recovery"] = []
    every = [int(x) for x in args.snapshot_records.split(",") if x.strip()]
    lengths = [int(x) for x in args.lengths.split(",") if x.strip()]
    n = 0
    for length in lengths:
        for snap in every:
            n += 1
            jdir = root / f"recovery-{length}-{snap}"
            extra = ["--journal", str(jdir), "--journal-sync", "group", "--journal-group-ms", "1"]
            if snap:  # only then: a server built before snapshots (an A/B baseline) runs the rest
                extra += ["--journal-snapshot-records", str(snap)]
            srv = Server(exe, domain_of(args, 10 + n), root / f"rec-{length}-{snap}-a.log", extra)
            servers.append(srv)
            srv.wait_ready()
            s = open_session_named(srv.domain, scene, "bench", args.algorithm)
            if args.history_mb is not None:
                s.configure(history_mb=args.history_mb)
            for i in range(length):
                s.deform(**deform_args(i))
            srv.kill()
            taken = [(float(mb), float(ms), float(save)) for mb, ms, save in re.findall(
                r"snapshot \d+ taken after \d+ record\(s\): ([\d.]+) MB, the request loop waited ([\d.]+) ms, of "
                r"which ([\d.]+) ms saving", srv.text())]
            s.client.reconnect = 0.0
            srv2 = Server(exe, domain_of(args, 10 + n), root / f"rec-{length}-{snap}-b.log", extra)
            servers.append(srv2)
            ready_s = srv2.wait_ready()
            m = re.search(r"recovered (\d+) request\(s\), (\d+) refusal\(s\), (\d+) expiries from ([\d.]+) MB in "
                          r"(\d+) ms(?:: (?:snapshot \d+ restored \((\d+) record\(s\) before it not replayed\)|"
                          r"no snapshot), (\d+) record\(s\) replayed)?", srv2.text())
            assert m, srv2.text()[-2000:]
            mb, replay_ms = float(m.group(4)), int(m.group(5))
            skipped = int(m.group(6) or 0)
            replayed = int(m.group(7)) if m.group(7) else sum(int(m.group(k)) for k in (1, 2, 3))
            block = [ms for _, ms, _ in taken]
            save = [ms for _, _, ms in taken]
            rec_rows.append([length, snap or "-", skipped, replayed, f"{mb:.1f}", replay_ms, f"{ready_s * 1e3:.0f}",
                             len(taken), f"{benchlib.median(block):.1f}" if block else "-",
                             f"{max(block):.1f}" if block else "-", f"{benchlib.median(save):.1f}" if save else "-",
                             f"{taken[-1][0]:.2f}" if taken else "-"])
            results["recovery"].append({"steps": length, "snapshot_records": snap, "skipped": skipped,
                                        "replayed": replayed, "mb": mb, "replay_ms": replay_ms,
                                        "ready_ms": ready_s * 1e3, "snapshots": len(taken), "snapshot_ms": block,
                                        "save_ms": save, "snapshot_mb": [t[0] for t in taken]})
            srv2.stop()
            try:
                s.client.close()
            except surfeledit.SurfelEditError:
                pass
            shutil.rmtree(jdir, ignore_errors=True)
    print(f"\nrecovery against journal length (steps of the small scene, algorithm {args.algorithm}, history_mb "
          f"{args.history_mb if args.history_mb is not None else 'default'}, plus load/configure/regions):")
    print(benchlib.table(["steps", "snapshot every", "records not replayed", "records replayed", "log MB",
                          "recovery ms", "start-to-ready ms", "snapshots taken", "snapshot blocks ms (median)",
                          "(max)", "of which save (median)", "snapshot MB"], rec_rows))


if __name__ == "__main__":
    main()
