"""A range scan at the size of a real one: face000.ply midpoint-subdivided to 2.8M faces, against MeshLab."""
from __future__ import annotations

import os

import numpy as np
import pymeshlab

from meshlab_holefill.evaluation.comparison import MeshCase, prepare_case, run_comparison
from meshlab_holefill.evaluation.report.labels import short_label
from meshlab_holefill.meshlab.mesh_files import mesh_arrays
from .cases import SAMPLES
from .scaling import STAGES, WHOLE_RUN_PAIR, whole_run_pair


def large_scan_case(iterations=2):
    """face000.ply with every edge split ``iterations`` times (4^iterations times its 166k faces).

    The scan keeps what makes a range scan's whole run cost what it does: its outer rim, a loop
    outlining the whole scan that the filters refuse, island outlines, and holes, the largest of
    908 boundary edges after two subdivisions. Its holes are filled as they are (no ground truth).
    """
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(SAMPLES, "rangemaps", "face000.ply"))
    ms.meshing_surface_subdivision_midpoint(iterations=iterations, threshold=pymeshlab.PercentageValue(0))
    V, F = mesh_arrays(ms)
    return MeshCase(f"face000_{len(F) // 1000}k", V, F)


# Alternating runs of each filler: with three, the whole-run ratio's median moved from 1.48x to 1.56x between two
# runs of the benchmark on one day.
LARGE_SCAN_REPEATS = 5


def large_scan_run(fillers, repeats=LARGE_SCAN_REPEATS, timeout=600.0):
    """The min-angle filter and MeshLab's Close Holes (all holes) on :func:`large_scan_case`, alternating.

    Each run is a fresh worker's (:func:`run_comparison`): the MeshSet is built from the arrays,
    then the filter's whole run is timed (loading the mesh excluded) and the worker's peak
    resident memory above its memory before building the MeshSet is taken.

    Returns
    -------
    (faces, rows) : rows per filler (of ``fillers``, those of :data:`.scaling.WHOLE_RUN_PAIR`) with
    ``seconds`` and ``memory_mb`` (one per run), ``closed`` and the first run's ``stage_seconds``
    """
    pair = whole_run_pair(fillers)
    prepared = prepare_case(large_scan_case(), maxholesize=2000)
    rows = {f.label: {"filler": f.label, "seconds": [], "memory_mb": []} for f in pair}
    for _ in range(repeats):
        for f in pair:
            run = run_comparison(None, cases=[prepared], filters=[f], timeout=timeout, full_metrics=False).runs[0]
            row = rows[f.label]
            row["seconds"].append(run["seconds"])
            row["memory_mb"].append(run.get("memory_mb"))
            row.setdefault("closed", run.get("closed_holes"))
            row.setdefault("stage_seconds", run.get("stage_seconds"))
    return len(prepared.F0), list(rows.values())


def large_scan_table(rows):
    """(header, rows) of :func:`large_scan_run`'s runs: each filler's runs, their median, its peak memory."""
    header = ["filler", "holes closed", "whole run (s, each run)", "median (s)", "peak MB (median)"]
    table = []
    for r in rows:
        memory = [m for m in r["memory_mb"] if m is not None]
        table.append([f"`{short_label(r['filler'])}`", str(r["closed"]), ", ".join(f"{s:.2f}" for s in r["seconds"]),
                      f"{np.median(r['seconds']):.2f}", f"{np.median(memory):.0f}" if memory else "–"])
    return header, table


def large_scan_summary(faces, rows):
    """One sentence: the min-angle filter's median whole run and peak memory against MeshLab's, and where its run
    goes; None unless both ran."""
    by_label = {r["filler"]: r for r in rows}
    if set(by_label) != set(WHOLE_RUN_PAIR):
        return None
    ours, theirs = by_label[WHOLE_RUN_PAIR[0]], by_label[WHOLE_RUN_PAIR[1]]
    time_ratio = np.median(ours["seconds"]) / np.median(theirs["seconds"])
    memories = [[m for m in r["memory_mb"] if m is not None] for r in (ours, theirs)]
    memory = (f", peak memory {np.median(memories[0]) / np.median(memories[1]):.2f}x"
              if all(memories) and np.median(memories[1]) > 0 else "")
    stages = ours.get("stage_seconds") or {}
    where = ", ".join(f"{name} {stages[name]:.2f}" for name in STAGES if name in stages)
    return (f"At {faces:,} faces the min-angle filter's whole run is {time_ratio:.2f}x MeshLab's Close Holes (all "
            f"holes){memory}; its first run by stage (s): {where}.")
