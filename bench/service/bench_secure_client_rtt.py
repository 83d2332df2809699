#!/usr/bin/env python3
"""Step round trip of the Python client with DDS Security on vs off, in one run, interleaved.

Run (after scripts/setup.sh, with the .venv-secure interpreter; needs build/server/app/surfeledit-server
and openssl):
    .venv-secure/bin/python bench/service/bench_secure_client_rtt.py [--build-dir build] [--rounds 3]
        [--steps 200] [--warmup 20] [--spacing 0.02] [--wheel-python .venv/bin/python] [--json-out r.json]

Two servers run side by side on two private DDS domains: one with `--security` (the demo setup of
scripts/make_security.py: discovery, liveliness and every topic encrypted, access control on), one
without. This process (the cyclonedds 0.10.2 binding of .venv-secure) holds a secured client of the
first (user alice) and a plain client of the second; each opens a session with the demo scene (slab
and sphere, `--spacing`), sets the regions and configures algorithm "none" (the step is the deformation
alone); then they make --warmup + --steps `Session.deform` calls, alternating (on, off, off, on, ...),
each timed around the call (perf_counter: request written, reply taken and decoded). Per round, a
third arm follows: the plain client on the cyclonedds 11 wheel of .venv (`--wheel-python`), in a child
process, the same steps against the plain server: the ordinary client, against which the
binding's own cost shows (not interleaved step by step: a round apart).
The warm-up steps are dropped; besides each arm's percentiles the median of the paired differences
(on - off of the same step index) is reported.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Dict, List

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402
from common import start_server  # noqa: E402

import surfeledit  # noqa: E402
from surfeledit.demo import default_scene  # noqa: E402

ON, OFF, WHEEL = "secured (0.10.2 binding)", "plain (0.10.2 binding)", "plain (11.0.1 wheel)"


def prepare(client: "surfeledit.Client", name: str, spacing: float) -> "surfeledit.Session":
    positions, normals, radii, part = default_scene(spacing)
    s = client.open_session(name)
    s.load_points(positions, normals, radii)
    s.set_regions(zero=np.flatnonzero(part == 0), one=np.flatnonzero(part == 1))
    s.configure(algorithm="none")
    return s


def step_ms(s: "surfeledit.Session", i: int) -> float:
    # Back and forth, so the model stays where it is over any number of steps.
    t = time.perf_counter()
    s.deform(translation=(0.0, 0.0, 0.001 if i % 2 == 0 else -0.001))
    return (time.perf_counter() - t) * 1e3


def worker(domain: int, session: str, spacing: float, steps: int) -> int:
    """Child process: the plain client of this interpreter's binding; prints the step times (JSON)."""
    with surfeledit.connect(domain, spawn=False, timeout=30) as c, prepare(c, session, spacing) as s:
        print(json.dumps([step_ms(s, i) for i in range(steps)]))
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build-dir")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--warmup", type=int, default=20)
    ap.add_argument("--spacing", type=float, default=0.02)
    ap.add_argument("--wheel-python", default=str(benchlib.REPO / ".venv" / "bin" / "python"))
    ap.add_argument("--json-out")
    ap.add_argument("--worker", nargs=2, metavar=("DOMAIN", "SESSION"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        return worker(int(args.worker[0]), args.worker[1], args.spacing, args.warmup + args.steps)
    from surfeledit.security import security_available
    if not security_available():
        print("this cyclonedds binding has no DDS Security plugins: run with .venv-secure/bin/python")
        return 2
    server = benchlib.build_dir(args.build_dir) / "server" / "app" / "surfeledit-server"
    print(benchlib.machine_line())
    domains = {ON: benchlib.take_domain(ON), OFF: benchlib.take_domain(OFF)}
    samples: Dict[str, List[float]] = {ON: [], OFF: [], WHEEL: []}
    n_surfels = 0
    with tempfile.TemporaryDirectory(prefix="surfeledit-bench-secclient-") as tmp:
        sec = Path(tmp) / "sec"
        subprocess.run([sys.executable, str(benchlib.REPO / "scripts" / "make_security.py"), str(sec),
                        "--clients", "alice", "--denied", "", "--rogue", ""], check=True, capture_output=True)
        servers = [start_server(server, domains[ON], sec / "server" / "security.conf", Path(tmp) / "on.log"),
                   start_server(server, domains[OFF], None, Path(tmp) / "off.log")]
        try:
            for r in range(args.rounds):
                with surfeledit.connect(domains[ON], security=sec / "alice" / "security.conf", timeout=30) as con, \
                        surfeledit.connect(domains[OFF], spawn=False, timeout=30) as coff, \
                        prepare(con, f"on-{r}", args.spacing) as son, prepare(coff, f"off-{r}", args.spacing) as soff:
                    n_surfels = int(son.info().surfels)
                    got: Dict[str, List[float]] = {ON: [], OFF: []}
                    for i in range(args.warmup + args.steps):
                        order = ((ON, son), (OFF, soff)) if i % 2 == 0 else ((OFF, soff), (ON, son))
                        for arm, s in order:
                            got[arm].append(step_ms(s, i))
                w = subprocess.run([args.wheel_python, __file__, "--worker", str(domains[OFF]), f"wheel-{r}",
                                    "--spacing", str(args.spacing), "--steps", str(args.steps), "--warmup",
                                    str(args.warmup)], capture_output=True, text=True, timeout=900)
                if w.returncode != 0:
                    raise RuntimeError(f"wheel worker failed:\n{w.stdout[-2000:]}\n{w.stderr[-2000:]}")
                got[WHEEL] = json.loads(w.stdout.strip().splitlines()[-1])
                for arm in samples:
                    samples[arm] += got[arm][args.warmup:]
                print(f"round {r}: median " + ", ".join(f"{a} {benchlib.median(got[a][args.warmup:]):.3f} ms"
                                                        for a in samples), flush=True)
        finally:
            for s in servers:
                s.terminate()
                s.wait(timeout=20)
    benchlib.report_paired(samples, ON, OFF, "step round trip (Python client)",
                           f"{n_surfels:,} surfels, {args.rounds} rounds x {args.steps} step pairs (after "
                           f"{args.warmup} warm-up pairs)", args.json_out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
