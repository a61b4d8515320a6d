"""Speed against CGAL's Liepa fill: in the suite's run, one core each, and holes on all cores."""
from __future__ import annotations

import concurrent.futures
import multiprocessing
import os
import time

import numpy as np
import pymeshlab

from meshlab_holefill.evaluation.comparison import prepare_case
from meshlab_holefill.evaluation.report.labels import short_label
from meshlab_holefill.meshlab import load_filter_kernels
from .cases import SAMPLES


def speed_table(result, anchor="cgal_liepa"):
    """Per-hole fill seconds of every filler against CGAL's Liepa fill, on the holes with ground truth.

    Each filler is timed on the holes that it and the anchor both closed (the filters' own per-hole
    time, measured in the same run and worker harness); the ratio is its total over the anchor's.
    """
    rows = [r for r in result.holes if r.get("ground_truth")]
    anchor_rows = {(r["case"], r["hole"]): r for r in rows if r["filler"] == anchor and r.get("closed")
                   and r.get("seconds") is not None}
    if not anchor_rows:
        return None
    out = []
    for label in dict.fromkeys(r["filler"] for r in rows):
        mine = [r for r in rows if r["filler"] == label and r.get("closed") and r.get("seconds") is not None
                and (r["case"], r["hole"]) in anchor_rows]
        if not mine:
            continue
        seconds = sum(r["seconds"] for r in mine)
        base = sum(anchor_rows[(r["case"], r["hole"])]["seconds"] for r in mine)
        slowest = max(mine, key=lambda r: r["seconds"])
        out.append([f"`{short_label(label)}`", str(len(mine)), f"{seconds:.2f}", f"{base:.2f}",
                    f"{seconds / base:.1f}" if base > 0 else "–",
                    f"{slowest['seconds']:.2f} ({slowest['case']}, {slowest['boundary_edges']} edges)"])
    return (["filler", "holes", "seconds", f"`{anchor}` seconds", "× CGAL", "slowest hole"], out)


# --------------------------------------------------------------------------- one core each

def one_core_speed(cases, holes, seed, repeats=3, anchor="cgal_liepa"):
    """Per-hole seconds of each filter (defaults, ``workers=1``) and of the anchor on the same holes, one core each.

    The anchor fills one hole at a time in one thread. With one worker per core two holes are
    filled at once and share the machine, which makes each one's seconds longer (on the suite's
    holes the min-angle filter's sum grows about 1.5x), so here the filters too fill one hole at
    a time, in this process, on the cases with ground truth (cut and given holes). The fillers
    alternate ``repeats`` times (the order rotated each time); per filler, the median of its
    totals over the holes that it and the anchor both closed, and the ratio of the medians.

    Returns
    -------
    (header, rows) for :func:`markdown_table`, or None when the anchor is not installed or no
    case has holes with ground truth
    """
    from meshlab_holefill.array_api import algorithm_names, fill_holes
    from meshlab_holefill.evaluation.anchors import missing_package, run_anchor

    if missing_package(anchor):
        return None
    prepared = [pc for pc in (prepare_case(c, holes=holes, seed=seed) for c in cases)
                if pc.holes and all(h.ground_truth is not None for h in pc.holes)]
    if not prepared:  # only natural holes among the cases: nothing to compare on
        return None
    names = algorithm_names()
    warm_V, warm_F = prepared[0].V0, prepared[0].F0
    for name in names:  # kernels loaded before the first timing
        fill_holes(warm_V, warm_F, name, workers=1)

    def per_hole(name, pc):
        """{hole index: seconds} of the holes ``name`` closed in case ``pc``."""
        everything = max(h.boundary_edges for h in pc.holes) + 1
        if name == anchor:
            result = run_anchor(anchor, pc.V0, pc.F0, {"maxholesize": everything})[2]
        else:
            result = fill_holes(pc.V0, pc.F0, name, workers=1, maxholesize=everything)[2]
        return {i: h["seconds"] for i, h in enumerate(result["holes"]) if h.get("status") == "closed"}

    fillers = names + [anchor]
    times = {name: [] for name in fillers}  # per repeat: {(case, hole): seconds}
    for r in range(repeats):
        for name in fillers[r % len(fillers):] + fillers[:r % len(fillers)]:
            times[name].append({(k, i): t for k, pc in enumerate(prepared) for i, t in per_hole(name, pc).items()})
    both = {name: set.intersection(*(set(run) for run in times[name] + times[anchor])) for name in names}  # closed in every run
    rows = []
    for name in names:
        mine = float(np.median([sum(run[h] for h in both[name]) for run in times[name]]))
        base = float(np.median([sum(run[h] for h in both[name]) for run in times[anchor]]))
        rows.append([f"`{name}`", str(len(both[name])), f"{mine:.2f}", f"{base:.2f}", f"{mine / base:.2f}"])
    header = ["filter", "holes", f"seconds (median of {repeats})", f"`{anchor}` seconds (median of {repeats})",
              "× CGAL"]
    return header, rows


