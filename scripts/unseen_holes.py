"""Holes no filter was tuned on: the benchmark's shapes cut with other seeds, every filler against an anchor.

The benchmark cuts its holes with seed 0. Here the same shapes get holes drawn with ``--seeds``:
pymeshlab's closed samples and the analytic sphere and torus (``prepare_case(..., seed=s)``, four holes
of about 20, 60 and 150 edges), the CAD-like parts of ``evaluation.creased`` with holes at random crease
points or next to random points of the crossing curves (``creased_case(name, seed=s)``), the same parts
tessellated as CAD exports (``cad_tessellation_case(name, seed=s)``), the bunny Loop-subdivided once with
three holes of 150-300 edges, the noisy cow, and virtual range scans of the bunny and of the noisy cow whose
holes are the surface the scanner did not see (``benchmark_sections.cases``). Every filler fills the same
holes in the same run. Printed per group of cases and filler: holes closed; the mean patch-to-ground-truth
distance (per mille of the bounding-box diagonal) over the holes both it and the anchor closed, with the
anchor's on the same holes; new faces crossing the mesh; holes with a triangle below min(0.1, the best
quality the hole's sharpest border corner allows); the slowest hole of at most 300 edges. Then each hole a
filler did not close, with the reason.

    .venv/bin/python scripts/unseen_holes.py [--seeds 1,2,3] [--groups closed,creased,cad,real-size,noisy,scan]
        [--filters "ours;cgal_liepa"] [--anchor cgal_liepa]
"""
from __future__ import annotations

import argparse
import collections

from meshlab_holefill.evaluation.comparison import prepare_case, run_comparison
from meshlab_holefill.evaluation.creased import CAD_TESSELLATED_PARTS, CREASED_CASES, cad_tessellation_case, creased_case

from benchmark_sections.cases import CLOSED, load_case, noisy_case, real_size_case, scan_cases

GROUPS = {
    "closed": lambda seed: [prepare_case(load_case(name), holes=4, seed=seed) for name in CLOSED],
    "creased": lambda seed: [prepare_case(creased_case(name, seed=seed)) for name in CREASED_CASES],
    "cad": lambda seed: [prepare_case(cad_tessellation_case(name, seed=seed)) for name in CAD_TESSELLATED_PARTS],
    "real-size": lambda seed: [prepare_case(real_size_case(seed))],
    "noisy": lambda seed: [prepare_case(noisy_case(seed))],
    "scan": lambda seed: [prepare_case(case) for case in scan_cases(seed)],
}
SLIVER = 0.1  # a triangle below min(SLIVER, the hole's corner bound) is a sliver no border corner forces
TIMED_EDGES = 300  # the slowest hole is reported among holes of at most this many boundary edges
LISTED = 12  # holes not closed listed one by one per filler and group; the others are counted by reason


def group_lines(filler, rows, anchor_rows):
    """The summary line of one filler on one group's holes, then its holes not closed.

    ``rows`` and ``anchor_rows`` map (case, hole) to the hole rows of run_comparison, the filler's and the
    anchor's (empty when the anchor did not run: the mean is then over the filler's closed holes).
    """
    closed = {key: r for key, r in rows.items() if r["closed"]}
    both = [key for key in closed if anchor_rows.get(key, {}).get("closed")] if anchor_rows else list(closed)
    mean = sum(closed[key]["dist_patch_to_gt_mean_permille"] for key in both) / max(len(both), 1)
    anchor = (sum(anchor_rows[key]["dist_patch_to_gt_mean_permille"] for key in both) / max(len(both), 1)
              if anchor_rows else float("nan"))
    crossing = sum(r.get("intersecting_new_faces") or 0 for r in closed.values())
    slivers = sum(r["quality_min"] < min(SLIVER, r.get("quality_bound") or 1.0) for r in closed.values())
    timed = [r for r in rows.values() if r["boundary_edges"] <= TIMED_EDGES and r.get("seconds") is not None]
    slowest = max(timed, key=lambda r: r["seconds"], default=None)
    line = (f"{filler}: {len(closed)}/{len(rows)} closed, patch->GT mean {mean:.3f} per mille against the anchor's "
            f"{anchor:.3f} on the same {len(both)} holes, {crossing} new faces crossing the mesh, {slivers} holes "
            f"with an unforced sliver")
    if slowest is not None:
        line += (f", slowest hole of <= {TIMED_EDGES} edges {slowest['seconds']:.3f} s ({slowest['case']} hole "
                 f"{slowest['hole']}, {slowest['boundary_edges']} edges)")
    open_rows = [(case, hole, r) for (case, hole), r in rows.items() if not r["closed"]]
    lines = [f"    not closed: {case} hole {hole} ({r['boundary_edges']} edges): {r.get('reason')}"
             for case, hole, r in open_rows[:LISTED]]
    if len(open_rows) > LISTED:  # a scan leaves hundreds of small holes: the rest by reason
        rest = collections.Counter((r.get("reason") or "").split(";")[0] for _, _, r in open_rows[LISTED:])
        lines += [f"    and {count} more: {reason}" for reason, count in rest.most_common()]
    return [line] + lines


def seeded_cases(group, seeds):
    """The group's prepared cases for every seed, each named "<case> s<seed>"."""
    cases = []
    for seed in seeds:
        for case in GROUPS[group](seed):
            case.name = f"{case.name} s{seed}"
            cases.append(case)
    return cases


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--groups", default="closed,creased,cad,real-size,noisy",
                    help=f"of {','.join(GROUPS)}; scan (hundreds of small holes a case) only when named")
    ap.add_argument("--filters", default="ours;cgal_liepa", help="fillers as compare takes them, ';'-separated")
    ap.add_argument("--anchor", default="cgal_liepa", help="the filler the distances are compared with")
    args = ap.parse_args(argv)
    for group in args.groups.split(","):
        cases = seeded_cases(group, [int(s) for s in args.seeds.split(",")])
        result = run_comparison(None, cases=cases, filters=args.filters.split(";"), timeout=300)
        by_filler = collections.defaultdict(dict)  # filler -> {(case, hole): row}
        for row in map(dict, result.holes):
            by_filler[row["filler"]][(row["case"], row["hole"])] = row
        print(f"# {group}, seeds {args.seeds}: {len(cases)} cases", flush=True)
        for filler, rows in by_filler.items():
            print("\n".join(group_lines(filler, rows, by_filler.get(args.anchor, {}))), flush=True)


if __name__ == "__main__":
    main()
