#!/usr/bin/env python3
"""DDS round trip of one deformation step vs a bare DDS ping of the same payload, in one run.

Run (after scripts/setup.sh; needs build/server/app/surfeledit-server and build/tests/surfeledit-proto-echo):
    .venv/bin/python bench/service/bench_step_rtt.py [--build-dir build] [--steps 200] [--warmup 20]
                                                     [--domain D] [--server-threads 1,0] [--max-load 1.0]
                                                     [--algorithm none] [--json-out r.json]

What is timed (all in milliseconds, client side, time.perf_counter):
  step  Session.deform(...) against a real surfeledit-server started by this script on a private DDS
        domain with `--threads T` for each T of --server-threads (0 = the server's default, all cores): the
        client writes a Request (OP_DEFORM) and waits for the matching Reply (StepResult.round_trip_ms).
        The server's own timings (reply `total`, `apply`) are reported beside it.
  ping  surfeledit-proto-echo on the same domain: the same deform Request sample (same type, same
        size) written to echo_in_Request and timed until it comes back on echo_out_Request.
Both go through the same Python cyclonedds stack and QoS (reliable, keep-all, volatile), so their
ratio is the server's overhead. Scenes (fixed seeds): "small" = make_default_scene() at spacing 0.05
(~9.9k surfels), "60k" = slab (F0) + sphere of ~60k deformable surfels (as bench_deformation.cpp).
Steps are sent back to back (the next request as soon as the reply arrives), or --gap-ms apart. The server writes the
Reply BEFORE it publishes the step's Update samples (server/service/src/service.cpp). Up to issue 2 it wrote
them on the same thread, so publishing the Update of step i delayed the serving of step i+1; since issue 3 the
request thread only copies the changed surfels and a publisher thread writes the samples.
--algorithm: the session's collision algorithm (OP_CONFIGURE; default "none", so that the step is the
deformation alone, as in the issue-2 figures; "default" leaves the server's default, robust). A server
without OP_CONFIGURE (before issue 3) is left as it is (it has no detection).
Per scene: ping block, then step block, then a second ping block (pings = both blocks).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Dict, List

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402

from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402

import surfeledit  # noqa: E402
from surfeledit import core  # noqa: E402
from surfeledit._protocol import proto, request_qos  # noqa: E402


def small_scene() -> Dict[str, np.ndarray]:
    s = core.make_default_scene().sample(spacing=0.05, seed=1)
    pos, nrm, part = np.asarray(s.positions), np.asarray(s.normals), np.asarray(s.part)
    sphere = part == 1
    return {"positions": pos, "normals": nrm, "zero": np.flatnonzero(part == 0),
            "one": np.flatnonzero(sphere & (pos[:, 2] > 1.25)), "deformable": int(sphere.sum())}


def scene_60k(deformable: int = 60_000) -> Dict[str, np.ndarray]:
    """Slab 3 x 3 x 0.3 (F0) + sphere r 0.5 at z = 1 with ~`deformable` samples (F1: z > 1.25)."""
    sphere = core.make_sphere(0.5, center=(0.0, 0.0, 1.0))
    slab = core.make_box((1.5, 1.5, 0.15))
    spacing = (sphere.area / deformable) ** 0.5
    spacing *= (len(sphere.sample(spacing=spacing, seed=7)) / deformable) ** 0.5
    sp, sb = sphere.sample(spacing=spacing, seed=7), slab.sample(spacing=spacing, seed=7)
    pos = np.vstack([sb.positions, sp.positions])
    nrm = np.vstack([sb.normals, sp.normals])
    nb = len(sb)
    return {"positions": pos, "normals": nrm, "zero": np.arange(nb),
            "one": nb + np.flatnonzero(np.asarray(sp.positions)[:, 2] > 1.25), "deformable": len(sp)}


def deform_args(i: int) -> dict:
    sign = 1.0 if i % 2 == 0 else -1.0  # oscillate in place
    return {"translation": (0.0, 0.01 * sign, 0.005 * sign), "axis": (1.0, 0.0, 0.0), "angle": 0.05 * sign}


class Echo:
    """surfeledit-proto-echo on `domain` plus a writer/reader pair on echo_in/out_Request."""

    def __init__(self, exe: Path, domain: int) -> None:
        self.proc = subprocess.Popen([str(exe), "--domain", str(domain)], stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, text=True)
        line = self.proc.stdout.readline()
        if "ready" not in line:
            raise RuntimeError(f"surfeledit-proto-echo did not start: {line!r}")
        self.dp = DomainParticipant(domain)
        self.writer = DataWriter(self.dp, Topic(self.dp, "echo_in_Request", proto.Request), qos=request_qos())
        self.reader = DataReader(self.dp, Topic(self.dp, "echo_out_Request", proto.Request), qos=request_qos())
        self.cond = ReadCondition(self.reader, SampleState.NotRead | ViewState.Any | InstanceState.Any)
        self.ws = WaitSet(self.dp)
        self.ws.attach(self.cond)
        deadline = time.monotonic() + 20
        while (self.writer.get_publication_matched_status().current_count == 0
               or self.reader.get_subscription_matched_status().current_count == 0):
            if time.monotonic() > deadline:
                raise RuntimeError("echo endpoints never matched")
            time.sleep(0.01)
        time.sleep(0.3)  # let the echo's writer discover our reader too (volatile)

    def ping(self, sample: "proto.Request") -> float:
        """ms from write to the echoed sample being taken."""
        t0 = time.perf_counter()
        self.writer.write(sample)
        while True:
            got = [s for s in self.reader.take(N=16, condition=self.cond) if isinstance(s, proto.Request)]
            if any(s.request_id == sample.request_id for s in got):
                return (time.perf_counter() - t0) * 1e3
            if time.perf_counter() - t0 > 10:
                raise TimeoutError("echo did not come back within 10 s")
            self.ws.wait(1_000_000_000)

    def close(self) -> None:
        self.proc.terminate()
        self.proc.wait(timeout=10)


def connect_when_up(domain: int, srv: subprocess.Popen, log: Path, timeout_s: float = 60.0) -> "surfeledit.Client":
    """connect(spawn=False) retried until the server we started answers."""
    deadline = time.monotonic() + timeout_s
    while True:
        if srv.poll() is not None:
            raise RuntimeError(f"surfeledit-server exited ({srv.returncode}):\n{log.read_text()[-2000:]}")
        try:
            return surfeledit.connect(domain=domain, spawn=False, timeout=10.0)
        except surfeledit.ServerStartError:
            if time.monotonic() > deadline:
                raise


def run_scenes(client: "surfeledit.Client", echo: Echo, args: argparse.Namespace, threads: int,
               results: Dict[str, dict], rows: List[list]) -> None:
    for name, make in [("small", small_scene), ("60k", scene_60k)]:
        sc = make()
        sess = client.open_session(f"bench-{name}")
        t0 = time.perf_counter()
        sess.load_points(sc["positions"], sc["normals"])
        sess.set_regions(zero=sc["zero"], one=sc["one"])
        if args.algorithm != "default":
            try:
                sess.configure(algorithm=args.algorithm)
            except surfeledit.SurfelEditError as e:  # a server before issue 3: no OP_CONFIGURE, no detection
                print(f"  (configure(algorithm={args.algorithm!r}) refused: {e}; server left as it is)")
        print(f"server --threads {threads}, scene {name}: {len(sc['positions']):,} surfels, {sc['deformable']:,} "
              f"deformable, {len(sc['one']):,} in F1; upload + regions {time.perf_counter() - t0:.1f} s", flush=True)
        # The ping payload: a deform Request exactly as Session.deform builds it.
        a = deform_args(0)
        dreq = proto.Deform(translation=proto.Vec3(*a["translation"]), axis=proto.Vec3(*a["axis"]),
                            angle=a["angle"], has_center=False, center=proto.Vec3(), blend="smooth")

        def ping_block() -> List[float]:
            out = []
            for i in range(args.warmup + args.steps):
                ms = echo.ping(client.new_request(proto.Op.OP_DEFORM, sess.name, deform=dreq))
                if i >= args.warmup:
                    out.append(ms)
            return out

        pings = ping_block()
        rtt, total, apply_ms = [], [], []
        for i in range(args.warmup + args.steps):
            if args.gap_ms > 0:
                time.sleep(args.gap_ms / 1e3)
            r = sess.deform(**deform_args(i))
            if i >= args.warmup:
                rtt.append(r.round_trip_ms)
                total.append(r.timings.get("total", float("nan")))
                apply_ms.append(r.timings.get("apply", float("nan")))
        pings += ping_block()
        sess.close()
        res = {"server_threads": threads, "surfels": len(sc["positions"]), "deformable": sc["deformable"],
               "ping": benchlib.latency_stats(pings), "step": benchlib.latency_stats(rtt),
               "server_total": benchlib.latency_stats(total), "server_apply": benchlib.latency_stats(apply_ms)}
        res["ratio_p50"] = res["step"]["p50"] / res["ping"]["p50"]
        res["ratio_p99"] = res["step"]["p99"] / res["ping"]["p99"]
        key = f"{name} (server --threads {threads})"
        results[key] = res
        for label, k in [("bare ping (echo)", "ping"), ("step round trip", "step"),
                         ("  server total", "server_total"), ("  server apply", "server_apply")]:
            st = res[k]
            rows.append([key, f"{res['surfels']:,} / {res['deformable']:,}", label, st["n"], f"{st['p50']:.3f}",
                         f"{st['p99']:.3f}", f"{st['max']:.3f}"])
        rows.append([key, "", "step / ping", "", f"{res['ratio_p50']:.2f}x", f"{res['ratio_p99']:.2f}x", ""])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build-dir")
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--warmup", type=int, default=20)
    ap.add_argument("--domain", type=int, default=None, help="DDS domain (default: one held by this process)")
    ap.add_argument("--server-threads", default="1,0", help="comma list of surfeledit-server --threads values")
    ap.add_argument("--gap-ms", type=float, default=0.0,
                    help="pause before each step (ms): lets the server finish publishing the previous Update")
    ap.add_argument("--algorithm", default="none",
                    help="collision algorithm of the sessions (none, simple, improved, temporal, robust; "
                         "'default': the server's)")
    ap.add_argument("--max-load", type=float, default=0.0)
    ap.add_argument("--json-out")
    args = ap.parse_args()
    if args.domain is None:
        args.domain = benchlib.take_domain()

    build = benchlib.build_dir(args.build_dir)
    server = build / "server" / "app" / "surfeledit-server"
    echo_exe = next((p for p in [build / "tests" / "surfeledit-proto-echo", build / "server" / "app" /
                                 "surfeledit-proto-echo"] if p.is_file()), None)
    if not server.is_file() or echo_exe is None:
        print(f"missing {server} or surfeledit-proto-echo under {build}: build first")
        return 2
    benchlib.wait_for_low_load(args.max_load, 600)
    print(benchlib.machine_line())
    print(f"DDS domain {args.domain}; server {server}; echo {echo_exe}; gap between steps {args.gap_ms} ms; "
          f"algorithm {args.algorithm}")

    echo = Echo(echo_exe, args.domain)
    results: Dict[str, dict] = {}
    rows = []
    try:
        for threads in [int(t) for t in args.server_threads.split(",")]:
            log = Path(f"/tmp/surfeledit-bench-server-{args.domain}-t{threads}.log")
            with log.open("w") as f:
                srv = subprocess.Popen([str(server), "--domain", str(args.domain), "--threads", str(threads)],
                                       stdin=subprocess.DEVNULL, stdout=f, stderr=subprocess.STDOUT)
            try:
                client = connect_when_up(args.domain, srv, log)
                try:
                    run_scenes(client, echo, args, threads, results, rows)
                finally:
                    client.close()
            finally:
                srv.terminate()
                srv.wait(timeout=20)
    finally:
        echo.close()

    print()
    print(benchlib.table(["scene", "surfels / deformable", "what", "n", "p50 ms", "p99 ms", "max ms"], rows))
    for name, res in results.items():
        ok = res["ratio_p50"] <= 2.0
        print(f"target step <= 2x bare ping ({name}): {'MET' if ok else 'MISSED'} at p50 ({res['ratio_p50']:.2f}x), "
              f"p99 {res['ratio_p99']:.2f}x")
    print("reply vs update: the server writes the Reply first, then queues the Update (issue 3: written by a "
          "publisher thread; before: on the request thread)")
    print(benchlib.machine_line())
    if args.json_out:
        Path(args.json_out).write_text(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
