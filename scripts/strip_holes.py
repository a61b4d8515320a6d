"""Strip-shaped holes on scan-sized meshes: every filter against CGAL's Liepa fill, hole by hole.

Range scans leave long, narrow gaps. On each of the Loop-subdivided pymeshlab samples of
``scripts/large_holes.py`` (bunny.obj once, cow.obj twice, bone.ply twice, airplane.obj once),
three bands are cut: the faces whose centroids lie within 2-5 mean edge lengths of a random
plane through a random face centroid and within 8-20 % of the bounding-box diagonal of that
centroid, kept when the band leaves one boundary loop of 80-400 edges. Each band is one case
with its ground truth, filled by every filler in the same run. Printed: per filler the holes
closed and the mean patch-to-ground-truth distance (per mille of the bounding-box diagonal),
then every hole.

    .venv/bin/python scripts/strip_holes.py [--seed 0] [--filters "ours;cgal_liepa"]
"""
from __future__ import annotations

import argparse
import collections
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from large_holes import MESHES, subdivided  # noqa: E402

from meshlab_holefill.core.holes import boundary_loops  # noqa: E402
from meshlab_holefill.evaluation.comparison import MeshCase, prepare_case, run_comparison  # noqa: E402

BANDS_PER_MESH = 3
TRIES = 50


def band(V, F, rng):
    """A removed-face mask of one strip leaving one loop of 80-400 edges, or None after TRIES tries."""
    diagonal = np.linalg.norm(V.max(axis=0) - V.min(axis=0))
    centroids = V[F].mean(axis=1)
    edge = np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1).mean()
    for _ in range(TRIES):
        centre = centroids[rng.integers(len(centroids))]
        normal = rng.normal(size=3)
        normal /= np.linalg.norm(normal)
        radius, width = diagonal * rng.uniform(0.08, 0.2), edge * rng.uniform(2, 5)
        removed = (np.abs((centroids - centre) @ normal) < width) & (np.linalg.norm(centroids - centre, axis=1) < radius)
        loops = boundary_loops(F[~removed])
        if removed.sum() > 20 and len(loops) == 1 and 80 <= len(loops[0]) <= 400:
            return removed
    return None


def cases(seed):
    rng = np.random.default_rng(seed)
    out = []
    for name in MESHES:
        V, F = subdivided(*MESHES[name])
        for i in range(BANDS_PER_MESH):
            removed = band(V, F, rng)
            if removed is not None:
                out.append(prepare_case(MeshCase(f"{name}_strip{i}", V, F, removed=removed, given_class="real-size")))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--filters", default="ours;cgal_liepa", help="fillers as compare takes them, ';'-separated")
    args = ap.parse_args(argv)
    result = run_comparison(None, cases=cases(args.seed), filters=args.filters.split(";"), timeout=300)
    rows = collections.defaultdict(dict)
    for d in result.holes:
        value = d.get("dist_patch_to_gt_mean_permille") if d.get("closed") else None
        rows[(d["case"], d["boundary_edges"])][d["filler"]] = value
    fillers = list(dict.fromkeys(d["filler"] for d in result.holes))
    for filler in fillers:
        values = [r[filler] for r in rows.values() if r.get(filler) is not None]
        mean = f"{np.mean(values):.3f}" if values else "-"
        print(f"{filler}: {len(values)}/{len(rows)} closed, patch->GT mean {mean} per mille")
    print("\ncase, edges | " + " | ".join(fillers))
    for (case, edges), r in rows.items():
        print(f"{case}, {edges} | " + " | ".join("failed" if r.get(f) is None else f"{r[f]:.2f}" for f in fillers))


if __name__ == "__main__":
    main()
