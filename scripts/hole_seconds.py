"""Per-hole fill seconds of filters on one benchmark case, warm, one process, one core: the best of several runs.

Each filter fills the case's holes as the benchmark does (its natural holes, or the holes cut with seed 0;
``maxholesize`` one above the largest) with ``workers=1`` once untimed, then ``--runs`` times; the run with the smallest sum of the per-hole ``seconds`` of
``fill_holes``' result is reported, by hole size, with its whole run. For comparing two builds of the code on the
same machine, run it from each and alternate.

    .venv/bin/python scripts/hole_seconds.py face000.ply [--filters differential_evolution,lssvm_poisson] [--runs 3]
"""
from __future__ import annotations

import argparse
import time

from meshlab_holefill import algorithm_names, fill_holes
from meshlab_holefill.evaluation.comparison import prepare_case

from benchmark_sections.cases import load_case

SIZES = ((0, 10), (10, 30), (30, 100), (100, 10**6))  # boundary edges, lower bound excluded


def best_run(V, F, algorithm, runs, maxholesize):
    """(whole-run seconds, hole entries) of the run whose per-hole seconds sum least."""
    fill_holes(V, F, algorithm, workers=1, maxholesize=maxholesize)
    best = None
    for _ in range(runs):
        t0 = time.perf_counter()
        result = fill_holes(V, F, algorithm, workers=1, maxholesize=maxholesize)[2]
        whole = time.perf_counter() - t0
        holes = [h for h in result["holes"] if h.get("status") == "closed"]
        if best is None or sum(h["seconds"] for h in holes) < sum(h["seconds"] for h in best[1]):
            best = (whole, holes)
    return best


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", help="a benchmark case (benchmark_sections.cases), e.g. face000.ply or bunny.obj")
    ap.add_argument("--filters", default=",".join(algorithm_names()))
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args(argv)
    case = prepare_case(load_case(args.case), holes=4, seed=0)
    maxholesize = max(h.boundary_edges for h in case.holes) + 1  # the benchmark's: every evaluated hole
    for algorithm in args.filters.split(","):
        whole, holes = best_run(case.V0, case.F0, algorithm, args.runs, maxholesize)
        print(f"{algorithm}: {len(holes)} holes closed, per-hole seconds summed {sum(h['seconds'] for h in holes):.3f} "
              f"(whole run {whole:.3f} s)")
        for lo, hi in SIZES:
            sel = sorted(h["seconds"] for h in holes if lo < h["boundary_edges"] <= hi)
            if sel:
                print(f"    {lo + 1}-{hi if hi < 10**6 else ''} edges: {len(sel)} holes, {sum(sel):.3f} s, "
                      f"median {sel[len(sel) // 2]:.4f} s")


if __name__ == "__main__":
    main()
