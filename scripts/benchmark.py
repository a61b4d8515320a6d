#!/usr/bin/env python
"""Benchmark every registered hole filter against MeshLab's Close Holes on holes with ground truth.

Cuts holes of four size classes (small ~20, medium ~60, large ~150 and irregular ~250 boundary
edges) into closed meshes (pymeshlab's bunny.obj and bone.ply, an analytic sphere and torus),
fills them with each filter and with ``meshing_close_holes`` (default, and with a
``maxholesize`` covering every hole), and prints one table per filter. Also times the
three-hole case on a ~200k-face mesh.

    .venv/bin/python scripts/benchmark.py [--filters a,b] [--out bench_out] [--seed 0] [--skip-speed]
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np
import pymeshlab

import meshlab_holefill
from meshlab_holefill.compare import (assign_patches, compact_mesh, cut_holes, mesh_checks, patch_metrics)
from meshlab_holefill.registry import apply_filter

SAMPLES = os.path.join(os.path.dirname(pymeshlab.__file__), "tests", "sample_meshes")
BASELINE = "meshing_close_holes"


def load_case(name):
    """Closed test meshes: (V, F) float64 / int64."""
    ms = pymeshlab.MeshSet()
    if name == "sphere":
        ms.create_sphere(subdiv=6)
    elif name == "torus":
        ms.create_torus(hradius=1.0, vradius=0.4, hsubdiv=192, vsubdiv=96)
    else:
        ms.load_new_mesh(os.path.join(SAMPLES, name))
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)


CASES = {
    "bunny.obj": ("small", "medium", "large", "irregular"),
    "bone.ply": ("small", "medium"),
    "sphere": ("small", "medium", "large", "irregular"),
    "torus": ("small", "medium", "large", "irregular"),
}


def fillers(selected=None):
    """(label, filter name, params) for every registered filter plus the baseline twice."""
    out = [(name, name, {}) for name in meshlab_holefill.filter_list()]
    out += [(f"{BASELINE} (default)", BASELINE, {}), (f"{BASELINE} (all holes)", BASELINE, {"maxholesize": 100000})]
    if selected:
        out = [row for row in out if row[1] in selected or row[0] in selected]
    return out


def run_case(case, sizes, seed, filter_rows):
    V, F = load_case(case)
    F_cut, holes = cut_holes(V, F, sizes=sizes, seed=seed)
    V0, F0 = compact_mesh(V, F_cut)
    used = np.unique(F_cut.ravel())
    remap = np.full(len(V), -1, np.int64)
    remap[used] = np.arange(len(used))
    diag = float(np.linalg.norm(V0.max(axis=0) - V0.min(axis=0)))
    loops, truths = [], []
    for h in holes:
        hv = np.unique(h.removed_faces.ravel())
        loops.append(remap[hv[remap[hv] >= 0]])
        truths.append(compact_mesh(V, h.removed_faces))
    rows = []
    for label, name, params in filter_rows:
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V0, face_matrix=F0.astype(np.int32)), case)
        t0 = time.perf_counter()
        try:
            apply_filter(ms, name, **params)
            error = None
        except Exception as exc:  # a benchmark reports a crashing filter instead of stopping
            error = f"{type(exc).__name__}: {exc}"
        seconds = time.perf_counter() - t0
        m = ms.current_mesh()
        V1, F1 = np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)
        checks = mesh_checks(V0, F0, V1, F1)
        patches = assign_patches(F1[len(F0):], loops)
        from meshlab_holefill.holes import boundary_halfedges

        he, _ = boundary_halfedges(F1)
        for h, hole in enumerate(holes):
            open_left = bool(np.isin(he, loops[h]).all(axis=1).any())
            pf = F1[len(F0):][patches[h]]
            metrics = patch_metrics(V0, F0, V1, pf, loops[h], truths[h], diag) if len(pf) else {}
            metrics.pop("quality_values", None)
            rows.append({"case": case, "filter": label, "size": hole.size_class,
                         "boundary_edges": hole.boundary_edges, "closed": (not open_left) and len(pf) > 0,
                         "error": error, "run_seconds": seconds, **checks, **metrics})
    return rows


def summarize(rows):
    """One table per filter: rows = size classes (all cases pooled)."""
    lines = []
    filters = list(dict.fromkeys(r["filter"] for r in rows))
    header = ("| size | holes closed | dist patch->GT mean / max (permille) | GT->patch mean | quality mean / min / >=0.7 "
              "| edge ratio | intersecting new faces | originals changed | seconds per run |")
    for f in filters:
        lines += [f"\n**{f}**\n", header, "|" + "---|" * 9]
        fr = [r for r in rows if r["filter"] == f]
        for size in ["small", "medium", "large", "irregular", "all"]:
            sr = fr if size == "all" else [r for r in fr if r["size"] == size]
            if not sr:
                continue
            closed = [r for r in sr if r["closed"]]

            def mean(key, rs=closed):
                vals = [r[key] for r in rs if r.get(key) is not None]
                return float(np.mean(vals)) if vals else float("nan")

            def mx(key, rs=closed):
                vals = [r[key] for r in rs if r.get(key) is not None]
                return float(np.max(vals)) if vals else float("nan")

            def mn(key, rs=closed):
                vals = [r[key] for r in rs if r.get(key) is not None]
                return float(np.min(vals)) if vals else float("nan")

            runs = {(r["case"]): r for r in sr}
            lines.append(
                f"| {size} | {len(closed)}/{len(sr)} | {mean('dist_patch_to_gt_mean_permille'):.3f} / "
                f"{mx('dist_patch_to_gt_max_permille'):.3f} | {mean('dist_gt_to_patch_mean_permille'):.3f} | "
                f"{mean('quality_mean'):.3f} / {mn('quality_min'):.3f} / {mean('quality_share07'):.2f} | "
                f"{mean('edge_ratio'):.2f} | {sum(r['intersecting_new_faces'] for r in runs.values())} | "
                f"{sum(r['originals_changed'] for r in runs.values())} | "
                f"{np.mean([r['run_seconds'] for r in runs.values()]):.3f} |")
    return "\n".join(lines)


def speed_case(filter_names, seed=0):
    """Three holes (~50, ~200, ~250 boundary edges) in a ~200k-face mesh: seconds per filter beyond loading."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(SAMPLES, "bunny.obj"))
    ms.meshing_surface_subdivision_loop(iterations=1, threshold=pymeshlab.PercentageValue(0))
    m = ms.current_mesh()
    V, F = np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)
    from meshlab_holefill import compare

    saved = dict(compare.SIZE_CLASSES)
    compare.SIZE_CLASSES.update({"s50": 50, "s200": 200, "s250": 250})
    try:
        F_cut, holes = cut_holes(V, F, sizes=("s50", "s200", "s250"), seed=seed)
    finally:
        compare.SIZE_CLASSES.clear()
        compare.SIZE_CLASSES.update(saved)
    V0, F0 = compact_mesh(V, F_cut)
    out = {"faces": int(len(F0)), "hole_edges": [h.boundary_edges for h in holes]}
    for name in filter_names:
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V0, face_matrix=F0.astype(np.int32)), "big")
        t0 = time.perf_counter()
        res = apply_filter(ms, name, **({"maxholesize": 100000} if name == BASELINE else {}))
        out[name] = {"seconds": time.perf_counter() - t0, "closed_holes": res.get("closed_holes")}
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--filters", default="", help="comma-separated filter names (default: all + baseline)")
    ap.add_argument("--out", default="bench_out")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--skip-speed", action="store_true")
    ap.add_argument("--update-readme", action="store_true",
                    help="replace the README's Results section with this run's tables")
    args = ap.parse_args(argv)
    selected = [s for s in args.filters.split(",") if s]
    rows_f = fillers(selected)
    rows = []
    for case in args.cases.split(","):
        t0 = time.perf_counter()
        rows += run_case(case, CASES[case], args.seed, rows_f)
        print(f"# {case}: {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "benchmark.json"), "w") as fh:
        json.dump(rows, fh, indent=1, default=float)
    text = summarize(rows)
    if not args.skip_speed:
        names = [n for n in dict.fromkeys(r[1] for r in rows_f)]
        speed = speed_case(names, args.seed)
        text += (f"\n\n**Speed**: {speed['faces']} faces, holes of {speed['hole_edges']} boundary edges; "
                 "seconds to fill all three (beyond loading):\n\n| filter | seconds | closed |\n|---|---|---|\n")
        text += "\n".join(f"| {n} | {speed[n]['seconds']:.3f} | {speed[n]['closed_holes']} |" for n in names)
    command = "scripts/benchmark.py " + " ".join(argv if argv is not None else sys.argv[1:])
    text = (f"Measured by `.venv/bin/python {command.strip()}` on {time.strftime('%Y-%m-%d')} "
            f"({os.cpu_count()} cores). Distances in per mille of the bounding-box diagonal.\n" + text)
    with open(os.path.join(args.out, "benchmark.md"), "w") as fh:
        fh.write(text + "\n")
    if args.update_readme:
        update_readme(text)
    print(text)


def update_readme(text, path=os.path.join(os.path.dirname(__file__), "..", "README.md")):
    """Replace what stands between the README's results markers."""
    with open(path) as fh:
        readme = fh.read()
    start, end = "<!-- results:start -->", "<!-- results:end -->"
    head, rest = readme.split(start, 1)
    _, tail = rest.split(end, 1)
    with open(path, "w") as fh:
        fh.write(head + start + "\n" + text.strip() + "\n" + end + tail)


if __name__ == "__main__":
    main()
