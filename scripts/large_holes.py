"""Large holes on scan-sized meshes: every filter against CGAL's Liepa fill, hole by hole.

The pymeshlab samples are Loop-subdivided (bunny.obj once, 212k faces; cow.obj twice, 93k;
airplane.obj once, 94k; bone.ply twice, 48k) and, per seed, two irregular holes (about 250
boundary edges) and one large hole (about 150) are cut with ground truth; the holes are handed
to the comparison as given holes, so every filler fills the same ones in the same run. Printed:
per filler the holes closed, the mean patch-to-ground-truth distance over its closed holes (per
mille of the bounding-box diagonal), the slowest hole and the failures; then the distance of
every hole for every filler.

    .venv/bin/python scripts/large_holes.py [--meshes bunny1,cow2,airplane1,bone2] [--seeds 1,2]
        [--filters "ours;cgal_liepa"] [--json out.json]
"""
from __future__ import annotations

import argparse
import collections
import json
import os

import numpy as np
import pymeshlab

from meshlab_holefill.evaluation.comparison import MeshCase, prepare_case, run_comparison
from meshlab_holefill.evaluation.cut_holes import cut_holes

SAMPLES = os.path.join(os.path.dirname(pymeshlab.__file__), "tests", "sample_meshes")
MESHES = {"bunny1": ("bunny.obj", 1), "cow2": ("cow.obj", 2), "airplane1": ("airplane.obj", 1),
          "bone2": ("bone.ply", 2)}  # name -> (sample, Loop subdivision iterations)
SIZES = ("irregular", "irregular", "large")


def subdivided(sample, iterations):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(SAMPLES, sample))
    if iterations:
        ms.meshing_surface_subdivision_loop(iterations=iterations, threshold=pymeshlab.PercentageValue(0))
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)


def cases(names, seeds):
    """One prepared case per mesh and seed, its holes given (the same for every filler)."""
    out = []
    for name in names:
        V, F = subdivided(*MESHES[name])
        for seed in seeds:
            _, holes = cut_holes(V, F, sizes=SIZES, seed=seed, strict=False)
            removed = np.zeros(len(F), bool)
            removed[np.concatenate([h.face_indices for h in holes])] = True
            out.append(prepare_case(MeshCase(f"{name}_s{seed}", V, F, removed=removed, given_class="real-size")))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", default=",".join(MESHES))
    ap.add_argument("--seeds", default="1,2")
    ap.add_argument("--filters", default="ours;cgal_liepa", help="fillers as compare takes them, ';'-separated")
    ap.add_argument("--json", help="write the per-hole rows here")
    args = ap.parse_args(argv)
    result = run_comparison(None, cases=cases(args.meshes.split(","), [int(s) for s in args.seeds.split(",")]),
                            filters=args.filters.split(";"), timeout=300)
    rows = [{key: value if isinstance(value, (int, float, str, bool, type(None))) else str(value)
             for key, value in dict(row).items()} for row in result.holes]
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)
    by_filler = collections.defaultdict(list)
    for row in rows:
        by_filler[row["filler"]].append(row)
    for filler, holes in by_filler.items():
        closed = [h for h in holes if h["closed"]]
        mean = np.mean([h["dist_patch_to_gt_mean_permille"] for h in closed]) if closed else float("nan")
        slowest = max(holes, key=lambda h: h.get("seconds") or 0.0)
        print(f"{filler}: {len(closed)}/{len(holes)} closed, patch->GT mean {mean:.3f} per mille, slowest "
              f"{slowest.get('seconds') or 0.0:.2f} s ({slowest['case']} hole {slowest['hole']}, "
              f"{slowest['boundary_edges']} edges)")
        for h in holes:
            if not h["closed"]:
                print(f"    failed: {h['case']} hole {h['hole']} ({h['boundary_edges']} edges): {h.get('reason')}")
    table = collections.defaultdict(dict)
    for row in rows:
        table[(row["case"], row["hole"], row["boundary_edges"])][row["filler"]] = (
            f"{row['dist_patch_to_gt_mean_permille']:.2f}" if row["closed"] else "failed")
    print("\ncase, hole, edges | " + " | ".join(by_filler))
    for (case, hole, edges), cells in table.items():
        print(f"{case}, {hole}, {edges} | " + " | ".join(cells.get(f, "-") for f in by_filler))


if __name__ == "__main__":
    main()
