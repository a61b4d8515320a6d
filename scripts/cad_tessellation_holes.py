"""Holes in CAD-like parts tessellated as CAD exports are (large triangles on flat faces): every filler, hole by hole.

The parts of :func:`meshlab_holefill.evaluation.creased.cad_tessellation_case` (a box united with a cylinder, a
box drilled through, a cylinder with sharp rims): remeshed, then decimated by MeshLab's quadric edge collapse
with planar simplification, which leaves large triangles on the flat faces and small ones along the creases
and the curved walls, as an STL export does; holes of about 20-60 boundary edges are cut around creases (their
borders mix short and long edges). Every filler fills the same holes in the same run. Printed per filler:
holes closed, mean patch-to-ground-truth distance (per mille of the bounding-box diagonal), smallest triangle
quality, new faces crossing the mesh, seconds; with ``--holes`` each hole.

    .venv/bin/python scripts/cad_tessellation_holes.py [--filters "ours;cgal_liepa;meshing_close_holes"] [--holes]
"""
from __future__ import annotations

import argparse
import collections

from meshlab_holefill.evaluation.comparison import prepare_case, run_comparison
from meshlab_holefill.evaluation.creased import CAD_TESSELLATED_PARTS, cad_tessellation_case
from meshlab_holefill.evaluation.report.labels import aggregate


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--parts", default=",".join(CAD_TESSELLATED_PARTS))
    ap.add_argument("--filters", default="ours;cgal_liepa;meshing_close_holes",
                    help="fillers as compare takes them, ';'-separated")
    ap.add_argument("--holes", action="store_true", help="print every hole")
    args = ap.parse_args(argv)
    cases = [prepare_case(cad_tessellation_case(name)) for name in args.parts.split(",")]
    result = run_comparison(None, cases=cases, filters=args.filters.split(";"), timeout=300)
    groups = collections.defaultdict(list)
    for row in map(dict, result.holes):
        groups[row["filler"]].append(row)
    for filler, rows in groups.items():
        closed = [r for r in rows if r["closed"]]
        mean, q_min = (float("nan") if value is None else value for value in
                       (aggregate(rows, "dist_patch_to_gt_mean_permille", "mean"), aggregate(rows, "quality_min", "min")))
        crossing = aggregate(rows, "intersecting_new_faces", "sum") or 0
        seconds = sum(r.get("seconds") or 0.0 for r in rows)
        print(f"{filler}: {len(closed)}/{len(rows)} closed, patch->GT mean {mean:.3f} per mille, quality min "
              f"{q_min:.3f}, {crossing} new faces crossing the mesh, {seconds:.2f} s")
        for r in rows if args.holes else [r for r in rows if not r["closed"]]:
            state = f"{r['dist_patch_to_gt_mean_permille']:.3f} per mille" if r["closed"] else f"not closed: {r.get('reason')}"
            print(f"    {r['case']} hole {r['hole']} ({r['boundary_edges']} edges): {state}")


if __name__ == "__main__":
    main()
