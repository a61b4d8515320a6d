#!/usr/bin/env python
"""Benchmark every registered hole filler against MeshLab's Close Holes: the standard suite.

The suite: pymeshlab's closed sample meshes (bunny.obj, bone.ply, cow.obj, airplane.obj) and
an analytic sphere and torus get holes with ground truth cut (``--holes`` per mesh, sizes
small/medium/large cycling, compact and irregular shapes alternating); the bunny scan's
natural holes (bunny10k_textured.obj) and the face range scan (rangemaps/face000.ply) are
filled as they are; the CAD-like cases of ``evaluation.creased`` (creased_box, bevelled_box,
cylinder_rims, union: holes a crease runs through; interpenetrating: holes next to where
overlapping parts cross) have their own holes; bunny_212k (the bunny Loop-subdivided once, about
212k faces) has three holes of 150-375 boundary edges with ground truth ("real-size"); cow_noisy (cow.obj
Loop-subdivided twice, about 93k faces, its vertices moved along their normals by Gaussian noise of 0.3 mean
edge lengths, as a range scan's error lies along the line of sight) has four holes of about 20-250 boundary
edges with jagged borders ("noisy"). CGAL's Liepa fill (``cgal_liepa``) and MeshFix
(``pymeshfix``) run as anchors when installed. The report (tables, charts, one picture per hole) goes to ``OUT/suite``.

``--scaling`` adds the scaling run: the same holes (same centres, same boundary sizes) in the
bunny subdivided to about 50k, 200k, 800k and 3M faces, per-hole seconds against mesh size; at the
largest size the min-angle filter and MeshLab's Close Holes run ``--scaling-repeats`` times,
alternating, and the ratio of their median whole runs is reported.
``--large-scan`` adds face000.ply midpoint-subdivided to 2.8M faces: the min-angle filter against MeshLab's
Close Holes, whole run and peak memory, alternating five times.
``--papers`` adds the "papers vs. ours" table (Brunton, Hu, Xu, Xie & Zou Table 1).
``--against bench_out/suite/results.csv`` sets the suite beside an earlier run (read before this run
overwrites it): per filter and hole class, holes closed, distance and removed crease error then and now.
``--update-readme`` replaces the README's Results section with this run's summary.
Each section is a module of ``benchmark_sections`` (cases, scaling, large_scan, papers, speed, refusals,
batch, compile_cost); this script runs the ones asked for and offers their functions under its own name.

    .venv/bin/python scripts/benchmark.py [--filters a,b] [--out bench_out] [--seed 0] [--cases bunny.obj,sphere]
                                          [--scaling] [--papers] [--refusals] [--compile-cost] [--update-readme]
                                          [--against bench_out/suite/results.csv]
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

from meshlab_holefill.evaluation.comparison import BASELINE, parse_fillers, run_comparison
from meshlab_holefill.evaluation.report.against import against_table, read_results_csv
from meshlab_holefill.evaluation.report.tables import markdown_table, summary_blocks, to_markdown
from meshlab_holefill.evaluation.report.write import write_report

from benchmark_sections.batch import batch_throughput
from benchmark_sections.cases import (CASES, CLOSED, CREASED, NATURAL, NOISE_SIGMA, NOISY, REAL_SIZE, REAL_SIZE_HOLES,
                                      SAMPLES, load_case, noisy_case, real_size_case)
from benchmark_sections.compile_cost import compile_cost
from benchmark_sections.papers import PAPERS, papers_table, xie_all_fillers
from benchmark_sections.refusals import debris_times, refusal_times, spherical_cap
from benchmark_sections.large_scan import LARGE_SCAN_REPEATS, large_scan_run, large_scan_summary, large_scan_table
from benchmark_sections.scaling import (SCALING_SIZES, SPEED_CASE_SIZES, scaling_plot, scaling_run, scaling_table,
                                        stage_table, whole_run_ratio)
from benchmark_sections.speed import one_core_speed, speed_table, workers_speedup

__all__ = ["CASES", "CLOSED", "CREASED", "NATURAL", "NOISE_SIGMA", "NOISY", "REAL_SIZE", "REAL_SIZE_HOLES", "SAMPLES",
           "PAPERS", "SCALING_SIZES", "SPEED_CASE_SIZES", "DEFAULT_FILTERS", "batch_throughput", "compile_cost",
           "debris_times", "large_scan_run", "large_scan_summary", "large_scan_table",
           "load_case", "main", "markdown_table", "noisy_case", "one_core_speed", "papers_table", "real_size_case",
           "refusal_times", "scaling_plot", "scaling_run", "scaling_table", "speed_table", "spherical_cap",
           "stage_table", "update_readme", "whole_run_ratio", "workers_speedup", "xie_all_fillers"]

# Ours with defaults; three measured variants (Xu et al.'s Table 1 membrane comparison, Hu's optional
# fairing as in its filters/ preset, curve unfolding on the paper's unfolded domain alone); MeshLab's Close Holes
# with its defaults and with every hole allowed.
# CGAL's Liepa fill and MeshFix as open anchors (skipped with a note when not installed).
DEFAULT_FILTERS = ("ours,lssvm_poisson:laplacian_prediction=zero:poisson_boundary=dirichlet,min_angle_bilateral:fairing=thinplate:iterations=0:smoothing=10,"
                   "curve_unfolding:domain=unfolding,differential_evolution:layouts=smoothest,anchors,baseline")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--filters", default=DEFAULT_FILTERS,
                    help="fillers as for `meshlab-holefill compare --filters` (default: all of ours, the measured "
                         "variants, meshing_close_holes twice)")
    ap.add_argument("--out", default="bench_out")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--holes", type=int, default=4, help="holes cut per closed mesh")
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds before a run is killed (default 60: "
                                                                 "keeps the suite under 10 minutes)")
    ap.add_argument("--refinehole", action="store_true", help="also meshing_close_holes with refinehole=True")
    ap.add_argument("--no-pictures", action="store_true")
    ap.add_argument("--scaling", action="store_true", help="also the scaling run (50k..3M faces)")
    ap.add_argument("--no-suite", action="store_true", help="skip the standard suite (e.g. only --scaling)")
    ap.add_argument("--scaling-levels", type=int, default=4)
    ap.add_argument("--scaling-repeats", type=int, default=3,
                    help="runs of the min-angle filter and MeshLab's Close Holes (all holes) at the largest scaling "
                         "level, alternating; their medians give the whole-run ratio (default 3)")
    ap.add_argument("--papers", action="store_true", help="also the papers-vs-ours table")
    ap.add_argument("--speed-case", action="store_true",
                    help="also the speed case: holes of ~50/200/250 edges in a ~200k-face mesh")
    ap.add_argument("--update-readme", action="store_true",
                    help="replace the README's Results section with this run's tables")
    ap.add_argument("--batch", action="store_true",
                    help="also batch throughput (files per minute) with 1 and 2 dask workers, and the speed-up")
    ap.add_argument("--workers", action="store_true", help="also face000.ply with workers=1 and 2")
    ap.add_argument("--large-scan", action="store_true",
                    help="also face000.ply subdivided to 2.8M faces: the min-angle filter's whole run and peak memory "
                         "against MeshLab's Close Holes")
    ap.add_argument("--one-core", action="store_true",
                    help="also every filter against CGAL's Liepa fill on the suite's cut holes, one hole at a time each")
    ap.add_argument("--compile-cost", action="store_true",
                    help="also the one-time cost of compiling the kernels (cold, empty numba cache) and the warm load")
    ap.add_argument("--refusals", action="store_true",
                    help="also the time each filter takes to refuse a loop that outlines its whole mesh")
    ap.add_argument("--batch-files", type=int, default=24, help="files in the batch throughput run (default 24)")
    ap.add_argument("--against", metavar="RESULTS_CSV",
                    help="also set the suite beside an earlier run's results.csv (e.g. bench_out/suite/results.csv, "
                         "read before this run overwrites it): holes closed, distance and removed crease error, "
                         "filler by filler and class by class")
    args = ap.parse_args(argv)
    earlier = None
    if args.against:
        if args.no_suite:
            ap.error("--against compares the suite: drop --no-suite")
        if not os.path.isfile(args.against):
            ap.error(f"--against: no file '{args.against}'")
        earlier = read_results_csv(args.against)
    command = ".venv/bin/python scripts/benchmark.py " + " ".join(argv if argv is not None else sys.argv[1:])
    command = command.strip()
    fillers = parse_fillers(args.filters or None, args.refinehole)
    t0 = time.perf_counter()
    os.makedirs(args.out, exist_ok=True)
    load_at_start = os.getloadavg()[0]  # other jobs on the machine slow every timing below
    text, result = f"Measured by `{command}` on {time.strftime('%Y-%m-%d')} ({os.cpu_count()} cores).\n", None
    if not args.no_suite:
        cases = [load_case(c) for c in args.cases.split(",") if c]
        result = run_comparison(cases, holes=args.holes, seed=args.seed, filters=fillers, timeout=args.timeout)
        suite_dir = os.path.join(args.out, "suite")
        write_report(result, suite_dir, pictures=not args.no_pictures, command=command)
        suite_seconds = time.perf_counter() - t0
        print(f"# suite: {suite_seconds:.1f} s (report in {suite_dir})", file=sys.stderr)
        text = (f"Measured by `{command}` on {time.strftime('%Y-%m-%d')} ({os.cpu_count()} cores, load average "
                f"{load_at_start:.1f} at the start): {suite_seconds:.0f} s for the suite including the report. Meshes: "
                + ", ".join(f"{c['case']} ({len(c['holes'])} {c['kind']})" for c in result.cases)
                + f". Full report: `{suite_dir}/report.md` (tables, charts, a picture of every hole).\n\n"
                + to_markdown(summary_blocks(result)))
        if earlier is not None:
            text += ("\n\n**Against an earlier run** (`" + args.against + "`; a hole is the same hole when its case, "
                     "number and boundary edges agree; each metric's mean over the holes both runs closed, the crease "
                     "error over those with a removed crease):\n\n" + markdown_table(*against_table(earlier, result.holes))
                     + "\n")
        speed = speed_table(result)
        if speed is not None:
            text += ("\n\n**Speed against CGAL** (the filters' own per-hole seconds on the cut holes that both they and "
                     "`cgal_liepa` closed, same run; the filters with `workers` = one per core, two holes at once):\n\n" + markdown_table(*speed) + "\n")
        if args.one_core:
            single = one_core_speed(cases, args.holes, args.seed)
            if single is not None:
                text += ("\n**One core each** (the same holes, every filter with its defaults and `workers=1` in one "
                         "process, CGAL's Liepa fill one hole at a time, alternating three times; per-hole seconds "
                         "summed, medians):\n\n" + markdown_table(*single) + "\n")
            else:
                text += ("\n**One core each**: skipped (CGAL's Python bindings, package `cgal` of the `bench` extra, "
                         "are not installed, or no case has cut or given holes).\n")
    # timing runs: each filter once, with its defaults (variants only change accuracy)
    plain = [f for f in fillers if not f.params or f.filter == BASELINE]
    if args.scaling:
        rows = scaling_run(plain, args.seed, args.scaling_levels, max(args.timeout, 180.0), args.out,
                           repeats=args.scaling_repeats)
        with open(os.path.join(args.out, "scaling.json"), "w") as fh:
            json.dump(rows, fh, indent=1)
        text += ("\n**Scaling** (the same three holes, ~20/60/150 boundary edges, in the bunny subdivided; "
                 "'filling the holes' is the sum of the filters' own per-hole times (holes are filled two at a "
                 "time, `workers` = one per core, so the sum can exceed the whole run; 'rest' is then negative), the "
                 "rest is the O(n) boundary search, mesh transfer and merge; 'peak MB' is the worker's peak resident memory while it builds the "
                 "MeshSet and runs the filter, above its memory before):\n\n" + markdown_table(*scaling_table(rows)) + f"\n\nPlot: `{args.out}/scaling.png`.\n")
        ratio = whole_run_ratio(rows)
        if ratio:
            text += "\n" + ratio + "\n"
        header, stages = stage_table(rows)
        if stages:
            text += ("\nWhere the min-angle filter's whole run goes (seconds, the first run at each size): its MeshSet "
                     "layer read into arrays, the edge table (each edge's faces; non-manifold edges and faces joined "
                     "only at a vertex refused), the boundary loops walked on it (`boundary_loops(F)` is these two), "
                     "the hole selection (each loop's measures and class), loading the kernels, the holes (filled, "
                     "checked against the mesh and merged), the attributes extended and the filled layer written; "
                     "reference: boundary loops under 0.5 s at 4M faces:\n\n"
                     + markdown_table(header, stages) + "\n")
    if args.large_scan:
        faces, rows = large_scan_run(plain, repeats=LARGE_SCAN_REPEATS, timeout=max(args.timeout, 180.0))
        text += (f"\n**A scan at scan size** (face000.ply midpoint-subdivided twice, {faces:,} faces: its outer "
                 "rim and island outlines refused, its holes (the largest of 908 boundary edges) filled; each run a "
                 "fresh worker building the MeshSet from arrays, the whole run timed without it, peak resident memory "
                 f"above the worker's before building the MeshSet; the two fillers alternating {LARGE_SCAN_REPEATS} "
                 "times):\n\n"
                 + markdown_table(*large_scan_table(rows)) + "\n")
        summary = large_scan_summary(faces, rows)
        if summary:
            text += "\n" + summary + "\n"
    if args.speed_case:
        rows = scaling_run(plain, args.seed, 2, max(args.timeout, 180.0), None, SPEED_CASE_SIZES, first_level=1)
        with open(os.path.join(args.out, "speed_case.json"), "w") as fh:
            json.dump(rows, fh, indent=1)
        edges = "/".join(str(e) for e in rows[0]["hole_edges"]) if rows else "?"
        text += (f"\n**Speed case** (three holes of about 50, 200 and 250 boundary edges, here {edges}, in the "
                 "bunny Loop-subdivided once; reference for `min_angle_bilateral`: whole run under 1.5 s):\n\n"
                 + markdown_table(*scaling_table(rows)) + "\n")
    if args.workers:
        text += ("\n**Holes on all cores** (face000.ply, each filter in a fresh process, its kernels loaded first, "
                 "each count run once untimed, then `workers=1` and `workers=2` alternating five times, medians; "
                 "'MeshSet': the filter's whole run "
                 "on a MeshSet; 'arrays': the same fill on the scan's arrays through `meshlab_holefill.fill_holes`, "
                 "without pymeshlab's serial transfer of the mesh and of the new layer):\n\n"
                 + markdown_table(*workers_speedup()) + "\n")
    if args.compile_cost:
        text += ("\n**Compiling the kernels** (`meshlab-holefill compile` with an empty numba cache, as after an "
                 "install, then again with the cache current; each filter's process seconds, compiling included, "
                 "one process per core, filters taken in the table's order; a kernel two filters share is compiled by "
                 "the first that needs it):\n\n" + markdown_table(*compile_cost()) + "\n")
    if args.refusals:
        what, header, rows = refusal_times()
        text += (f"\n**Refused loops** (a spherical cap, {what}: the rim outlines the whole mesh, so the "
                 "filters refuse it; whole run of each filter at its defaults):\n\n" + markdown_table(header, rows) + "\n")
        what, header, rows = debris_times()
        text += (f"\nThe same cap with a range scan's debris ({what} of two triangles each, scattered around it): "
                 "every loop outlines its component and is refused; the loops are measured and classed all at once "
                 "('hole selection'):\n\n" + markdown_table(header, rows) + "\n")
    if args.papers and result is not None:
        papers = papers_table(result, command, args.seed, max(args.timeout, 180.0))
        with open(os.path.join(args.out, "papers.md"), "w") as fh:
            fh.write(papers)
        text += "\n**Papers vs. ours**\n\n" + papers
    if args.batch:
        text += ("\n**Batch throughput** (`meshlab_holefill.batch` on a running LocalCluster, copies of the bunny scan "
                 "with its 5 natural holes, `meshing_close_holes_min_angle_bilateral` defaults):\n\n"
                 + batch_throughput(args.out, args.batch_files) + "\n")
    with open(os.path.join(args.out, "benchmark.md"), "w") as fh:
        fh.write(text + "\n")
    if args.update_readme:
        update_readme(text)
    print(text)
    print(f"# total: {time.perf_counter() - t0:.1f} s", file=sys.stderr)


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
