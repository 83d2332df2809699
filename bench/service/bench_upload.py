#!/usr/bin/env python3
"""What a Python client pays to upload a model and read it back (issue 14, the update stream's other direction):
`Session.load_points(positions, normals, radii)` of N surfels through a real server, then `Session.state()` (every page).

    .venv/bin/python bench/service/bench_upload.py [--surfels 1000000] [--repetitions 3]

Per repetition (a fresh session each): the wall time and the client thread's CPU time (time.thread_time) of the
upload (LOAD_BEGIN, the chunks, LOAD_COMMIT) and of the full state fetch; medians are printed. The surfels are
random points of a unit sphere with their normals and radii 0.01 (seed 1). For an A/B of two clients, put another
build's package first: `PYTHONPATH=/tmp/old_client_py .venv/bin/python bench/service/bench_upload.py`.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path
from typing import Dict, List

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parents[1] / "tests" / "python"))
sys.path.insert(0, str(HERE))
import benchlib  # noqa: E402
from common import served_client  # noqa: E402

import surfeledit  # noqa: E402


def sphere(n: int) -> Dict[str, np.ndarray]:
    """n random unit-sphere surfels: positions, normals (N, 3), radii (N,)."""
    p = np.random.default_rng(1).normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    return {"positions": p, "normals": p.copy(), "radii": np.full(n, 0.01)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--surfels", type=int, default=1_000_000)
    ap.add_argument("--repetitions", type=int, default=3)
    ap.add_argument("--build-dir", default=None)
    args = ap.parse_args()
    exe = benchlib.build_dir(args.build_dir) / "server" / "app" / "surfeledit-server"
    model = sphere(args.surfels)
    print(f"# {benchlib.machine_line()}; client from {Path(surfeledit.__file__).parent}", flush=True)
    times: Dict[str, List[float]] = {"upload": [], "upload_cpu": [], "state": [], "state_cpu": []}
    with served_client(exe, "bench-upload-") as client:
        for k in range(args.repetitions):
            session = client.open_session(f"upload{k}")
            w, c = time.perf_counter(), time.thread_time()
            session.load_points(**model)
            times["upload"].append((time.perf_counter() - w) * 1e3)
            times["upload_cpu"].append((time.thread_time() - c) * 1e3)
            w, c = time.perf_counter(), time.thread_time()
            state = session.state()
            times["state"].append((time.perf_counter() - w) * 1e3)
            times["state_cpu"].append((time.thread_time() - c) * 1e3)
            if not np.array_equal(state.positions, model["positions"]):
                raise RuntimeError("the state read back differs from the model uploaded")
            session.close()
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"{args.surfels:,} surfels, {args.repetitions} repetitions: upload {med['upload']:.0f} ms (client CPU "
          f"{med['upload_cpu']:.0f}), state read back {med['state']:.0f} ms (client CPU {med['state_cpu']:.0f}); "
          f"load {benchlib.load_average()}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