# ------------------------------------------------------------------------ holes on all cores

def workers_speedup(filters=("meshing_close_holes_min_angle_bilateral", "meshing_close_holes_curve_unfolding",
                             "meshing_close_holes_lssvm_poisson", "meshing_close_holes_differential_evolution"),
                    mesh=os.path.join(SAMPLES, "rangemaps", "face000.ply"), counts=(1, 2), repeats=5):
    """Seconds of each filter on a scan with ``workers`` = 1 and 2, and whether the results are equal.

    Two runs per count: the MeshSet filter's whole run, and the same fill on the scan's arrays
    (:func:`meshlab_holefill.array_api.fill_holes`), which leaves out the serial transfer of the
    mesh into and out of pymeshlab and its new layer. Each filter runs in a fresh process, as a
    script filling one scan would (the benchmark's own process holds the suite's meshes, which
    every fork would copy the page tables of); its kernels are loaded first (their one-time cost
    is in ``--compile-cost``) and each count runs once untimed (the first fork of a process and
    the first fill at a count touch memory the later runs find ready); the worker counts then
    alternate ``repeats`` times and the medians are reported.
    """
    rows = []
    spawn = multiprocessing.get_context("spawn")
    for name in filters:
        with concurrent.futures.ProcessPoolExecutor(max_workers=1, mp_context=spawn) as fresh:
            seconds, same, closed = fresh.submit(_timed_counts, name, mesh, counts, repeats).result()
        row = [f"`{short_label(name)}`", str(closed)]
        for api in (False, True):
            medians = [float(np.median(seconds[c, api])) for c in counts]
            row += [f"{x:.2f}" for x in medians] + [f"{medians[0] / medians[-1]:.2f}"]
        rows.append(row + ["yes" if same else "**no**"])
    per_count = [f"workers={c} (s, median of {repeats})" for c in counts]
    header = (["filter", "holes closed"] + [f"MeshSet {h}" for h in per_count] + ["MeshSet speed-up"]
              + [f"arrays {h}" for h in per_count] + ["arrays speed-up", "same result"])
    return header, rows


def _timed_counts(name, mesh, counts, repeats):
    """:func:`workers_speedup`'s runs of one filter, in this (fresh) process: (seconds, same result, holes closed).

    ``seconds`` maps (count, arrays door) to the run times.
    """
    from meshlab_holefill.array_api import fill_holes

    load_filter_kernels(name)
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(mesh)
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    for workers in counts:
        fill_holes(V, F, name, workers=workers)
    seconds, results, closed = {(c, api): [] for c in counts for api in (False, True)}, [], None
    for _ in range(repeats):
        for workers in counts:
            ms = pymeshlab.MeshSet()
            ms.load_new_mesh(mesh)
            t = time.perf_counter()
            res = getattr(ms, name)(workers=workers)
            seconds[workers, False].append(time.perf_counter() - t)
            m = ms.current_mesh()
            results.append((m.vertex_matrix(), m.face_matrix()))
            closed = res["closed_holes"]
            t = time.perf_counter()
            V2, F2, _ = fill_holes(V, F, name, workers=workers)
            seconds[workers, True].append(time.perf_counter() - t)
            results.append((V2, F2))
    # every count and both doors (MeshSet, arrays) give the first run's mesh
    same = all(np.array_equal(a, b) for other in results[1:] for a, b in zip(results[0], other))
    return seconds, same, closed
