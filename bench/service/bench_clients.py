#!/usr/bin/env python3
"""Deform steps per second with 1, 2, 4 and 8 client processes, on ONE session and on SEPARATE sessions
(issue 11 §6).

Run (after scripts/setup.sh; needs build/server/app/surfeledit-server):
    .venv/bin/python bench/service/bench_clients.py [--build-dir build] [--repeats 3] [--seconds 5]
                                                     [--spacing 0.1] [--clients 1,2,4,8]

Each run starts a fresh server on a fresh DDS domain and k client processes (tests/python/service/
collab_peer.py, mode "edit" without a watcher: the real Python client). "one": the bench process opens one session with the
demo scene (sampled at --spacing; slab = zero region, sphere = one region, default collision settings; in "one" each client's tool moves one
sector of the sphere, the rest rigid to it) and
invites the k clients as editors; "separate": each client opens its own session with the same scene. Once
all are ready they start together and send deform steps (small random translations, one at a time each,
waiting for the reply) for --seconds; ops/s = acknowledged steps of all clients / the longest client's
editing time. Medians over --repeats runs per configuration (configurations interleaved: one round runs
every configuration once), with the machine and its load (uptime) before and after.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Dict, List, Tuple

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "client_py"))
sys.path.insert(0, str(ROOT / "tests" / "python"))

import surfeledit  # noqa: E402

from service.conftest import free_domain  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import connect_when_up  # noqa: E402

PEER = ROOT / "tests" / "python" / "service" / "collab_peer.py"




def read(p: subprocess.Popen) -> Dict:
    line = p.stdout.readline() if p.stdout else ""
    if not line:
        raise RuntimeError(f"client process ended: {p.stderr.read() if p.stderr else ''}")
    return json.loads(line)


def one_run(exe: str, k: int, shared: bool, seconds: float, spacing: float) -> Tuple[float, int]:
    """(ops per second, acknowledged steps) of k clients for `seconds`."""
    domain = free_domain()
    log = tempfile.NamedTemporaryFile(prefix="bench-clients-", suffix=".log", delete=False)
    srv = subprocess.Popen([exe, "--domain", str(domain), "--log-level", "warn"], stdout=log,
                           stderr=subprocess.STDOUT, start_new_session=True)
    owner = None
    peers: List[subprocess.Popen] = []
    try:
        owner = connect_when_up(domain)
        token = ""
        if shared:
            from surfeledit.demo import default_scene, sphere_sectors
            s = owner.open_session("bench")
            pos, nrm, rad, part = default_scene(spacing)
            s.load_points(pos, nrm, rad)
            tools = sphere_sectors(pos, part, s.ids(), k)  # one sector of the sphere per client: disjoint locks
            token = s.invite("editor")
        for i in range(k):
            args = dict(session="bench" if shared else f"bench-{i}", token=token, steps=10**9, seconds=seconds,
                        seed=i, scene=spacing, watch=False)
            if shared:
                args["one"] = tools[i]
            peers.append(subprocess.Popen([sys.executable, str(PEER), "edit", str(domain), json.dumps(args)],
                                          stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                          text=True, start_new_session=True))
        for p in peers:
            read(p)
        for p in peers:
            assert p.stdin is not None
            p.stdin.write("go\n")
            p.stdin.flush()
        results = [read(p) for p in peers]
        steps = sum(len(r["versions"]) for r in results)
        return steps / max(r["seconds"] for r in results), steps
    finally:
        for p in peers:
            try:
                if p.stdin:
                    p.stdin.write("quit\n")
                    p.stdin.flush()
                p.wait(timeout=20)
            except (OSError, subprocess.TimeoutExpired):
                p.kill()
                p.wait()
        if owner is not None:
            owner.close()
        srv.terminate()
        srv.wait(timeout=20)
        os.unlink(log.name)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build-dir", default=str(ROOT / "build"))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--seconds", type=float, default=5.0)
    ap.add_argument("--spacing", type=float, default=0.1)
    ap.add_argument("--clients", default="1,2,4,8")
    a = ap.parse_args()
    exe = str(Path(a.build_dir) / "server" / "app" / "surfeledit-server")
    counts = [int(c) for c in a.clients.split(",")]
    uptime_before = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    rates: Dict[Tuple[int, bool], List[float]] = {}
    for _ in range(a.repeats):
        for k in counts:
            for shared in (True, False):
                rate, steps = one_run(exe, k, shared, a.seconds, a.spacing)
                rates.setdefault((k, shared), []).append(rate)
                print(f"  k={k} {'one session' if shared else 'separate'}: {rate:.1f} ops/s ({steps} steps)",
                      file=sys.stderr, flush=True)
    uptime_after = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, {platform.platform()}")
    print(f"load before: {uptime_before}")
    print(f"load after:  {uptime_after}")
    print(f"{a.repeats} runs of {a.seconds:.0f} s per configuration, demo scene at spacing {a.spacing}")
    print("| clients | one session: ops/s (median) | separate sessions: ops/s (median) | one / separate |")
    print("|---|---|---|---|")
    for k in counts:
        one = statistics.median(rates[(k, True)])
        sep = statistics.median(rates[(k, False)])
        print(f"| {k} | {one:.1f} | {sep:.1f} | {one / sep:.2f} |")


if __name__ == "__main__":
    main()
