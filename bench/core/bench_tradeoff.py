"""The speed/accuracy trade study (issue 5): every session setting that trades accuracy for speed,
swept on the scenario runner's scenes with exact truth, in-process, one thread.

Swept on every scene (a representative subset of the product of settings, not all of it -- see configs()):
  - the four algorithms (simple, improved, temporal, robust), no tree;
  - hierarchy kinds: zero tree AABB / OBB (SAT lite and full) / sphere / sphere cluster trees
    (hierarchical, incremental), alone and with a deformable AABB tree;
  - simplification: hierarchical and region growing at cluster sizes 1, 4, 18, 50, 100, 200
    (member_margin 0 = the thesis; margin 1 at a few sizes), robust and temporal;
  - knn_eps 0, 0.1, 0.5, 1, 2 (robust; simple at 0.5 and 2);
  - the inside/outside threshold W at 0 and +-0.5 spacing (robust, simple);
  - sphere_margin 0, 0.5, 1 (robust).
For each run: median / 90th percentile of the step time (deform + detect, in-process) and of the
detector alone, preprocessing, and precision / recall / F1 against the scene's exact truth summed over
all steps (TP, FP, FN over the judged surfels). Writes a summary CSV and a per-step CSV under --out
and the Pareto plot (median step time vs F1, one panel per scene) to --png.

Then the recommended GUI setting (the fastest configuration within 0.01 F1 of exact Robust on
piercing, or --gui) and exact Robust are run on a ~1M-surfel piercing (scale 4.8), 1 and all threads.
Last, the configurations of the thesis's Figs. 9.2, 9.3, 9.5-9.7 on piercing (figures.csv).

    .venv/bin/python bench/core/bench_tradeoff.py [--scenes piercing:1.0,cup:1.0,concave:1.0]
        [--out bench/out/tradeoff] [--png bench/tradeoff_pareto.png] [--big-scale 4.8] [--quick] [--figures-only]
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from pathlib import Path
from typing import Any, Dict, List, Tuple

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import benchlib  # noqa: E402

from surfeledit import scenario as S  # noqa: E402

AA = dict(zero_hierarchy="aabb", deformable_hierarchy="aabb")


def configs(spacing: float, full: bool) -> List[Tuple[str, str, str, Dict[str, Any]]]:
    """(family, label, algorithm, settings). ``full`` = the whole sweep (else --quick's subset:
    algorithms, two hierarchies, simplification at 1/18/100, eps 0.5/2, W, margins)."""
    out: List[Tuple[str, str, str, Dict[str, Any]]] = []
    for alg in ("simple", "improved", "temporal", "robust"):
        out.append(("algorithm", f"{alg}", alg, {}))
    hier = [
        ("robust AABB", dict(zero_hierarchy="aabb")),
        ("robust AABB-AABB hybrid", dict(AA, update="hybrid", hybrid_f=0.5)),
        ("robust OBB lite", dict(zero_hierarchy="obb", sat="lite")),
        ("robust OBB-AABB lite", dict(zero_hierarchy="obb", deformable_hierarchy="aabb", sat="lite")),
        ("robust OBB-AABB full", dict(zero_hierarchy="obb", deformable_hierarchy="aabb", sat="full")),
        ("robust sphere", dict(zero_hierarchy="sphere")),
        ("robust sphere_hierarchical", dict(zero_hierarchy="sphere_hierarchical")),
        ("robust sphere_incremental", dict(zero_hierarchy="sphere_incremental")),
        ("robust sphere_hier.-AABB", dict(zero_hierarchy="sphere_hierarchical", deformable_hierarchy="aabb")),
    ]
    if not full:
        hier = hier[:1] + hier[6:7]
    for label, cfg in hier:
        out.append(("hierarchy", label, "robust", cfg))
    if full:
        out.append(("hierarchy", "simple AABB-AABB hybrid", "simple", dict(AA, update="hybrid", hybrid_f=0.5)))
    sizes = (1, 4, 18, 50, 100, 200) if full else (1, 18, 100)
    for method in ("hierarchical", "region_growing"):
        for n in sizes:
            out.append(("simplify", f"robust {method} {n}", "robust",
                        dict(simplify=method, cluster_size=n, member_margin=0.0)))
    more = [(18, "hierarchical"), (100, "hierarchical")] if full else [(18, "hierarchical")]
    for n, method in more:
        out.append(("simplify", f"robust {method} {n} margin 1", "robust",
                    dict(simplify=method, cluster_size=n, member_margin=1.0)))
        out.append(("simplify", f"temporal {method} {n}", "temporal",
                    dict(simplify=method, cluster_size=n, member_margin=0.0)))
    for eps in ((0.1, 0.5, 1.0, 2.0) if full else (0.5, 2.0)):
        out.append(("knn_eps", f"robust eps {eps:g}", "robust", dict(knn_eps=eps)))
    for eps in ((0.5, 2.0) if full else ()):
        out.append(("knn_eps", f"simple eps {eps:g}", "simple", dict(knn_eps=eps)))
    if full:  # combinations: the cheapest exact-ish detector with the cheapest search, and with clusters
        out.append(("knn_eps", "temporal eps 2", "temporal", dict(knn_eps=2.0)))
        out.append(("knn_eps", "robust hierarchical 18 eps 2", "robust",
                    dict(simplify="hierarchical", cluster_size=18, member_margin=0.0, knn_eps=2.0)))
    for alg in ("robust", "simple"):
        for w in (-0.5, 0.5):
            out.append(("threshold", f"{alg} W {w:+g}h", alg, dict(threshold=w * spacing)))
    for m in (0.0, 1.0):
        out.append(("sphere_margin", f"robust sphere_margin {m:g}", "robust", dict(sphere_margin=m)))
    return out


def run_one(sc, alg: str, cfg: Dict[str, Any], threads: int = 1, measure: bool = True) -> Dict[str, Any]:
    res = S.run(sc, alg, backend=S.LocalBackend(threads), settings=dict(threads=threads, **cfg), measure=measure)
    recs = res.records
    step = [r.step_ms for r in recs]
    det = [r.detect_ms for r in recs]
    tp = sum(r.tp for r in recs)
    fp = sum(r.fp for r in recs)
    fn = sum(r.fn for r in recs)
    precision = tp / (tp + fp) if tp + fp else 1.0
    recall = tp / (tp + fn) if tp + fn else 1.0
    f1 = 2 * precision * recall / (precision + recall) if precision + recall else 0.0
    return dict(median_step_ms=benchlib.median(step), p90_step_ms=benchlib.percentile(step, 0.9),
                median_detect_ms=benchlib.median(det), p90_detect_ms=benchlib.percentile(det, 0.9),
                preprocess_ms=recs[0].preprocess_ms, precision=precision, recall=recall, f1=f1,
                min_recall=min(r.recall for r in recs), queries=sum(r.queries for r in recs),
                surfels=recs[-1].surfels, tp=tp, fp=fp, fn=fn, result=res)


def pareto(rows: List[Dict[str, Any]]) -> List[Dict[str, Any]]:
    """Rows no other row beats in both median step time (lower) and F1 (higher), by time."""
    front, best = [], -1.0
    for r in sorted(rows, key=lambda r: (r["median_step_ms"], -r["f1"])):
        if r["f1"] > best + 1e-12:
            front.append(r)
            best = r["f1"]
    return front


def plot(path: Path, by_scene: Dict[str, List[Dict[str, Any]]]) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker  # noqa: F401 (tick labels)
    families = ["algorithm", "hierarchy", "simplify", "knn_eps", "threshold", "sphere_margin"]
    colours = dict(zip(families, ["black", "tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple"]))
    fig, axes = plt.subplots(1, len(by_scene), figsize=(6.2 * len(by_scene), 5.2), squeeze=False)
    for ax, (scene, rows) in zip(axes[0], by_scene.items()):
        for fam in families:
            pts = [r for r in rows if r["family"] == fam]
            if pts:
                ax.scatter([r["median_step_ms"] for r in pts], [r["f1"] for r in pts], s=22, c=colours[fam],
                           label=fam, alpha=0.8)
        front = pareto(rows)
        ax.plot([r["median_step_ms"] for r in front], [r["f1"] for r in front], "k--", lw=1, label="Pareto front")
        for r in front:
            ax.annotate(r["label"], (r["median_step_ms"], r["f1"]), fontsize=6, xytext=(3, -8),
                        textcoords="offset points")
        ax.set_xscale("log")
        ax.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
        ax.set_xlabel("median step time, ms (deform + detect, 1 thread)")
        ax.set_ylabel("F1 vs exact truth (all steps)")
        ax.set_title(f"{scene} ({rows[0]['surfels']:,} surfels)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


# Thesis Figs. 9.2/9.3 (exact vs simplified, clusters of ~18), 9.5/9.6 (sphere cluster trees of ~120
# surfels per leaf vs AABB, with and without a deformable AABB tree), 9.7 (OBB vs sphere cluster tree,
# at most 175 surfels per leaf box): (figure, label, algorithm, settings).
FIGURES = [
    ("9.2/9.3", "temporal exact", "temporal", {}),
    ("9.2/9.3", "temporal hierarchical 18", "temporal", dict(simplify="hierarchical", cluster_size=18, member_margin=0.0)),
    ("9.2/9.3", "temporal incremental 18", "temporal", dict(simplify="region_growing", cluster_size=18, member_margin=0.0)),
    ("9.2/9.3", "robust exact", "robust", {}),
    ("9.2/9.3", "robust hierarchical 18", "robust", dict(simplify="hierarchical", cluster_size=18, member_margin=0.0)),
    ("9.2/9.3", "robust incremental 18", "robust", dict(simplify="region_growing", cluster_size=18, member_margin=0.0)),
    ("9.5-9.7", "AABB - Surfels", "robust", dict(zero_hierarchy="aabb", leaf_max_surfels=175)),
    ("9.5-9.7", "AABB - AABB", "robust", dict(AA, leaf_max_surfels=175)),
    ("9.5-9.7", "OBB - Surfels", "robust", dict(zero_hierarchy="obb", leaf_max_surfels=175)),
    ("9.5-9.7", "OBB - AABB", "robust", dict(zero_hierarchy="obb", deformable_hierarchy="aabb", leaf_max_surfels=175)),
    ("9.5-9.7", "Hierarchical - Surfels", "robust", dict(zero_hierarchy="sphere_hierarchical", cluster_size=120)),
    ("9.5-9.7", "Hierarchical - AABB", "robust",
     dict(zero_hierarchy="sphere_hierarchical", deformable_hierarchy="aabb", cluster_size=120)),
    ("9.5-9.7", "Incr. - Surfels", "robust", dict(zero_hierarchy="sphere_incremental", cluster_size=120)),
    ("9.5-9.7", "Incr. - AABB", "robust",
     dict(zero_hierarchy="sphere_incremental", deformable_hierarchy="aabb", cluster_size=120)),
]


def figures(scale: float, out: Path) -> None:
    """The thesis figures' configurations on piercing: per-step detect time and colliding counts."""
    sc = S.make_scenario("piercing", scale=scale, seed=1)
    print(f"\n## Thesis Figs. 9.2, 9.3, 9.5-9.7 configurations: piercing scale {scale}, one thread", flush=True)
    rows = []
    for fig, label, alg, cfg in FIGURES:
        r = run_one(sc, alg, cfg)
        res = r.pop("result")
        det = [x.detect_ms for x in res.records]
        col = [x.colliding for x in res.records]
        rows.append([fig, label] + [f"{d:.3f}" for d in det] + col)
        print(f"{fig:8s} {label:26s} detect median {np.median(det):7.2f} ms, first 10 steps {np.median(det[:10]):7.2f}, "
              f"last 10 {np.median(det[-10:]):7.2f}, max {max(det):7.2f}; prep {r['preprocess_ms']:7.1f} ms; "
              f"colliding at steps 10/20/30/40/50: {[col[k] for k in (9, 19, 29, 39, 49) if k < len(col)]}; "
              f"F1 {r['f1']:.4f}", flush=True)
    with open(out / "figures.csv", "w", newline="") as f:
        w = csv.writer(f)
        n = sc.steps
        w.writerow(["figure", "label"] + [f"detect_ms_{k}" for k in range(1, n + 1)] +
                   [f"colliding_{k}" for k in range(1, n + 1)])
        w.writerows(rows)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="piercing:1.0,cup:1.0,concave:1.0", help="name:scale,... (the GUI check uses the first)")
    ap.add_argument("--out", default="bench/out/tradeoff")
    ap.add_argument("--png", default="bench/tradeoff_pareto.png")
    ap.add_argument("--big-scale", type=float, default=4.8, help="piercing scale of the ~1M-surfel GUI check (0 = skip)")
    ap.add_argument("--gui", default="", help="labels (comma-separated) of GUI settings to time at 1M "
                    "(default: the chosen one)")
    ap.add_argument("--quick", action="store_true", help="subset sweep on every scene")
    ap.add_argument("--figures-only", action="store_true", help="only the thesis figures' configurations")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(benchlib.machine_line(), flush=True)
    t_all = time.perf_counter()
    if args.figures_only:
        figures(1.0, out)
        print(f"total {time.perf_counter() - t_all:.0f} s; {benchlib.load_average()}")
        return 0
    by_scene: Dict[str, List[Dict[str, Any]]] = {}
    all_cfgs: Dict[str, Tuple[str, str, str, Dict[str, Any]]] = {}
    step_rows = []
    for i, item in enumerate(args.scenes.split(",")):
        name, scale = item.split(":")
        sc = S.make_scenario(name, scale=float(scale), seed=1)
        full = not args.quick
        rows = []
        print(f"\n## {name} scale {scale}: {len(sc.scene.positions):,} surfels, {sc.steps} steps", flush=True)
        for fam, label, alg, cfg in configs(sc.scene.spacing, full):
            all_cfgs[label] = (fam, label, alg, cfg)
            t0 = time.perf_counter()
            r = run_one(sc, alg, cfg)
            res = r.pop("result")
            r.update(scene=name, scale=float(scale), family=fam, label=label, algorithm=alg, settings=json.dumps(cfg))
            rows.append(r)
            for rec in res.records:
                step_rows.append([name, label, rec.step, f"{rec.step_ms:.4f}", f"{rec.detect_ms:.4f}", rec.colliding,
                                  rec.queries, rec.tp, rec.fp, rec.fn])
            print(f"{label:38s} step {r['median_step_ms']:8.2f} ms (p90 {r['p90_step_ms']:8.2f})  detect "
                  f"{r['median_detect_ms']:8.2f}  prep {r['preprocess_ms']:8.1f}  P {r['precision']:.4f}  "
                  f"R {r['recall']:.4f}  F1 {r['f1']:.4f}  [{time.perf_counter() - t0:.0f} s]", flush=True)
        by_scene[name] = rows
        print("Pareto front:", "; ".join(f"{r['label']} ({r['median_step_ms']:.1f} ms, F1 {r['f1']:.4f})"
                                         for r in pareto(rows)), flush=True)
    fields = ["scene", "scale", "family", "label", "algorithm", "settings", "surfels", "median_step_ms", "p90_step_ms",
              "median_detect_ms", "p90_detect_ms", "preprocess_ms", "precision", "recall", "f1", "min_recall",
              "queries", "tp", "fp", "fn"]
    with open(out / "summary.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(fields)
        for rows in by_scene.values():
            for r in rows:
                w.writerow([f"{r[k]:.6g}" if isinstance(r[k], float) else r[k] for k in fields])
    with open(out / "steps.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["scene", "label", "step", "step_ms", "detect_ms", "colliding", "queries", "tp", "fp", "fn"])
        w.writerows(step_rows)
    plot(Path(args.png), by_scene)
    print(f"\nwrote {out / 'summary.csv'}, {out / 'steps.csv'}, {args.png}; sweep {time.perf_counter() - t_all:.0f} s",
          flush=True)

    if args.big_scale > 0:
        first = next(iter(by_scene.values()))
        exact = next(r for r in first if r["label"] == "robust")
        ok = [r for r in first if r["f1"] >= exact["f1"] - 0.01]
        chosen = min(ok, key=lambda r: r["median_step_ms"])["label"]
        labels = [chosen] + [x for x in args.gui.split(",") if x and x != chosen]
        big = S.make_scenario("piercing", scale=args.big_scale, seed=1)
        print(f"\n## GUI check: piercing scale {args.big_scale}: {len(big.scene.positions):,} surfels; "
              f"chosen setting '{chosen}', then {labels[1:]} and exact robust", flush=True)
        for lab in dict.fromkeys(labels + ["robust"]):
            _, _, alg, cfg = all_cfgs[lab]
            for threads in (1, 0):
                r = run_one(big, alg, cfg, threads=threads)
                r.pop("result")
                print(f"{lab:38s} threads {threads or 'all'}: step median {r['median_step_ms']:.2f} ms "
                      f"(p90 {r['p90_step_ms']:.2f}), detect median {r['median_detect_ms']:.2f} ms, prep "
                      f"{r['preprocess_ms']:.0f} ms, P {r['precision']:.4f} R {r['recall']:.4f} F1 {r['f1']:.4f}, "
                      f"{r['surfels']:,} surfels", flush=True)
    figures(1.0, out)
    print(f"total {time.perf_counter() - t_all:.0f} s; {benchlib.load_average()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
