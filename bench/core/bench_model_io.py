#!/usr/bin/env python3
"""What loading a model file costs and how exact it is: `core.load_file` on each shared mesh as OBJ (the file as
shipped) and as ASCII OFF, ASCII STL and binary STL written from the same vertices and faces, wall milliseconds
(median of --repeats), and the largest distance between a loaded surfel and its vertex (0 for float64 readers; the
float32 ones round each coordinate). Each mesh is also moved 1e6 away from the origin, where float32 loses ~0.03.

    .venv/bin/python bench/core/bench_model_io.py [--repeats 5] [--package <another build's package dir, for an A/B>]

Needs the shared test models (SURFELEDIT_MODELS or ../shared/data/models); prints a note and stops without them.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Dict, List, Tuple

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402

MODELS = ["spot.obj", "mug.obj", "bunny_watertight.obj"]


def models_dir() -> Path:
    env = os.environ.get("SURFELEDIT_MODELS")
    return Path(env) if env else benchlib.REPO.parent / "shared" / "data" / "models"


def read_obj(path: Path) -> Tuple[np.ndarray, np.ndarray]:
    """Vertices (#V by 3, float64 as written) and triangles (#F by 3, 0-based) of a triangle OBJ."""
    verts: List[List[float]] = []
    faces: List[List[int]] = []
    for line in path.read_text().splitlines():
        t = line.split()
        if t and t[0] == "v":
            verts.append([float(x) for x in t[1:4]])
        elif t and t[0] == "f":
            faces.append([int(x.split("/")[0]) - 1 for x in t[1:4]])
    return np.array(verts), np.array(faces)


def write_all(d: Path, stem: str, v: np.ndarray, f: np.ndarray) -> Dict[str, Path]:
    """The mesh as OBJ, OFF, ASCII STL and binary STL in `d`."""
    num = lambda row: " ".join(f"{x:.17g}" for x in row)  # noqa: E731
    out = {k: d / f"{stem}.{k.split()[0]}" for k in ("obj", "off", "stl ascii")}
    out["stl binary"] = d / f"{stem}_b.stl"
    out["obj"].write_text("".join(f"v {num(p)}\n" for p in v) + "".join(f"f {a+1} {b+1} {c+1}\n" for a, b, c in f))
    out["off"].write_text(f"OFF\n{len(v)} {len(f)} 0\n" + "".join(f"{num(p)}\n" for p in v) +
                          "".join(f"3 {a} {b} {c}\n" for a, b, c in f))
    out["stl ascii"].write_text("solid m\n" + "".join(
        "facet normal 0 0 0\nouter loop\n" + "".join(f"vertex {num(v[i])}\n" for i in tri) + "endloop\nendfacet\n"
        for tri in f) + "endsolid m\n")
    tri = np.zeros(len(f), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    tri["v"] = v[f]
    out["stl binary"].write_bytes(b"\0" * 80 + np.uint32(len(f)).tobytes() + tri.tobytes())
    return out


def max_error(loaded: np.ndarray, v: np.ndarray) -> float:
    """Largest distance from a loaded position to the nearest vertex (scipy's cKDTree)."""
    from scipy.spatial import cKDTree
    return float(cKDTree(v).query(loaded)[0].max())


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    benchlib.add_package_arg(ap)
    args = ap.parse_args()
    surfeledit = benchlib.import_surfeledit(args.package)
    from surfeledit import core

    src = models_dir()
    if not src.is_dir():
        print(f"# the shared test models are not at {src}: nothing to measure")
        return 0
    print(f"# surfeledit from {Path(surfeledit.__file__).parent}; {benchlib.machine_line()}", flush=True)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in MODELS:
            v, f = read_obj(src / name)
            for offset in (0.0, 1e6):
                moved = v + offset
                files = write_all(Path(tmp), f"{Path(name).stem}_{int(offset)}", moved, f)
                for kind, path in files.items():
                    times = []
                    try:
                        for _ in range(args.repeats):
                            t0 = time.perf_counter()
                            d = core.load_file(str(path))
                            times.append(time.perf_counter() - t0)
                    except surfeledit.errors.SurfelEditError as e:  # a build that does not read this format
                        rows.append([name, f"{offset:g}", kind, "-", "-", f"refused: {type(e).__name__}"])
                        continue
                    rows.append([name, f"{offset:g}", kind, len(d["positions"]),
                                 f"{1e3 * benchlib.median(times):.1f}", f"{max_error(d['positions'], moved):.3g}"])
                    print("| " + " | ".join(str(c) for c in rows[-1]) + " |", flush=True)
    print(benchlib.table(["model", "offset", "format", "surfels", "load ms (median)", "max |loaded - vertex|"], rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
