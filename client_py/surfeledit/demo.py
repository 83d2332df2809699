"""Scripted demo: load the default scene, pin the slab, push the sphere down until it collides.

Runs twice: once with the back-off response (the sphere stops where it touches the slab) and once
with the merge response (the sphere is merged into the slab with a sharp crease), which ends with one
blend of the crease (the oriented particle blend tool). Each step line prints the colliding count and
what the response did (back-off: fraction kept; merge: feature surfels and the length of the
intersection curves); the blend prints its particles, energy and how the crease's normals changed.

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
from .results import Curve, StepResult


def default_scene(spacing: float = 0.05) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """positions (P, 3), normals (P, 3), radii (P,) float64 and part (P,) (0 slab, 1 sphere) of the
    demo scene from ``surfeledit.core.make_default_scene()``; ``spacing`` in model units."""
    from . import core

    s = core.make_default_scene().sample(spacing=spacing)
    return (np.asarray(s.positions, np.float64), np.asarray(s.normals, np.float64),
            np.asarray(s.radii, np.float64), np.asarray(s.part))


def sphere_sectors(positions: np.ndarray, part: np.ndarray, ids: np.ndarray, n: int) -> list:
    """The ids of the demo scene's sphere (``part`` 1) cut into ``n`` sectors by the angle around its centre in
    the x-y plane: ``n`` disjoint lists, one client's tool each (a tool's lock must not overlap another's)."""
    sphere = part == 1
    c = positions[sphere].mean(axis=0)
    angle = np.arctan2(positions[sphere, 1] - c[1], positions[sphere, 0] - c[0])
    k = np.minimum(((angle + np.pi) / (2 * np.pi) * n).astype(int), n - 1)
    return [ids[sphere][k == j].tolist() for j in range(n)]


def curve_length(curves: Sequence[Curve]) -> float:
    """Total length of intersection curves, model units (closed ones include the closing edge)."""
    total = 0.0
    for c in curves:
        pts = np.vstack([c.points, c.points[:1]]) if c.closed else c.points
        total += float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
    return total


def response_text(r: StepResult, session: object) -> str:
    """What the response of one step did, in a few words."""
    if r.response == "backed_off":
        return f"backed off: kept {r.backoff.kept:.2f} of the step, depth {r.backoff.final_depth:.4f}"
    if r.response == "merged":
        curves = session.intersection_curves()  # type: ignore[attr-defined]
        return (f"merged: {r.features.size} feature surfels, {len(curves)} curve(s) "
                f"{curve_length(curves):.3f} long")
    return r.response


def crease_angle(session: object, ids: np.ndarray, spacing: float) -> float:
    """95th percentile of the angles (degrees) between the normals of two of `ids`' surfels closer than 1.5
    spacings (the largest is a single outlier at the region's corners)."""
    st = session.state()  # type: ignore[attr-defined]
    rows = np.flatnonzero(np.isin(st.ids, ids))
    p, n = st.positions[rows], st.normals[rows]
    close = np.linalg.norm(p[:, None] - p[None], axis=2) < 1.5 * spacing
    np.fill_diagonal(close, False)
    cos = np.clip((n @ n.T)[close], -1.0, 1.0)
    return float(np.degrees(np.percentile(np.arccos(cos), 95))) if cos.size else 0.0


def blend_once(session: object, iterations: int = 30) -> None:
    """One blend of the last merge's crease (only along the normals, so the blend adds material), and a
    few lines on what it did."""
    spacing = float(np.median(session.state().radii))  # type: ignore[attr-defined]
    t0 = time.perf_counter()
    b = session.blend(iterations=iterations, only_grow=True)  # type: ignore[attr-defined]
    rt = (time.perf_counter() - t0) * 1e3
    after = crease_angle(session, b.moved, spacing)
    session.undo()  # type: ignore[attr-defined]
    before = crease_angle(session, b.moved, spacing)
    session.redo()  # type: ignore[attr-defined]
    print(f"blend: {b.particles} particles, {iterations} iterations ({b.substeps} sub-steps) in {b.ms:.1f} ms "
          f"(round trip {rt:.1f} ms); {b.removed.size} crease copies removed, {b.inserted.size} inserted")
    print(f"blend: energy {b.energy[0]:.1f} -> {b.energy[-1]:.1f}; 95th percentile of the normal angles between neighbours "
          f"in the blend region {before:.0f} -> {after:.0f} degrees")


def run(client: object, response: str, pos: np.ndarray, nrm: np.ndarray, rad: np.ndarray, part: np.ndarray,
        steps: int, drop: float) -> None:
    """One session with ``response``: the sphere pushed ``steps`` x ``drop`` down, one line per step."""
    with client.open_session(f"demo-{response}-{client.client_id}") as session:  # type: ignore[attr-defined]
        t0 = time.perf_counter()
        session.load_points(pos, nrm, rad)
        ids = session.ids()  # ascending ids, assigned in upload order
        session.set_regions(zero=ids[part == 0], one=ids[part == 1])
        session.configure(response=response)
        print(f"\nresponse={response} (loaded in {(time.perf_counter() - t0) * 1e3:.1f} ms)")
        print(f"{'seq':>4} {'version':>8} {'moved':>8} {'colliding':>9} {'step ms':>9} {'rt ms':>9}  response")
        for _ in range(steps):
            r = session.deform(translation=(0.0, 0.0, -drop))
            print(f"{r.seq:>4} {r.version:>8} {r.moved:>8} {r.colliding.size:>9} "
                  f"{r.timings.get('total', float('nan')):>9.2f} {r.round_trip_ms:>9.2f}  {response_text(r, session)}")
        if response == "merge":
            blend_once(session)
        st = session.state()
        sphere = np.isin(st.ids, ids[part == 1])
        clipped = 0 if st.clips is None else int(np.any(st.clips[:, 3:] != 0, axis=1).sum())
        print(f"sphere lowest z: {st.positions[sphere, 2].min():.3f}; {len(st)} surfels, {clipped} clipped")
        held = session.info()
        parts = ", ".join(f"{s.name} {s.bytes / 1024:.0f} KiB" for s in held.structures)
        print(f"session holds {held.surfels} surfels, {held.bytes_per_surfel:.1f} bytes/surfel ({parts})")


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m surfeledit.demo", description=__doc__.split("\n\n")[0])
    ap.add_argument("--domain", type=int, default=None, help="DDS domain (default: $SURFELEDIT_DOMAIN or 0)")
    ap.add_argument("--steps", type=int, default=16)
    ap.add_argument("--spacing", type=float, default=0.05, help="sample spacing, model units")
    ap.add_argument("--drop", type=float, default=0.03, help="downward translation per step, model units")
    ap.add_argument("--responses", default="backoff,merge", help="comma-separated responses, one run each")
    args = ap.parse_args(argv)

    pos, nrm, rad, part = default_scene(args.spacing)
    print(f"scene: {len(pos)} surfels (a rigid slab and a sphere above it, spacing {args.spacing})")
    with connect(domain=args.domain, spawn=True) as client:
        info = client.info()
        print(f"server {info.version} on domain {client.domain}, max_chunk_surfels={info.max_chunk_surfels}")
        for response in args.responses.split(","):
            run(client, response.strip(), pos, nrm, rad, part, args.steps, args.drop)
    return 0


if __name__ == "__main__":
    sys.exit(main())
