"""Running a comparison: the meshes (cases), the fillers, isolated runs, and the measurements.

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
from scipy.sparse.csgraph import connected_components

from ..core.holes import boundary_halfedges, boundary_loops
from ..core.outlines import OUTLINE_RATIO, outline_ratios
from ..geometry.topology import face_adjacency
from ..meshlab.mesh_files import is_mesh, load_mesh, mesh_arrays
from ..meshlab.registration import filter_list, is_builtin_filter, parse_text_value
from .anchors import ANCHORS, is_anchor, missing_package
from .cut_holes import SIZE_CLASSES, cut_holes, hole_plan
from .isolation import IsolatedRunner, json_safe
from .metrics import assign_patches, compact_mesh, corner_quality_bound, hole_metrics, mesh_checks

__all__ = ["BASELINE", "Comparison", "Filler", "Hole", "MeshCase", "PreparedCase", "anchor_fillers", "as_case",
           "default_fillers", "evaluate_run", "parse_fillers", "prepare_case", "resolve_params", "run_comparison"]

BASELINE = "meshing_close_holes"

#: One INFO record per run (case, filler, status, holes closed, seconds); a child of the package's
#: ``logging.getLogger("meshlab_holefill")``.
logger = logging.getLogger(__name__)


# ----------------------------------------------------------------------------------- cases

@dataclass
class MeshCase:
    """A mesh to compare fillers on.

    Attributes
    ----------
    name : str
    V : (n, 3) float64, F : (m, 3) int
    analytic : callable, optional
        (N, 3) points -> (N,) distance to the exact surface the mesh samples (sphere, torus).
    removed : (m,) bool, optional
        Faces to remove as holes with ground truth (instead of holes cut at random).
    surface_area : float, optional  area of the analytic surface (Xu et al.'s error normalisation)
    given_class : str  size class of the ``removed`` holes in the report ("given"; the creased cases
        of :mod:`.creased` use "crease" and "crossing")
    """

    name: str
    V: np.ndarray
    F: np.ndarray
    analytic: object = None
    removed: np.ndarray | None = None
    surface_area: float | None = None
    given_class: str = "given"


@dataclass
class Hole:
    """One evaluated hole of a prepared case."""

    index: int  # the hole's number: its boundary loop index, as in `meshlab-holefill holes` and fill results
    size_class: str
    shape: str
    boundary_edges: int
    loop: np.ndarray  # (k,) ordered boundary vertices (indices into the case's V0)
    loop_index: int  # position among boundary_loops(F0), as in our filters' result['holes'] (== index)
    border: tuple  # ((k, 2) int64 half-edges, (k,) int64 faces) in F0
    ground_truth: tuple | None = None  # ((n0 + g, 3), (r, 3)) indexed like a filled mesh
    quality_bound: float = 1.0  # metrics.corner_quality_bound: best reachable minimum quality


@dataclass
class PreparedCase:
    """A case ready to run: the mesh with its holes (V0, F0), the evaluated holes, notes.

    Attributes
    ----------
    name : str
    kind : str  "cut holes", "natural holes" or "given holes"
    V0 : (n0, 3) float64, F0 : (m0, 3) int64  the mesh the fillers get
    diag : float  bounding-box diagonal of the source mesh (per-mille figures)
    holes : list of Hole
    notes : list of str  holes that could not be cut or are not evaluated, and why
    analytic, surface_area : as in MeshCase
    source_faces : int  faces of the source mesh before holes were cut
    """

    name: str
    kind: str  # "cut holes" | "natural holes" | "given holes"
    V0: np.ndarray
    F0: np.ndarray
    diag: float
    holes: list
    notes: list = field(default_factory=list)
    analytic: object = None
    surface_area: float | None = None
    source_faces: int = 0

    def summary(self):
        return {"case": self.name, "kind": self.kind, "vertices": int(len(self.V0)), "faces": int(len(self.F0)),
                "source_faces": self.source_faces, "bbox_diagonal": self.diag, "notes": list(self.notes),
                "holes": [{"hole": h.index, "size_class": h.size_class, "shape": h.shape,
                           "boundary_edges": h.boundary_edges, "ground_truth": h.ground_truth is not None,
                           "quality_bound": h.quality_bound}
                          for h in self.holes]}


def as_case(mesh, index=0):
    """A MeshCase from a path, pymeshlab.Mesh (or MeshSet: its current mesh), (V, F) tuple or MeshCase.

    Parameters
    ----------
    mesh : str, os.PathLike, pymeshlab.Mesh, pymeshlab.MeshSet, ((n, 3) float, (m, 3) int) or MeshCase
    index : int  names an unnamed mesh ``mesh{index}``

    Returns
    -------
    MeshCase
    """
    if isinstance(mesh, MeshCase):
        return mesh
    if isinstance(mesh, (str, os.PathLike)):
        V, F = load_mesh(mesh)
        return MeshCase(os.path.basename(str(mesh)), V, F)
    if isinstance(mesh, tuple) and len(mesh) == 2:
        return MeshCase(f"mesh{index}", np.asarray(mesh[0], np.float64), np.asarray(mesh[1], np.int64))
    if is_mesh(mesh):
        return MeshCase(f"mesh{index}", *mesh_arrays(mesh))
    raise TypeError(f"cannot compare on {type(mesh).__name__}: give a path, (V, F), pymeshlab.Mesh or MeshCase")


def _with_ground_truth(V, F, removed_groups):
    """Mesh without the removed faces, and each removed group as ground truth indexed like a fill.

    Parameters
    ----------
    removed_groups : list of (r_i,) int  face indices into F, one group per hole

    Returns
    -------
    V0 (n0, 3), F0 (m0, 3), truths: list of ((n0 + g, 3) float64, (r, 3) int64)
    """
    keep = np.ones(len(F), bool)
    for group in removed_groups:
        keep[group] = False
    V0, F0 = compact_mesh(V, F[keep])
    used = np.unique(F[keep].ravel())
    truths = []
    for group in removed_groups:
        faces = F[group]
        remap = np.full(len(V), -1, np.int64)
        remap[used] = np.arange(len(used))
        interior = np.setdiff1d(np.unique(faces.ravel()), used)
        remap[interior] = len(V0) + np.arange(len(interior))
        truths.append((np.concatenate([V0, V[interior]]), remap[faces]))
    return V0, F0, truths


def _match_loops(F0, vertex_sets):
    """For each vertex set, the boundary loop of F0 lying in it (index, loop) or (-1, None)."""
    loops = boundary_loops(F0)
    out = []
    for verts in vertex_sets:
        found = (-1, None)
        for i, lp in enumerate(loops):
            if lp.closed and np.isin(lp.vertices, verts).all():
                found = (i, lp)
                break
        out.append(found)
    return out, loops


def _border(F0, he, hf, loop):
    mask = np.isin(he, loop).all(axis=1)
    return he[mask], hf[mask]


def prepare_case(case, holes=4, sizes=("small", "medium", "large"), seed=0, maxholesize=1000):
    """Holes with ground truth cut into a closed mesh, or the natural holes of an open one.

    Parameters
    ----------
    case : MeshCase
    holes : int  holes to cut into a closed mesh (sizes cycle, compact and irregular shapes alternate)
    sizes : sequence of str  keys of cut_holes.SIZE_CLASSES
    seed : int
    maxholesize : int  natural holes with more boundary edges are not evaluated

    Returns
    -------
    PreparedCase
    """
    V, F = np.asarray(case.V, np.float64), np.asarray(case.F, np.int64)
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    notes = []
    if case.removed is not None or not len(boundary_loops(F)):
        if case.removed is not None:
            kind = "given holes"
            removed = np.flatnonzero(np.asarray(case.removed, bool))
            if not len(removed):
                raise ValueError(f"case '{case.name}': removed marks no face, so it has no hole to fill")
            _, label = connected_components(face_adjacency(F[removed]), directed=False)
            groups = [removed[label == c] for c in np.unique(label)]
            specs = [(case.given_class, "given", None) for _ in groups]
        else:
            kind = "cut holes"
            plan = hole_plan(holes, sizes)
            _, cut = cut_holes(V, F, sizes=[s for s, _ in plan], shapes=[sh for _, sh in plan], seed=seed,
                               strict=False)
            if len(cut) < len(plan):
                got, missing = [(h.size_class, h.shape) for h in cut], []
                for wanted in plan:
                    if wanted in got:
                        got.remove(wanted)
                    else:
                        missing.append(wanted)
                notes.append("could not cut " + ", ".join(f"{s} {sh}" for s, sh in missing)
                             + " hole(s) (no room for a simple hole of that size)")
            groups = [h.face_indices for h in cut]
            specs = [(h.size_class, h.shape, h.boundary_edges) for h in cut]
        V0, F0, truths = _with_ground_truth(V, F, groups)
        vertex_sets = [np.unique(t[1])[np.unique(t[1]) < len(V0)] for t in truths]
        matches, _ = _match_loops(F0, vertex_sets)
        he, hf = boundary_halfedges(F0)
        out = []
        for (size, shape, _), truth, (li, lp) in zip(specs, truths, matches):
            if lp is None:
                notes.append(f"a {size} hole did not leave a simple boundary loop; left out")
                continue
            out.append(Hole(li, size, shape, len(lp), lp.vertices, li, _border(F0, he, hf, lp.vertices),
                            truth, corner_quality_bound(V0, F0, lp.vertices)))
        out.sort(key=lambda h: h.index)  # numbered and listed as `meshlab-holefill holes` lists the loops
    else:
        kind = "natural holes"
        V0, F0 = V, F
        loops = boundary_loops(F0)
        he, hf = boundary_halfedges(F0)
        outline = outline_ratios(V0, F0, loops) >= OUTLINE_RATIO
        out = []
        for i, lp in enumerate(loops):
            if not lp.closed or lp.pinched or len(lp) < 3 or len(lp) > maxholesize:
                why = ("open chain" if not lp.closed else "pinched (non-manifold vertex)" if lp.pinched
                       else f"{len(lp)} edges > maxholesize {maxholesize}" if len(lp) > maxholesize else "degenerate")
                notes.append(f"boundary loop {i} ({len(lp)} edges) not evaluated: {why}")
                continue
            # An island's outline is listed apart: capping it folds over the island (outlines.outline_ratios).
            kind_of = "outline" if outline[i] else "natural"
            out.append(Hole(i, kind_of, kind_of, len(lp), lp.vertices, i,
                            _border(F0, he, hf, lp.vertices), None, corner_quality_bound(V0, F0, lp.vertices)))
    return PreparedCase(case.name, kind, V0, F0, diag, out, notes, case.analytic, case.surface_area, len(F))


# ---------------------------------------------------------------------------------- fillers

@dataclass
class Filler:
    """A filter with fixed parameters, as one contestant of the comparison."""

    label: str
    filter: str
    params: dict = field(default_factory=dict)


def _parse_value(text):
    # "all" (maxholesize covering every hole), enum names and "5%" stay text here.
    return parse_text_value(text, percentages=False)


def _resolve_name(name):
    ours = filter_list()
    if name in ours or name == BASELINE or is_anchor(name) or is_builtin_filter(name):
        return name
    matches = [f for f in ours if f.endswith(name) or f.endswith("_" + name)]
    if len(matches) == 1:
        return matches[0]
    raise ValueError(f"unknown filter '{name}' (ours: {', '.join(ours)}; third-party: {', '.join(ANCHORS)}; "
                     "or any pymeshlab filter name)")


def default_fillers(refinehole=False):
    """Every registered filter of ours with its defaults, the third-party anchors, MeshLab's Close Holes twice.

    The anchors (:data:`.anchors.ANCHORS`: ``cgal_liepa``, ``pymeshfix``) get ``maxholesize``
    "all"; one whose package is not installed is skipped with a note when the comparison runs.

    ``meshing_close_holes`` runs with its defaults (holes up to 30 edges) and with a
    ``maxholesize`` covering every hole ("all", resolved per comparison), optionally also with
    ``refinehole=True``.

    Returns
    -------
    list of Filler
    """
    out = [Filler(name, name) for name in filter_list()]
    out += anchor_fillers()
    out += [Filler(f"{BASELINE} (default)", BASELINE),
            Filler(f"{BASELINE} (all holes)", BASELINE, {"maxholesize": "all"})]
    if refinehole:
        out.append(Filler(f"{BASELINE} (all holes, refined)", BASELINE, {"maxholesize": "all", "refinehole": True}))
    return out


def anchor_fillers():
    """The third-party fillers with their defaults and a ``maxholesize`` covering every hole.

    Returns
    -------
    list of Filler
    """
    return [Filler(name, name, {"maxholesize": "all"}) for name in ANCHORS]


def parse_fillers(spec, refinehole=False):
    """Fillers from ``--filters`` text.

    Entries are separated by commas (or given as a list); each is ``name`` or
    ``name:param=value[:param=value...]`` (a comma-separated ``param=value`` right after an
    entry also belongs to it). ``name`` may be a unique suffix of one of our filters
    (``min_angle_bilateral``); ``ours`` means all registered filters of ours, ``anchors`` the
    third-party fillers (``cgal_liepa``, ``pymeshfix``; each also by name) and ``baseline``
    the two ``meshing_close_holes`` variants. ``maxholesize=all`` covers every hole; the
    anchors get it unless their ``maxholesize`` is given.

    Returns
    -------
    list of Filler
    """
    if spec is None or spec == "" or spec == []:
        return default_fillers(refinehole)
    items = spec if isinstance(spec, (list, tuple)) else [spec]
    tokens = [t.strip() for item in items for t in str(item).split(",") if t.strip()]
    entries = []
    for tok in tokens:
        if "=" in tok and ":" not in tok and entries:
            entries[-1].append(tok)
        else:
            entries.append(tok.split(":"))
    out = []
    for name, *assignments in entries:
        params = {}
        for a in assignments:
            if "=" not in a:
                raise ValueError(f"filter parameter '{a}' of '{name}' must be param=value")
            key, value = a.split("=", 1)
            params[key.strip()] = _parse_value(value.strip())
        if name == "ours":
            out += [Filler(n, n, dict(params)) for n in filter_list()]
            continue
        if name == "baseline":
            out += [f for f in default_fillers(refinehole) if f.filter == BASELINE]
            continue
        if name == "anchors":
            out += [Filler(f.label, f.filter, {**f.params, **params}) for f in anchor_fillers()]
            continue
        full = _resolve_name(name)
        if is_anchor(full):
            label = full if not params else f"{full} ({', '.join(f'{k}={v}' for k, v in params.items())})"
            out.append(Filler(label, full, {"maxholesize": "all", **params}))
            continue
        label = full if not params else f"{full} ({', '.join(f'{k}={v}' for k, v in params.items())})"
        out.append(Filler(label, full, params))
    labels = [f.label for f in out]
    dupes = {x for x in labels if labels.count(x) > 1}
    if dupes:
        raise ValueError(f"filter given twice: {', '.join(sorted(dupes))}")
    return out


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
