#!/usr/bin/env python3
"""Step round trip with DDS Security on vs off, in one run, interleaved.

Run (after scripts/setup.sh; needs build/server/app/surfeledit-server, build/tests/surfeledit-secure-probe
and openssl):
    .venv/bin/python bench/service/bench_security_rtt.py [--build-dir build] [--rounds 3] [--steps 200]
                                                         [--warmup 20] [--surfels 10000] [--json-out r.json]

Two servers run side by side on two private DDS domains: one with `--security` (certificates and
signed documents made by scripts/make_security.py in a temp dir: discovery, liveliness and every
topic encrypted, access control on), one without. Each round runs one `surfeledit-secure-probe bench`
process holding a client of each server (a secured participant and a plain one): each opens a session,
uploads a slab + sphere of about --surfels surfels, sets the regions and configures algorithm "none"
(the step is the deformation alone); then the two make --warmup + --steps deform steps, alternating
(on, off, off, on, ...), each timed in the probe from dds_write of the Request to the taken Reply (steady
clock). The warm-up pairs are dropped. Besides each arm's percentiles, the median of the paired
differences (on - off of the same step index) is reported: it cancels load that drifts between pairs. The probe is a C++
participant because the Python client's cyclonedds wheel has no security plugins; both arms use the
same probe, so the difference is the security (encryption and signing of every sample, secured discovery).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Dict, List

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402
from common import start_server  # noqa: E402


def run_probe(probe: Path, domains: Dict[str, int], alice: Path, args: argparse.Namespace, tag: str) -> Dict[str, List[float]]:
    cmd = [str(probe), "bench", "--domain", str(domains["security on"]), "--security", str(alice),
           "--plain-domain", str(domains["security off"]), "--client-id", tag, "--session", tag,
           "--surfels", str(args.surfels), "--steps", str(args.warmup + args.steps), "--timeout-s", "30"]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    if r.returncode != 0:
        raise RuntimeError(f"probe failed ({r.returncode}):\n{r.stdout[-2000:]}\n{r.stderr[-2000:]}")
    out: Dict[str, List[float]] = {"security on": [], "security off": []}
    for line in r.stdout.splitlines():
        key, _, value = line.partition("=")
        if key == "surfels":
            args.surfels_actual = int(value)
        if key in ("on_ms", "off_ms"):
            out["security on" if key == "on_ms" else "security off"].append(float(value))
    return {k: v[args.warmup:] for k, v in out.items()}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build-dir")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--warmup", type=int, default=20)
    ap.add_argument("--surfels", type=int, default=10_000)
    ap.add_argument("--json-out")
    args = ap.parse_args()
    build = benchlib.build_dir(args.build_dir)
    server = build / "server" / "app" / "surfeledit-server"
    probe = build / "tests" / "surfeledit-secure-probe"
    if not server.is_file() or not probe.is_file():
        print(f"missing {server} or {probe}: build first")
        return 2
    print(benchlib.machine_line())
    domains = {"security on": benchlib.take_domain("on"), "security off": benchlib.take_domain("off")}
    with tempfile.TemporaryDirectory(prefix="surfeledit-bench-security-") as tmp:
        tmpdir = Path(tmp)
        subprocess.run([sys.executable, str(benchlib.REPO / "scripts" / "make_security.py"), str(tmpdir / "sec"),
                        "--clients", "alice", "--denied", "", "--rogue", ""], check=True, capture_output=True)
        confs = {"security on": (tmpdir / "sec" / "server" / "security.conf", tmpdir / "sec" / "alice" / "security.conf"),
                 "security off": (None, None)}
        servers = {k: start_server(server, domains[k], confs[k][0], tmpdir / f"server-{domains[k]}.log") for k in domains}
        samples: Dict[str, List[float]] = {k: [] for k in domains}
        try:
            for r in range(args.rounds):
                got = run_probe(probe, domains, confs["security on"][1], args, f"alice.bench-{r}")  # alice's reply partitions
                for k in domains:
                    samples[k] += got[k]
                print(f"round {r}: median on {benchlib.median(got['security on']):.3f} ms, off "
                      f"{benchlib.median(got['security off']):.3f} ms over {len(got['security on'])} step pairs",
                      flush=True)
        finally:
            for s in servers.values():
                s.terminate()
                s.wait(timeout=20)
    benchlib.report_paired(samples, "security on", "security off", "step round trip",
                           f"{args.surfels_actual:,} surfels (half deformable), {args.rounds} rounds x {args.steps} "
                           f"step pairs (after {args.warmup} warm-up pairs)", args.json_out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
