"""Collision detection with bounding volume hierarchies on scene 1 (the scenario runner's
``piercing`` at full size: ~210k surfels, ~60k deformable, 50 steps), in-process, one thread, all
configurations side by side in one run (thesis Figs. 8.8-8.12, Table 10.1):

1. update strategies of the deformable AABB tree over f (Fig. 8.8), zero tree AABB;
2. zero tree AABB vs OBB (SAT lite / full) vs sphere, without (surfel/tree) and with a deformable
   tree (tree/tree), with the counters Nv, Np, Nu of Eq. 8.11 (Figs. 8.9-8.11);
3. extended variants (Fig. 8.12);
4. preprocessing (Table 10.1): tree builds, whole reset;
5. against Robust (and Simple) without a tree; a step with no collision (the steps before contact).
Every configuration's colliding set is checked against the same algorithm without a tree.

    .venv/bin/python bench/core/bench_hierarchies.py [--scale 1.0] [--out bench/out/hierarchies]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402

from surfeledit import scenario as S  # noqa: E402

AA = dict(zero_hierarchy="aabb", deformable_hierarchy="aabb")
CONFIGS = [
    ("robust", "no tree", {}),
    ("simple", "no tree", {}),
    # 1. update strategies (AABB-AABB)
    ("robust", "AABB-AABB bottom_up", dict(AA, update="bottom_up")),
    ("robust", "AABB-AABB hybrid f=0.25", dict(AA, update="hybrid", hybrid_f=0.25)),
    ("robust", "AABB-AABB hybrid f=0.5", dict(AA, update="hybrid", hybrid_f=0.5)),
    ("robust", "AABB-AABB hybrid f=0.75", dict(AA, update="hybrid", hybrid_f=0.75)),
    ("robust", "AABB-AABB top_down", dict(AA, update="top_down")),
    # 2. zero kinds, surfel/tree
    ("robust", "AABB zero, surfel/tree", dict(zero_hierarchy="aabb")),
    ("robust", "OBB zero, surfel/tree", dict(zero_hierarchy="obb")),
    ("robust", "sphere zero, surfel/tree", dict(zero_hierarchy="sphere")),
    # 2. zero kinds, tree/tree (hybrid f=0.5)
    ("robust", "OBB-AABB SAT lite", dict(zero_hierarchy="obb", deformable_hierarchy="aabb", sat="lite")),
    ("robust", "OBB-AABB SAT full", dict(zero_hierarchy="obb", deformable_hierarchy="aabb", sat="full")),
    ("robust", "sphere-AABB", dict(zero_hierarchy="sphere", deformable_hierarchy="aabb")),
    ("simple", "AABB-AABB (simple narrow)", dict(AA)),
    # 3. extended
    ("robust", "AABB-AABB extended", dict(AA, extended=True)),
    ("robust", "OBB-AABB extended", dict(zero_hierarchy="obb", deformable_hierarchy="aabb", extended=True)),
]


def run(sc, alg, cfg):
    b = S.LocalBackend(1)
    b.start(sc.scene)
    t0 = time.perf_counter()
    b.configure(algorithm=alg, threads=1, **cfg)
    configure_ms = (time.perf_counter() - t0) * 1e3
    h = b.session.hierarchy()
    # Idle steps first: nothing moves and nothing collides yet (the detector was just reset); the
    # piercing scene itself touches from its first step, so these are its steps with no collision.
    idle = [b.session.deform().stats["detect_ms"] for _ in range(20)]
    b.configure(algorithm=alg, threads=1, **cfg)  # back to the reset state for the scenario
    params = sc.step_params()
    outs = [b.deform(**params) for _ in range(sc.steps)]
    rebuild_ms = float("nan")
    if cfg.get("deformable_hierarchy") == "aabb":
        # Rebuild on idle: the finished tree is picked up by a later step (idle steps: no motion).
        assert b.session.rebuild()
        while b.session.hierarchy()["last_rebuild_ms"] == 0.0:
            time.sleep(0.002)
            b.session.deform()
        rebuild_ms = b.session.hierarchy()["last_rebuild_ms"]
    return dict(outs=outs, h=h, idle=idle, configure_ms=configure_ms, rebuild_ms=rebuild_ms,
                bytes={k: v for k, v in b.session.report()["structures"].items() if k.startswith("bvh_")})


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scale", type=float, default=1.0)
    ap.add_argument("--out", default="bench/out/hierarchies")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    sc = S.make_scenario("piercing", scale=a.scale)
    s = sc.scene
    print(benchlib.machine_line())
    print(f"load at start: {benchlib.load_average()}")
    print(f"\nScene 1 (piercing, scale {a.scale}): {s.size} surfels, {len(s.zero)} zero, {len(s.deformable)} deformable, "
          f"{sc.steps} steps, 1 thread\n")
    ref = {}
    rows = []
    csv = ["algorithm,config,step,detect_ms,colliding,nv,np,nu,queries"]
    for alg, name, cfg in CONFIGS:
        r = run(sc, alg, cfg)
        outs = r["outs"]
        cols = [np.sort(np.asarray(o.colliding)) for o in outs]
        if not cfg:
            ref[alg] = cols
        base = ref["robust" if cfg.get("extended") else alg]
        same = sum(np.array_equal(x, y) for x, y in zip(cols, base))
        det = np.array([o.stats["detect_ms"] for o in outs])
        col = np.array([len(c) for c in cols])
        pre = np.array(r["idle"])
        st = {k: np.array([o.stats[k] for o in outs]) for k in ("nv", "np", "nu", "queries")}
        for k, o in enumerate(outs, 1):
            csv.append(f"{alg},{name},{k},{o.stats['detect_ms']:.4f},{len(o.colliding)},{int(o.stats['nv'])},"
                       f"{int(o.stats['np'])},{int(o.stats['nu'])},{int(o.stats['queries'])}")
        h = r["h"]
        rows.append([alg, name, f"{np.median(det):.3f}", f"{det.max():.3f}",
                     f"{np.median(pre):.3f}" if len(pre) else "-", f"{int(np.median(st['nv'])):,}",
                     f"{int(np.median(st['np'])):,}", f"{int(np.median(st['nu'])):,}", f"{int(np.median(st['queries'])):,}",
                     f"{h['zero_build_ms']:.1f}" if h["status"] else "-",
                     f"{h['deformable_build_ms']:.1f}" if h["deformable_build_ms"] else "-",
                     f"{outs[0].stats['preprocess_ms']:.1f}",
                     f"{r['rebuild_ms']:.1f}" if r["rebuild_ms"] == r["rebuild_ms"] else "-",
                     f"{int(col.max())}", f"{same}/{len(outs)}"])
        print("| " + " | ".join(rows[-1]) + " |", flush=True)
    print()
    print(benchlib.table(["algorithm", "configuration", "detect median ms", "detect max ms",
                          "idle step (no collision) median ms", "Nv median", "Np median", "Nu median", "queries median",
                          "zero tree build ms", "deformable tree build ms", "whole reset ms",
                          "background rebuild ms", "peak colliding", "steps equal to no tree"], rows))
    print(f"\nload at end: {benchlib.load_average()}")
    (out / "hierarchies.csv").write_text("\n".join(csv) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
