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

from .client import connect


def fallback_scene(spacing: float = 0.05) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A small numpy scene used when ``surfeledit.core`` is not built: a box slab and a sphere above it.

    Returns positions (P, 3), normals (P, 3), radii (P,) float64 in model units and part (P,) int
    (0 = slab, 1 = sphere).
    """
    # Sphere of radius 0.5 centred at (0, 0, 1): Fibonacci lattice with about one sample per spacing^2.
    r, c = 0.5, np.array([0.0, 0.0, 1.0])
    n_sphere = max(64, int(4 * np.pi * r * r / spacing ** 2))
    k = np.arange(n_sphere) + 0.5
    z = 1.0 - 2.0 * k / n_sphere
    phi = np.pi * (1.0 + 5 ** 0.5) * k
    ring = np.sqrt(1.0 - z * z)
    sph_n = np.stack([ring * np.cos(phi), ring * np.sin(phi), z], axis=1)
    sph_p = c + r * sph_n
    # Slab: top and bottom faces of a 2 x 2 x 0.2 box centred at the origin (sides omitted: a demo).
    g = np.arange(-1.0 + spacing / 2, 1.0, spacing)
    gx, gy = np.meshgrid(g, g)
    top = np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, 0.1)], axis=1)
    bottom = top * [1, 1, -1]
    slab_p = np.concatenate([top, bottom])
    slab_n = np.concatenate([np.tile([0.0, 0.0, 1.0], (len(top), 1)), np.tile([0.0, 0.0, -1.0], (len(top), 1))])
    pos = np.concatenate([slab_p, sph_p])
    nrm = np.concatenate([slab_n, sph_n])
    part = np.concatenate([np.zeros(len(slab_p), int), np.ones(len(sph_p), int)])
    return pos, nrm, np.full(len(pos), spacing), part


def default_scene(spacing: float = 0.05) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, str]:
    """(positions (P, 3), normals (P, 3), radii (P,), part (P,), source) of the demo scene.

    ``spacing``: target sample spacing, model units.
    """
    try:
        from . import core  # type: ignore[attr-defined]
    except ImportError:
        pos, nrm, rad, part = fallback_scene(spacing)
        return pos, nrm, rad, part, "numpy fallback (surfeledit.core not built)"
    s = core.make_default_scene().sample(spacing=spacing)
    return (np.asarray(s.positions, np.float64), np.asarray(s.normals, np.float64),
            np.asarray(s.radii, np.float64), np.asarray(s.part), "surfeledit.core.make_default_scene()")


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m surfeledit.demo", description=__doc__.split("\n\n")[0])
    ap.add_argument("--domain", type=int, default=None, help="DDS domain (default: $SURFELEDIT_DOMAIN or 0)")
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--spacing", type=float, default=0.05, help="sample spacing, model units")
    ap.add_argument("--drop", type=float, default=0.03, help="downward translation per step, model units")
    args = ap.parse_args(argv)

    pos, nrm, rad, part, source = default_scene(args.spacing)
    print(f"scene: {len(pos)} surfels from {source}")
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
