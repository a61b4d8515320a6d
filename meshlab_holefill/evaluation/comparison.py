"""Running a comparison: every filler on every case in an isolated run, and the measurements.

The cases are :mod:`.mesh_cases`' and the fillers :mod:`.fillers`' (their names are offered here
too).

Each filler runs on each case in a spawned worker (:mod:`.isolation`), so one filter crashing
or hanging is reported and the others still run. Only arrays travel to and from the worker.
All metrics are computed here in the parent, by :func:`.metrics.hole_metrics`.
"""
from __future__ import annotations

import logging
import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from ..core.holes import boundary_halfedges
from .anchors import is_anchor, missing_package
from .cut_holes import SIZE_CLASSES
from .fillers import BASELINE, Filler, anchor_fillers, default_fillers, parse_fillers
from .isolation import IsolatedRunner, json_safe
from .mesh_cases import Hole, MeshCase, PreparedCase, as_case, prepare_case
from .metrics import assign_patches, compact_mesh, hole_metrics, mesh_checks

__all__ = ["BASELINE", "Comparison", "Filler", "Hole", "MeshCase", "PreparedCase", "anchor_fillers", "as_case",
           "default_fillers", "evaluate_run", "parse_fillers", "prepare_case", "resolve_params", "run_comparison"]

#: One INFO record per run (case, filler, status, holes closed, seconds); a child of the package's
#: ``logging.getLogger("meshlab_holefill")``.
logger = logging.getLogger(__name__)


# ------------------------------------------------------------------------------- measuring

@dataclass
class Comparison:
    """Everything a comparison measured (rows are plain dicts, ready for JSON/CSV)."""

    cases: list  # PreparedCase.summary() dicts
    fillers: list  # Filler
    runs: list  # one dict per (case, filler)
    holes: list  # one dict per (case, hole, filler)
    settings: dict
    wall_seconds: float
    render: dict = field(default_factory=dict)  # arrays for pictures, not saved


def _hole_entry(result, loop_index):
    for entry in result.get("holes", []) if isinstance(result, dict) else []:
        if isinstance(entry, dict) and entry.get("hole") == loop_index:
            return entry
    return None


# The pipeline's own entry fields (and the hole's measures), which are not the algorithm's figures.
_ENTRY_KEYS = {"hole", "boundary_edges", "pinched", "status", "reason", "seconds", "new_vertices", "new_faces",
               "centroid", "perimeter", "diameter", "area", "planarity", "size_class"}


def _patch_info(entry):
    """The algorithm's own per-hole figures (Patch.info: restarts, step times, ...) as ``info_*`` columns."""
    if not isinstance(entry, dict):
        return {}
    return {f"info_{key}": value for key, value in entry.items()
            if key not in _ENTRY_KEYS and isinstance(value, (bool, int, float, str))}


def _context_faces(V0, F0, loop):
    """Faces of the mesh around a hole, for pictures: within 1.7 hole radii of its centre."""
    P = V0[loop]
    c = P.mean(axis=0)
    radius = 1.7 * np.linalg.norm(P - c, axis=1).max()
    near = np.linalg.norm(V0[F0].mean(axis=1) - c, axis=1) < radius
    return F0[near]


