"""Scripted demo: load the default scene, pin the slab, move the sphere down in ten steps.

Run with ``python -m surfeledit.demo [--domain D] [--steps N]``. Connects with ``spawn=True`` (a
local ``surfeledit-server`` is started if none answers) and prints one line per step to stdout.
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Optional, Sequence, Tuple

import numpy as np

from .connection import connect


def default_scene(spacing: float = 0.05) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """positions (P, 3), normals (P, 3), radii (P,) float64 and part (P,) (0 slab, 1 sphere) of the
    demo scene from ``surfeledit.core.make_default_scene()``; ``spacing`` in model units."""
    from . import core

    s = core.make_default_scene().sample(spacing=spacing)
    return (np.asarray(s.positions, np.float64), np.asarray(s.normals, np.float64),
            np.asarray(s.radii, np.float64), np.asarray(s.part))


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m surfeledit.demo", description=__doc__.split("\n\n")[0])
    ap.add_argument("--domain", type=int, default=None, help="DDS domain (default: $SURFELEDIT_DOMAIN or 0)")
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--spacing", type=float, default=0.05, help="sample spacing, model units")
    ap.add_argument("--drop", type=float, default=0.03, help="downward translation per step, model units")
    args = ap.parse_args(argv)

    pos, nrm, rad, part = default_scene(args.spacing)
    print(f"scene: {len(pos)} surfels (a rigid slab and a sphere above it, spacing {args.spacing})")
    with connect(domain=args.domain, spawn=True) as client:
        info = client.info()
        print(f"server {info.version} on domain {client.domain}, max_chunk_surfels={info.max_chunk_surfels}")
        with client.open_session(f"demo-{client.client_id}") as session:
            t0 = time.perf_counter()
            session.load_points(pos, nrm, rad)
            print(f"loaded in {(time.perf_counter() - t0) * 1e3:.1f} ms")
            ids = session.ids()  # ascending ids, assigned in upload order
            session.set_regions(zero=ids[part == 0], one=ids[part == 1])
            print(f"{'seq':>4} {'version':>8} {'moved':>8} {'step ms':>9} {'rt ms':>9}")
            for _ in range(args.steps):
                r = session.deform(translation=(0.0, 0.0, -args.drop))
                print(f"{r.seq:>4} {r.version:>8} {r.moved:>8} {r.timings.get('total', float('nan')):>9.2f} "
                      f"{r.round_trip_ms:>9.2f}")
            final = session.positions()
            print(f"sphere lowest z: {final[part == 1, 2].min():.3f}")
            held = session.info()
            parts = ", ".join(f"{s.name} {s.bytes / 1024:.0f} KiB" for s in held.structures)
            print(f"session holds {held.surfels} surfels, {held.bytes_per_surfel:.1f} bytes/surfel ({parts})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
