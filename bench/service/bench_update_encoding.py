#!/usr/bin/env python3
"""What a watching GUI pays for a deform update, full encoding vs compact (issue 14; PROTOCOL.md "Updates,
compact"), in one run.

Run (after scripts/setup.sh; needs build/server/app/surfeledit-server):
    .venv/bin/python bench/service/bench_update_encoding.py [--build-dir build] [--steps 40] [--rounds 3]
                                                            [--deformable 60000]

A surfeledit-server (`--threads 1`) on a private DDS domain holds the 60k scene of bench_step_rtt.py (slab +
sphere, ~60k deformable surfels, collision algorithm "none"); one client deforms it (a rotation with a
translation, oscillating in place) while one watcher of the chosen encoding is attached. Blocks of --steps
steps alternate between the encodings, --rounds times. Per step (milliseconds, client side,
time.perf_counter, one process):
  rtt     Session.deform(...) until its reply;
  seen    from the deform call until the watcher returned the step's complete update (all parts decoded to
          numpy) and it was applied to a (P, 3) positions / normals copy of the state -- what a GUI waits for.
Bytes: the CDR size of the update samples of one step (sum over parts of the sample's serialisation),
per moved surfel. Accuracy: the compact replay against the session's state after the last step.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Dict, List

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parents[1] / "tests" / "python"))
sys.path.insert(0, str(HERE))
import benchlib  # noqa: E402

import surfeledit  # noqa: E402
from bench_step_rtt import deform_args, scene_60k  # noqa: E402
from common import connect_when_up  # noqa: E402
from service.conftest import free_domain  # noqa: E402
from surfeledit._protocol import proto  # noqa: E402

ENCODINGS = ("full", "compact")


def step_bytes(client: surfeledit.Client, session: surfeledit.Session, encoding: str, i: int) -> int:
    """CDR bytes of the update samples of one step, read raw from an inbox of that encoding."""
    inbox = client.update_inbox(compact=encoding == "compact")
    try:
        version = session.deform(**deform_args(i)).version
        total, parts, got = 0, None, 0
        deadline = time.monotonic() + 30
        while parts is None or got < parts:
            if time.monotonic() > deadline:
                raise RuntimeError(f"{encoding}: the update of v{version} did not arrive")
            for s in inbox.take(64):
                if isinstance(s, proto.Update) and s.session == session.name and s.version == version:
                    total += len(s.serialize())
                    parts, got = int(s.parts), got + 1
            inbox.wait(0.1)
        return total
    finally:
        inbox.close()


def block(session: surfeledit.Session, encoding: str, steps: int, first: int, positions: np.ndarray,
          normals: np.ndarray) -> Dict[str, List[float]]:
    out: Dict[str, List[float]] = {"rtt": [], "seen": []}
    with session.watch(encoding=encoding) as w:
        for i in range(first, first + steps):
            t0 = time.perf_counter()
            version = session.deform(**deform_args(i)).version
            t1 = time.perf_counter()
            while True:
                ev = w.get(timeout=30.0)
                if ev is None:
                    raise RuntimeError(f"{encoding}: no update for v{version}")
                if ev.version == version:
                    break
            rows = ev.ids.astype(np.int64)
            positions[rows] = ev.positions
            normals[rows] = ev.normals
            t2 = time.perf_counter()
            out["rtt"].append((t1 - t0) * 1e3)
            out["seen"].append((t2 - t0) * 1e3)
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build-dir", default=None)
    ap.add_argument("--steps", type=int, default=40)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--deformable", type=int, default=60_000)
    args = ap.parse_args()
    exe = benchlib.build_dir(args.build_dir) / "server" / "app" / "surfeledit-server"
    print(benchlib.machine_line())
    domain = free_domain()
    log = tempfile.NamedTemporaryFile(prefix="bench-update-encoding-", suffix=".log", delete=False)
    srv = subprocess.Popen([str(exe), "--domain", str(domain), "--threads", "1"], stdout=log,
                           stderr=subprocess.STDOUT, start_new_session=True)
    try:
        client = connect_when_up(domain)
        scene = scene_60k(args.deformable)
        session = client.open_session("bench-encoding")
        pos, nrm = scene["positions"], scene["normals"]
        session.load_points(pos, nrm, np.full(len(pos), 0.01))
        ids = session.state().ids
        session.set_regions(zero=ids[scene["zero"]], one=ids[scene["one"]])
        session.configure(algorithm="none")
        state = session.state()
        copies = {e: (state.positions.copy(), state.normals.copy()) for e in ENCODINGS}
        times: Dict[str, Dict[str, List[float]]] = {e: {"rtt": [], "seen": []} for e in ENCODINGS}
        step, err_p, err_n = 0, 0.0, 0.0
        for r in range(args.rounds):
            for e in (ENCODINGS if r % 2 == 0 else ENCODINGS[::-1]):
                # Each copy replays every step: catch it up with the other encoding's steps first.
                fresh = session.state()
                copies[e] = (fresh.positions.copy(), fresh.normals.copy())
                got = block(session, e, args.steps, step, *copies[e])
                step += args.steps
                for k in got:
                    times[e][k] += got[k]
                if e == "compact":  # the replay of this block's updates against the state after it
                    st = session.state()
                    p, n = copies[e]
                    extent = (st.positions.max(axis=0) - st.positions.min(axis=0)).max()
                    err_p = max(err_p, float(np.abs(p - st.positions).max()) / extent)
                    cos = np.clip(np.einsum("ij,ij->i", n, st.normals), -1.0, 1.0)
                    err_n = max(err_n, float(np.arccos(cos).max()))
        moved = int(session.deform(**deform_args(step)).moved)
        step += 1
        sizes = {}
        for e in ENCODINGS:
            sizes[e] = step_bytes(client, session, e, step)
            step += 1
        rows = []
        for e in ENCODINGS:
            t = times[e]
            rows.append([e, f"{sizes[e] / 1e6:.2f}", f"{sizes[e] / moved:.1f}", f"{statistics.median(t['rtt']):.2f}",
                         f"{benchlib.percentile(t['rtt'], 0.9):.2f}", f"{statistics.median(t['seen']):.2f}",
                         f"{benchlib.percentile(t['seen'], 0.9):.2f}"])
        print(f"\n{len(pos):,} surfels, {moved:,} moved per step, {args.rounds} rounds x {args.steps} steps per "
              f"encoding (interleaved), server --threads 1, algorithm none\n")
        print(benchlib.table(["encoding", "MB per step", "bytes per moved surfel", "rtt ms (median)", "rtt p90",
                              "update seen + applied ms (median)", "seen p90"], rows))
        print(f"\ncompact replay vs the state after each compact block: largest position error {err_p:.3g} of the "
              f"scene's extent, largest normal angle {err_n:.3g} rad (arccos of the dot product: ~1e-8 is its "
              f"own rounding)")
        session.close()
        client.close()
    finally:
        srv.terminate()
        srv.wait(timeout=30)
    print(benchlib.machine_line())
    return 0


if __name__ == "__main__":
    sys.exit(main())