def evaluate_run(case, filler, reply, resolved_params, full_metrics=True):
    """Turn one worker reply into a run row, hole rows and picture data.

    Parameters
    ----------
    case : PreparedCase
    filler : Filler
    reply : dict  :func:`.isolation.execute_task`'s reply (``V_new``/``F_new`` or ``V``/``F``, ``result``)
    resolved_params : dict  the parameters the filter ran with (:func:`resolve_params`)
    full_metrics : bool  all metrics, or only closed/reason/time/counts

    Returns
    -------
    run : dict  one row for the run
    holes : list of dict  one row per hole of the case
    pictures : dict  {hole index: {"V": (p, 3) float64, "F": (q, 3) int64, "quality": (q,), "face_distance": (q,)}}
    """
    V0, F0 = case.V0, case.F0
    run = {"case": case.name, "filler": filler.label, "filter": filler.filter,
           "params": json_safe(resolved_params), "status": reply["status"], "error": reply.get("error"),
           "seconds": reply.get("seconds"), "memory_mb": reply.get("memory_mb")}
    pictures = {}
    base = [{"case": case.name, "filler": filler.label, "filter": filler.filter, "hole": h.index,
             "size_class": h.size_class, "shape": h.shape, "boundary_edges": h.boundary_edges,
             "ground_truth": h.ground_truth is not None, "quality_bound": h.quality_bound,
             "run_seconds": reply.get("seconds")} for h in case.holes]
    if reply["status"] != "ok":
        for row in base:
            row.update(closed=False, reason=f"{reply['status']}: {reply.get('error')}")
        run["closed_holes"] = 0
        return run, base, pictures
    if "V" in reply:
        V1, F1 = np.asarray(reply["V"], np.float64), np.asarray(reply["F"], np.int64)
    else:
        V1 = np.concatenate([V0, np.asarray(reply["V_new"], np.float64).reshape(-1, 3)])
        F1 = np.concatenate([F0, np.asarray(reply["F_new"], np.int64).reshape(-1, 3)])
    result = reply.get("result") or {}
    if result.get("stage_seconds"):
        run["stage_seconds"] = result["stage_seconds"]
    if full_metrics:
        checks, hits = mesh_checks(V0, F0, V1, F1, return_hits=True)
    else:
        checks = {"new_faces": int(len(F1) - len(F0)), "new_vertices": int(len(V1) - len(V0))}
        hits = np.zeros(0, np.int64)
    run.update(checks)
    he1, _ = boundary_halfedges(F1)
    # Xu et al.'s boundary pre-treatment appends the split halves of border faces before the
    # patches: they are original surface, not patch.
    first_patch_face = len(F0) + int(result.get("split_boundary_edges", 0) or 0)
    patches = assign_patches(F1[first_patch_face:], [h.loop for h in case.holes])
    max_size = resolved_params.get("maxholesize", 30 if filler.filter == BASELINE else 1000)
    closed_count = 0
    for position, (h, row) in enumerate(zip(case.holes, base)):
        entry = _hole_entry(result, h.loop_index)
        open_left = bool(np.isin(he1, h.loop).all(axis=1).any())
        patch_idx = first_patch_face + patches[position]
        closed = (not open_left) and len(patch_idx) > 0
        if entry is not None and entry.get("seconds") is not None:
            row["seconds"] = entry["seconds"]
        row.update(_patch_info(entry))
        if not closed:
            if entry is not None and entry.get("status") != "closed":
                reason = f"{entry.get('status')}: {entry.get('reason', '')}"
            elif isinstance(max_size, (int, float)) and h.boundary_edges >= max_size:
                reason = f"skipped: {h.boundary_edges} edges >= maxholesize {max_size}"
            else:
                reason = "left open by the filter" + (" (no patch)" if len(patch_idx) == 0 else " (patch incomplete)")
            row.update(closed=False, reason=reason)
            continue
        closed_count += 1
        row.update(closed=True, reason="", originals_changed=checks.get("originals_changed"))
        if full_metrics:
            metrics, arrays = hole_metrics(V0, F0, V1, F1[patch_idx], h.loop, h.border, h.ground_truth,
                                           case.diag, case.analytic)
            metrics["intersecting_new_faces"] = int(np.isin(hits, patch_idx).sum())
            row.update(metrics)
            pV, pF = compact_mesh(V1, F1[patch_idx])
            pictures[h.index] = {"V": pV, "F": pF, **arrays}
        else:
            used = np.unique(F1[patch_idx].ravel())
            row.update(faces=int(len(patch_idx)), new_vertices=int(np.count_nonzero(used >= len(V0))))
    run["closed_holes"] = closed_count
    return run, base, pictures


def short_filler(label):
    """A filler label without the common ``meshing_close_holes_`` prefix (for the progress bar)."""
    return label.replace("meshing_close_holes_", "")


def _progress_bar(total, progress):
    """A tqdm bar over the runs on stderr, or None.

    ``progress`` None (the default) shows it when stderr is a terminal, True always, False never.
    """
    if progress is None:
        progress = bool(getattr(sys.stderr, "isatty", lambda: False)())
    if not progress:
        return None
    from tqdm import tqdm

    return tqdm(total=total, unit="run", file=sys.stderr, dynamic_ncols=True)


