"""Holes with jagged borders in scan-like meshes: every filter against CGAL's Liepa fill, hole by hole.

The pymeshlab samples are Loop-subdivided (as ``scripts/large_holes.py``: bunny.obj once, cow.obj twice,
airplane.obj once, bone.ply twice), their vertices moved along the normals by Gaussian noise of
``--sigmas`` mean edge lengths (``evaluation.noisy.normal_noise``), and per seed four holes of about
20, 60, 150 and 250 boundary edges are cut with ground truth (the noisy surface); every filler fills
the same holes in the same run. Printed: per filler and noise level the holes closed, the mean
patch-to-ground-truth distance (per mille of the bounding-box diagonal) over its closed holes, the
smallest triangle quality, the new faces crossing the mesh; then the holes a filler did not close.

    .venv/bin/python scripts/noisy_holes.py [--meshes bunny1,cow2,airplane1,bone2] [--sigmas 0.15,0.3]
        [--seeds 3,4] [--filters "ours;cgal_liepa"]
"""
from __future__ import annotations

import argparse
import collections

import numpy as np

from large_holes import MESHES, subdivided
from meshlab_holefill.evaluation.comparison import MeshCase, prepare_case, run_comparison
from meshlab_holefill.evaluation.cut_holes import cut_holes
from meshlab_holefill.evaluation.noisy import normal_noise
from meshlab_holefill.evaluation.report.labels import aggregate

SIZES = ("small", "medium", "large", "irregular")


def cases(names, sigmas, seeds):
    """One prepared case per mesh, noise level and seed (noise seeded 0), its holes given."""
    out = []
    for name in names:
        V0, F = subdivided(*MESHES[name])
        for sigma in sigmas:
            V = normal_noise(V0, F, sigma, seed=0)
            for seed in seeds:
                _, holes = cut_holes(V, F, sizes=SIZES, seed=seed, strict=False)
                removed = np.zeros(len(F), bool)
                removed[np.concatenate([h.face_indices for h in holes])] = True
                out.append(prepare_case(MeshCase(f"{name}_n{sigma:g}_s{seed}", V, F, removed=removed,
                                                 given_class="noisy")))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", default=",".join(MESHES))
    ap.add_argument("--sigmas", default="0.15,0.3")
    ap.add_argument("--seeds", default="3,4")
    ap.add_argument("--filters", default="ours;cgal_liepa", help="fillers as compare takes them, ';'-separated")
    args = ap.parse_args(argv)
    sigmas = [float(s) for s in args.sigmas.split(",")]
    result = run_comparison(None, cases=cases(args.meshes.split(","), sigmas, [int(s) for s in args.seeds.split(",")]),
                            filters=args.filters.split(";"), timeout=300)
    groups = collections.defaultdict(list)
    for row in map(dict, result.holes):
        groups[(row["filler"], row["case"].split("_n")[1].split("_s")[0])].append(row)
    for (filler, sigma), rows in sorted(groups.items()):
        closed = [r for r in rows if r["closed"]]
        mean, q_min = (float("nan") if value is None else value for value in
                       (aggregate(rows, "dist_patch_to_gt_mean_permille", "mean"), aggregate(rows, "quality_min", "min")))
        crossing = aggregate(rows, "intersecting_new_faces", "sum") or 0
        seconds = [r.get("seconds") or 0.0 for r in rows]
        slowest = rows[int(np.argmax(seconds))]
        print(f"{filler} sigma {sigma}: {len(closed)}/{len(rows)} closed, patch->GT mean {mean:.3f} per mille, "
              f"quality min {q_min:.3f}, {crossing} new faces crossing the mesh, {sum(seconds):.2f} s, slowest hole "
              f"{max(seconds):.2f} s ({slowest['case']} hole {slowest['hole']}, {slowest['boundary_edges']} edges)")
        for r in rows:
            if not r["closed"]:
                print(f"    not closed: {r['case']} hole {r['hole']} ({r['boundary_edges']} edges): {r.get('reason')}")


if __name__ == "__main__":
    main()