def _log_run(run, holes, number, total):
    """One INFO record per run on the ``meshlab_holefill`` logger (its extra fields carry the run row)."""
    seconds = run.get("seconds")
    logger.info("compare run %d/%d: %s / %s: %s, %d/%d holes closed, %s s%s", number, total, run["case"],
                run["filler"], run["status"], run.get("closed_holes", 0), holes,
                "?" if seconds is None or seconds != seconds else f"{seconds:.2f}",
                "" if run["status"] == "ok" else f" ({run.get('error')})",
                extra={"comparison_run": {k: v for k, v in run.items()}})


def resolve_params(filler, cases):
    """The filler's parameters for these cases ("all" -> a maxholesize covering every hole).

    Parameters
    ----------
    filler : Filler
    cases : list of PreparedCase

    Returns
    -------
    dict
    """
    params = dict(filler.params)
    if params.get("maxholesize") == "all":
        largest = max([h.boundary_edges for c in cases for h in c.holes] or [3])
        params["maxholesize"] = int(largest) + 1
    return params


def run_comparison(meshes, holes=4, sizes=("small", "medium", "large"), seed=0, filters=None, refinehole=False,
                   timeout=300.0, maxholesize=1000, progress=None, full_metrics=True, cases=None):
    """Prepare the cases, run every filler on each in an isolated worker, measure.

    Parameters are those of :func:`.compare.compare` (``progress``: a tqdm bar per run on stderr,
    None = when stderr is a terminal; each run is also logged at INFO); ``cases`` may pass
    already prepared cases (then ``meshes`` is ignored), ``full_metrics=False`` keeps only
    closed/reason/time/counts (for the scaling run).

    Returns
    -------
    Comparison
    """
    t_start = time.perf_counter()
    sizes = tuple(sizes.split(",")) if isinstance(sizes, str) else tuple(sizes)
    unknown = [s for s in sizes if s not in SIZE_CLASSES]
    if unknown:
        raise ValueError(f"unknown hole size {unknown}; choose from {', '.join(SIZE_CLASSES)}")
    if cases is None:
        cases = [prepare_case(as_case(m, i), holes, sizes, seed, maxholesize) for i, m in enumerate(meshes)]
    fillers = filters if filters and isinstance(filters[0], Filler) else parse_fillers(filters, refinehole)
    runs, rows, render = [], [], {}
    for case in cases:
        for h in case.holes:
            render[(case.name, h.index)] = {"context": _context_faces(case.V0, case.F0, h.loop), "V0": case.V0,
                                            "ground_truth": h.ground_truth, "loop": h.loop, "patches": {}}
    jobs = [(c, f) for c in cases for f in fillers]
    bar = _progress_bar(len(jobs), progress)
    with IsolatedRunner() as runner:
        for number, (case, filler) in enumerate(jobs, 1):
            if bar is not None:
                bar.set_description(f"{case.name} | {short_filler(filler.label)}"[:50])
            params = resolve_params(filler, cases)
            kind = "anchor" if is_anchor(filler.filter) else "filter"
            missing = missing_package(filler.filter) if kind == "anchor" else None
            if missing:  # not installed: a note in the report, no worker run
                reply = {"status": "skipped", "error": missing, "seconds": None}
            else:
                task = {"kind": kind, "V": case.V0, "F": case.F0, "filter": filler.filter, "params": params,
                        "label": case.name}
                reply = runner.run(task, timeout)
            run, hole_rows, pictures = evaluate_run(case, filler, reply, params, full_metrics)
            runs.append(run)
            rows += hole_rows
            for index, pic in pictures.items():
                render[(case.name, index)]["patches"][filler.label] = pic
            _log_run(run, len(case.holes), number, len(jobs))
            if bar is not None:
                bar.set_postfix_str(f"{run['status']}, {run['closed_holes']}/{len(case.holes)} closed", refresh=False)
                bar.update()
    if bar is not None:
        bar.close()
    settings = {"holes": holes, "sizes": list(sizes), "seed": seed, "timeout": timeout, "maxholesize": maxholesize,
                "refinehole": refinehole, "fillers": [{"label": f.label, "filter": f.filter,
                                                       "params": json_safe(resolve_params(f, cases))}
                                                      for f in fillers],
                "cores": os.cpu_count()}
    return Comparison([c.summary() for c in cases], fillers, runs, rows, settings,
                      time.perf_counter() - t_start, render)
