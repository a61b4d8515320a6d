"""The per-hole pipeline every filter shares, on arrays: find holes, fill each, validate, check, merge.

An algorithm only provides ``fill(ctx, **params) -> Patch`` on one :class:`HoleContext`;
this module does the rest of the filter contract: hole selection by size and selection,
all-or-nothing per hole, patch validation, the optional self-intersection check, bit-exact
originals, attributes carried over, and the per-hole report. The MeshSet filters
(meshlab.close_holes) and the array API (:func:`meshlab_holefill.fill_holes`) both call
:func:`fill_mesh_holes`.
"""
from __future__ import annotations

import logging
import time

import numpy as np

from dataclasses import dataclass

from .content_key import content_key
from .attributes import MeshArrays, check_faces_joined, check_manifold_edges, extend_attributes, refine_mesh_arrays
from .crossings import (clashing_patches, context_crossings, crossing_patches, face_boxes_near, load_crossing_kernels,
                        patch_box, patch_intersections)
from .face_grid import face_grid
from .parallel import FILL_ERRORS, fill_one, reason_of, run_jobs, worker_count
from .kernel_cache import refresh_kernel_cache_once
from .holes import boundary_loops, edge_summary, hole_context, vertex_face_incidence
from .failure_reasons import explain_folded_surroundings, explain_outlines
from .outlines import loops_measured, outlines_one_face, pinch_vertices
from .parameters import ParamSpec, Percentage
from .patch import load_validation_kernel, merge_patches

__all__ = ["COMMON_PARAMS", "FilledMesh", "fill_mesh_holes"]

# One INFO record per hole when a filter is done (its number, edges, status, reason, time); a child of the
# package logger "meshlab_holefill", which library users configure.
_LOG = logging.getLogger(__name__)

COMMON_PARAMS = [
    ParamSpec("maxholesize", "int", 1000,
              "Largest hole to close, as its number of boundary edges; larger holes are skipped "
              "(MeshLab's Close Holes uses 30; these algorithms target large holes, hence 1000).",
              minimum=3, mlx_name="MaxHoleSize", display="Max size to be closed"),
    ParamSpec("maxholediameter", "length", Percentage(100),
              "Largest hole to close, as the diameter of its boundary loop (a length, or a percentage of the "
              "bounding-box diagonal); larger holes are skipped. The default allows every hole.",
              minimum=0.0, mlx_name="MaxHoleDiameter", display="Max diameter to be closed"),
    ParamSpec("selected", "bool", False,
              "Close only holes with at least one selected border face.",
              mlx_name="Selected", display="Close holes with selected faces"),
    ParamSpec("newfaceselected", "bool", True,
              "Select the new faces after filling (the original selection is kept).",
              mlx_name="NewFaceSelected", display="Select the newly created faces"),
    ParamSpec("selfintersection", "bool", True,
              "Reject a patch that intersects the existing mesh or itself; the hole is then reported failed. "
              "A patch crossing faces beyond the ones its filter looked at is first filled again, avoiding them.",
              mlx_name="SelfIntersection", display="Prevent creation of selfIntersecting faces"),
    ParamSpec("filloutlines", "bool", False,
              "Also cap loops that outline a whole connected component (an island of a range scan, a loose "
              "fragment, a fragment held by one vertex, the rim of a scan whose surface lies inside it): such a "
              "loop is not a hole, and its cap would lie over the fragment, so by default it is skipped.",
              mlx_name="FillOutlines", display="Fill island outlines"),
    ParamSpec("workers", "int", 0,
              "Processes filling holes at once: 0, one per CPU when the holes are worth it (a run of a few "
              "small holes is faster in one process); 1, in this process. The mesh is the same whatever "
              "the number.",
              minimum=0, mlx_name="Workers", display="Worker processes"),
    ParamSpec("timelimit", "float", 0.0,
              "Seconds one hole may take (0: no limit); a hole that takes longer is reported failed.",
              minimum=0.0, mlx_name="TimeLimit", display="Time limit per hole (s)"),
]


@dataclass
class FilledMesh:
    """A mesh after :func:`fill_mesh_holes`: originals first (bit-exact), then the new elements.

    Attributes
    ----------
    source : MeshArrays
        The mesh the holes were filled in (after any border refinement).
    V : (n2, 3) float64
    F : (m2, 3) int32 or int64
        The integer type of the mesh given (after border refinement, int64).
    vertex_attrs, face_attrs : dict name -> array  (rows for V, F)
    wedge_texcoords : (3 m2, 2) float64 or None
    select_faces : (k,) int64 or None
        Rows of F to select (the new faces, with ``newfaceselected``).
    changed : bool
        Whether anything differs from the mesh given (a patch merged or a border refined).
    """

    source: MeshArrays
    V: np.ndarray
    F: np.ndarray
    vertex_attrs: dict
    face_attrs: dict
    wedge_texcoords: np.ndarray | None
    select_faces: np.ndarray | None
    changed: bool

    def release_source(self):
        """Let the source mesh's own arrays go: ``source`` then holds views of the leading rows here.

        The filled arrays begin with the originals, bit-exact, so nothing is lost; a caller
        that drops its own references to the source frees one whole copy of the mesh (at
        3.6M faces about 160 MB) before the filled mesh is handed to pymeshlab.
        """
        s = self.source
        n, m = len(s.V), len(s.F)
        self.source = MeshArrays(
            V=self.V[:n], F=self.F[:m], vertex_attrs={name: A[:n] for name, A in self.vertex_attrs.items()},
            face_attrs={name: A[:m] for name, A in self.face_attrs.items()},
            wedge_texcoords=None if self.wedge_texcoords is None else self.wedge_texcoords[:3 * m],
            label=s.label, mesh_id=s.mesh_id, textures=s.textures, transform=s.transform,
            vertex_selected=s.vertex_selected)


class _StageClock:
    """Seconds by stage of a run: ``stage(name)`` ends the stage ``name`` (its time adds up) and starts the next."""

    def __init__(self):
        self.seconds = {}
        self._last = time.perf_counter()

    def __call__(self, name):
        now = time.perf_counter()
        self.seconds[name] = self.seconds.get(name, 0.0) + now - self._last
        self._last = now


def fill_mesh_holes(arrays, fill, params, *, algorithm_params=(), rings=3, prepare=None, warm_up=None,
                    seconds_per_edge=None, progress=None):
    """Run one hole-filling algorithm on every eligible hole of a mesh given as arrays.

    Parameters
    ----------
    arrays : MeshArrays
        The mesh and its attributes (``face_attrs['selected']`` for ``selected``).
    fill : callable ``fill(ctx, **algorithm_params) -> Patch``
    params : dict
        Validated filter parameters (common ones and the algorithm's).
    algorithm_params : iterable of str
        Names in ``params`` passed on to ``fill``.
    rings : int
        Face rings of surrounding mesh each HoleContext carries.
    prepare : callable, optional
        ``prepare(V, F, loops, params) -> refinement or None``, the algorithm module's
        ``PREPARE``: refines the borders of the holes to be filled before any is filled
        (the only way a filter may change original faces: the surface must stay the same,
        original vertices keep positions and order). ``refinement`` has ``V``, ``F``
        (originals first, split faces' second children after the m original rows),
        ``loops`` (the refined loops, in the order given), ``edge_vertices``,
        ``edge_weights``, ``face_parents`` (see :func:`.attributes.refine_mesh_arrays`) and
        ``split_counts``. When a hole with a refined border fails, the holes are filled
        again without it, so its border is left as it was.
    warm_up : callable, optional
        The algorithm module's ``WARM_UP``: loads its compiled kernels, called once before the
        holes are filled, so that forked workers inherit them instead of each loading them
        within its first hole's time; it also drops what the algorithm kept from an earlier run.
    seconds_per_edge : float, optional
        The algorithm module's ``SECONDS_PER_EDGE``: its fill time per boundary edge with the
        defaults, from which ``workers=0`` judges whether forking workers pays
        (:func:`.parallel.worker_count`); without it ``workers=0`` is one per CPU.

    Returns
    -------
    filled : FilledMesh
        The filled mesh and its attributes.
    result : dict
        ``closed_holes``, ``new_faces``, ``new_vertices``, ``skipped_holes``,
        ``failed_holes``, ``holes`` (per-hole dicts), ``seconds`` and ``stage_seconds`` (the run's
        seconds by stage: "edge table" (each edge's faces, the mesh's edges checked), "boundary
        loops", "hole selection" (each loop's measures and class), "kernels", "holes" (filled,
        checked and merged), "attributes"); with ``prepare`` also
        ``split_boundary_edges`` (new faces and vertices then count the patches only; the
        split faces' second children are rows m .. m + split_boundary_edges - 1).
    """
    t_start = time.perf_counter()
    stage = _StageClock()
    V, F = arrays.V, arrays.F
    he, he_faces, bad_edges = edge_summary(F)
    check_manifold_edges(F, arrays.label, bad_edges)
    check_faces_joined(F, len(he), arrays.label)
    stage("edge table")
    loops = boundary_loops(F, (he, he_faces))
    stage("boundary loops")
    incidence = vertex_face_incidence(F, len(V)) if len(loops) else None
    report, todo = _select_holes(V, F, loops, params, arrays.face_attrs["selected"].ravel() > 0, incidence)
    stage("hole selection")
    fill_kwargs = {name: params[name] for name in algorithm_params}
    base = (arrays, list(loops), [dict(entry) for entry in report], incidence)
    fills = {}  # hole -> outcome of its fill, reused by a later pass while its surroundings are the same
    if todo:  # kernels the fills use, loaded before any worker forks
        refresh_kernel_cache_once()
        load_validation_kernel()
        if warm_up is not None:
            warm_up()
    stage("kernels")
    while True:
        arrays, V, F, V2, F2, done_loops, patches, refinement, report = _fill_holes(
            base, todo, params, fill, fill_kwargs, rings, prepare, fills, seconds_per_edge, progress)
        # A hole whose border was refined and which then failed would leave its split border
        # faces behind: fill again with that hole left out, so nothing of it is changed.
        undo = [i for i in todo if report[i]["status"] == "failed" and report[i].get("split_boundary_edges")]
        if not undo:
            break
        for i in undo:
            base[2][i] = dict(report[i], split_boundary_edges=0)
        todo = [i for i in todo if i not in undo]
    explain_folded_surroundings(base[0].V, base[0].F, base[1], report, incidence)
    stage("holes")
    n_new_faces = len(F2) - len(F)
    if n_new_faces:
        vattrs, fattrs, wedge = extend_attributes(arrays, V2, F2, done_loops, [len(p.vertices) for p in patches])
    else:  # borders refined, or nothing closed
        vattrs, fattrs, wedge = arrays.vertex_attrs, arrays.face_attrs, arrays.wedge_texcoords
    select = np.arange(len(F), len(F2)) if params["newfaceselected"] else None
    filled = FilledMesh(arrays, V2, F2, vattrs, fattrs, wedge, select,
                        changed=bool(n_new_faces) or refinement is not None)
    stage("attributes")
    statuses = [h["status"] for h in report]
    result = {
        "closed_holes": statuses.count("closed"),
        "new_faces": int(n_new_faces),
        "new_vertices": int(len(V2) - len(V)),
        "skipped_holes": statuses.count("skipped"),
        "failed_holes": statuses.count("failed"),
        "holes": report,
        "seconds": time.perf_counter() - t_start,
        "stage_seconds": stage.seconds,
    }
    if prepare is not None:
        result["split_boundary_edges"] = int(len(refinement.edge_weights)) if refinement is not None else 0
    if _LOG.isEnabledFor(logging.INFO):
        for h in report:
            closed = f", {h['new_faces']} new faces" if h["status"] == "closed" else ""
            took = f" in {h['seconds']:.2f} s" if "seconds" in h else ""
            why = f": {h['reason']}" if h.get("reason") else ""
            _LOG.info("hole %d (%d edges): %s%s%s%s", h["hole"], h["boundary_edges"], h["status"], closed, took, why)
    return filled, result


def _select_holes(V, F, loops, params, selected_faces, incidence):
    """Per-hole report entries with their measures, and the holes to fill (by the filter's parameters)."""
    report, todo = [], []
    measured = loops_measured(V, F, loops, incidence)
    for i, loop in enumerate(loops):
        entry = {"hole": i, "boundary_edges": loop.edge_count, "pinched": bool(loop.pinched)}
        if i in measured:
            entry.update(measured[i][0])
            entry["size_class"] = measured[i][1]
        if not loop.closed:
            entry.update(status="skipped", reason="open boundary chain (inconsistent face orientation): run "
                                                  "meshing_re_orient_faces_coherently first")
        elif len(loop) < 3:
            entry.update(status="skipped", reason="degenerate loop with fewer than 3 edges")
        elif outlines_one_face(loop):
            entry.update(status="skipped", reason="the loop outlines a single face (all three of its edges are "
                                                  "border edges): its only fill is a second copy of that face")
        elif len(loop) > params["maxholesize"]:
            entry.update(status="skipped", reason=f"too large ({len(loop)} > maxholesize {params['maxholesize']})")
        elif entry["diameter"] > params["maxholediameter"]:
            entry.update(status="skipped", reason=f"too large (diameter {entry['diameter']:.6g} > maxholediameter "
                                                  f"{params['maxholediameter']:.6g})")
        elif params["selected"] and not selected_faces[loop.border_faces].any():
            entry.update(status="skipped", reason="not selected")
        elif entry["size_class"] == "outline" and not params["filloutlines"]:
            entry.update(status="skipped", reason="island outline: the loop outlines its whole component, which it "
                                                  "would cap with a second sheet (filloutlines=True fills it)")
        else:
            todo.append(i)
        report.append(entry)
    return report, todo


def _context_key(ctx):
    """Fingerprint of everything a fill can see of its hole: the local vertices and faces.

    The algorithms read only the HoleContext's local arrays (normals, scales and the rest
    derive from these), and they are deterministic, so an equal key means an equal outcome.
    """
    return content_key(ctx.vertices, ctx.faces, ctx.border_faces, ctx.forbidden_edges, ctx.depth,
                       np.array([bool(ctx.pinched)]))


# Building a face grid takes about as long as 9 scans of the faces for one patch box (measured at
# 0.9M faces: 35-45 ms against 4-5 ms), and it is built before the workers fork while the scans
# are shared among them: with workers checking their own patches it pays from 9 holes per worker.
GRID_SCANS = 9


def _fill_holes(base, todo, params, fill, fill_kwargs, rings, prepare, fills, seconds_per_edge=None, progress=None):
    """One pass of :func:`close_holes` over the holes ``todo``: refine, fill, check, merge.

    ``base`` is (arrays, loops, report entries, vertex-face incidence) of the mesh as given; nothing is written to
    the MeshSet here. ``fills`` maps a hole to (context key, patch or failure reason, seconds)
    of an earlier pass: a hole whose surroundings did not change is not filled again (a
    second pass only undoes the border refinement of holes that failed, and on face000.ply
    with LS-SVM refilling every hole doubled the run).
    """
    arrays, loops, report, incidence = base[0], list(base[1]), [dict(entry) for entry in base[2]], base[3]
    arrays, incidence, refinement = _prepared_borders(arrays, loops, report, incidence, todo, params, prepare)
    V, F = arrays.V, arrays.F
    # A hole met in an earlier pass is filled again only where its surroundings changed.
    refill = [i for i in todo if i not in fills or fills[i][0] != _key_here(V, F, loops[i], incidence, rings, i)]
    # Largest holes first: the run ends when its longest fill does, so start that one early.
    order = sorted(refill, key=lambda i: -len(loops[i]))
    estimate = None if seconds_per_edge is None else seconds_per_edge * sum(len(loops[i]) for i in order)
    workers = worker_count(params["workers"], len(order), estimate)
    # With workers each checks its own patches against the mesh, instead of waiting for every fill here.
    check_in_job = params["selfintersection"] and workers > 1
    grid = None
    if params["selfintersection"] and order:
        load_crossing_kernels(F)  # for faces of F's type; forked workers inherit them
    if check_in_job and len(order) >= GRID_SCANS * workers:
        grid = face_grid(V, F)  # the workers inherit it, and its kernels

    def fill_hole(i):
        """(context key, patch or failure reason, seconds, mesh crossings or None) of hole ``i``."""
        t0 = time.perf_counter()
        try:
            ctx = hole_context(V, F, loops[i], incidence, rings=rings, index=i)
        except FILL_ERRORS as exc:
            return None, reason_of(exc), time.perf_counter() - t0, None
        ctx.crossings_allowed = not params["selfintersection"]
        context_seconds = time.perf_counter() - t0
        outcome, seconds = fill_one(fill, ctx, fill_kwargs, params["timelimit"])
        key, crossed, seconds = _context_key(ctx), None, context_seconds + seconds
        if check_in_job and not isinstance(outcome, str):
            crossed = _mesh_crossings(V, F, ctx.loop, outcome, grid=grid)
            if crossed[0]:
                key = None  # the fill depends on more of the mesh than the context: never reused
                outcome, crossed, seconds = refill_clear(i, outcome, crossed, seconds, grid, ctx)
        return key, outcome, seconds, crossed

    def refill_clear(i, patch, crossed, seconds, grid=None, ctx=None):
        return _refill_clear_of_mesh(V, F, loops[i], incidence, rings, i, fill, fill_kwargs, params["timelimit"],
                                     patch, crossed, seconds, grid, ctx)

    def filled_one(position):  # run_jobs counts positions in ``order``; the caller wants hole ids
        progress(order[position], len(order))

    outcomes = run_jobs(fill_hole, order, workers, progress=filled_one if progress else None)
    checked = {}  # hole -> (mesh faces crossed, seconds) where the job checked its own patch
    for i, outcome in zip(order, outcomes):
        key, outcome, seconds, crossed = (None, outcome, 0.0, None) if isinstance(outcome, str) else outcome
        fills[i] = (key, outcome, seconds)
        if crossed is not None:
            checked[i] = crossed
    filled = []  # (hole id, loop vertices, patch, seconds) of patches that passed validation
    for i in todo:
        key, outcome, seconds = fills[i]
        if isinstance(outcome, str):
            report[i].update(status="failed", reason=outcome, seconds=seconds)
            continue
        filled.append((i, np.asarray(loops[i].vertices, np.int64), outcome, seconds))
    if params["selfintersection"]:
        for position in _check_here(V, F, filled, checked):
            i, loop, patch, seconds = filled[position]
            if checked[i][0]:
                fills[i] = (None,) + fills[i][1:]
                patch, checked[i], seconds = refill_clear(i, patch, checked[i], seconds)
                filled[position] = (i, loop, patch, seconds)
    V2, F2, done_loops, patches = _closed_patches(V, F, filled, checked, loops, report, incidence,
                                                 params["selfintersection"])
    return arrays, V, F, V2, F2, done_loops, patches, refinement, report


def _prepared_borders(arrays, loops, report, incidence, todo, params, prepare):
    """The algorithm's own preparation of the borders of the holes ``todo`` (``prepare``: LS-SVM's border split).

    ``loops`` and ``report`` are updated in place (the split loops, each hole's
    ``split_boundary_edges``).

    Returns
    -------
    arrays : MeshArrays  the mesh with the split border faces, or as given
    incidence : its vertex-face incidence
    refinement : the ``prepare`` result, or None
    """
    if prepare is None:
        return arrays, incidence, None
    refinement = None
    if todo:  # the algorithms' own steps see int64 faces, whatever the mesh holds
        refinement = prepare(arrays.V, np.asarray(arrays.F, np.int64), [loops[i] for i in todo], params)
    if refinement is None:
        for i in todo:
            report[i]["split_boundary_edges"] = 0
        return arrays, incidence, None
    arrays = refine_mesh_arrays(arrays, refinement)
    for i, loop, count in zip(todo, refinement.loops, refinement.split_counts):
        loops[i] = loop
        report[i]["split_boundary_edges"] = int(count)
    return arrays, vertex_face_incidence(arrays.F, len(arrays.V)), refinement


def _closed_patches(V, F, filled, checked, loops, report, incidence, selfintersection):
    """The validated patches that close their holes, merged into the mesh; the report entries updated.

    ``filled`` holds (hole id, loop vertices, patch, seconds) of the patches that passed validation,
    ``checked`` (mesh faces crossed, seconds) per hole. With ``selfintersection`` a patch crossing the mesh
    fails its hole, and of two patches that cross each other the later one is withdrawn
    (:func:`.crossings.crossing_patches`); so is the later of two that would leave an edge of a pinched
    vertex with more than two faces (:func:`.crossings.clashing_patches`).

    Returns
    -------
    V2 : (n2, 3) float64, F2 : (m2, 3) int  the mesh with the patches
    done_loops : list of (k,) int64, patches : list of Patch  the holes closed, in ``filled``'s order
    """
    done_loops, patches, closed_ids, crossing = [], [], [], []
    for i, loop, patch, seconds in filled:
        entry = report[i]
        if selfintersection:
            hits, check_seconds = checked[i]
            seconds += check_seconds
            if hits:
                entry.update(status="failed", reason=f"patch would intersect the mesh ({hits} faces)",
                             seconds=seconds)
                crossing.append((i, loops[i]))
                continue
        entry.update(status="closed", new_vertices=len(patch.vertices), new_faces=len(patch.faces),
                     seconds=seconds, **_json_safe(patch.info))
        done_loops.append(loop)
        patches.append(patch)
        closed_ids.append(i)
    if crossing:
        explain_outlines(V, F, crossing, report, incidence, pinch_vertices(loops, len(V)))
    V2, F2 = merge_patches(V, F, done_loops, patches)
    # Patches checked one by one can still meet one another: withdraw the later ones.
    checks = ([crossing_patches] if selfintersection else []) + [clashing_patches]
    for check in checks:
        kept = check(V2, F, F2, done_loops, patches, report, closed_ids)
        if len(kept) < len(patches):
            done_loops, patches, closed_ids = ([done_loops[j] for j in kept], [patches[j] for j in kept],
                                               [closed_ids[j] for j in kept])
            V2, F2 = merge_patches(V, F, done_loops, patches)
    return V2, F2, done_loops, patches


def _key_here(V, F, loop, incidence, rings, index):
    """:func:`_context_key` of a hole's context built here, or None where it cannot be built."""
    try:
        return _context_key(hole_context(V, F, loop, incidence, rings=rings, index=index))
    except FILL_ERRORS:
        return None


def _mesh_crossings(V, F, loop, patch, candidates=None, grid=None):
    """(mesh faces the patch of the hole with ``loop`` crosses, seconds): the self-intersection check of one patch.

    ``candidates`` are :func:`.crossings.face_boxes_near` of a union of patch boxes holding
    this patch's; without them (in a job, for its own patch) they are those of this patch's
    box alone, from the :class:`.face_grid.FaceGrid` ``grid`` or, without one, a scan of the
    faces. Either way the faces tested are those overlapping the patch's box, so the answer is the same.
    """
    t0 = time.perf_counter()
    points = patch.all_points(V[loop])
    if candidates is None:
        box = patch_box(points)
        candidates = face_boxes_near(V, F, box[None]) if grid is None else grid.near(box)
    hits = patch_intersections(points, patch.faces, V, F, candidates, loop)
    return len(hits), time.perf_counter() - t0


def _check_here(V, F, filled, checked):
    """Check, in this process, the patches no job checked, adding them to ``checked``; their positions in ``filled``.

    Their mesh faces are found in one pass over the mesh for the union of their boxes.
    """
    todo = [position for position, (i, _, _, _) in enumerate(filled) if i not in checked]
    if not todo:
        return todo
    boxes = [patch_box(filled[position][2].all_points(V[filled[position][1]])) for position in todo]
    candidates = face_boxes_near(V, F, np.stack(boxes))
    for position in todo:
        i, loop, patch, _ = filled[position]
        checked[i] = _mesh_crossings(V, F, loop, patch, candidates)
    return todo


# A patch that crosses the mesh beyond its hole's rings is filled once more with the mesh faces
# near it as obstacles: those overlapping its box grown by this fraction of the box's diagonal
# on every side, so that a patch of another shape still meets them.
OBSTACLE_MARGIN = 0.25


def _refill_clear_of_mesh(V, F, loop, incidence, rings, index, fill, fill_kwargs, timelimit, patch, crossed, seconds,
                          grid=None, ctx=None):
    """Fill a hole again, seeing the mesh faces its patch crossed: (patch, (crossings, seconds), seconds).

    A filter sees only its hole's rings (:class:`.holes.HoleContext`), so its own crossing
    avoidance cannot act on a face beyond them: a large hole under steep walls, a part of
    another component. The hole is filled once more with every mesh face near the crossing
    patch as ``obstacles`` of its context (:attr:`.holes.HoleContext.obstacle_faces`), then
    checked against the mesh again. Where that fill fails too or still crosses, or the time
    limit leaves no time for it, the first patch and its crossings are returned, so the
    hole is reported as it was; so are they, without a second fill, where the patch crosses
    itself or the faces its filter saw (its avoidance failed on what it could see).
    ``crossed`` is the first check's (faces crossed, seconds), ``seconds`` the first fill's
    (the time returned includes it), ``ctx`` the first fill's context when the caller has it.
    """
    t0 = time.perf_counter()
    left = timelimit - seconds if timelimit > 0 else 0.0
    if timelimit > 0 and left <= 0:
        return patch, crossed, seconds
    points = patch.all_points(V[loop.vertices])
    try:
        if ctx is None:
            ctx = hole_context(V, F, loop, incidence, rings=rings, index=index)
        # A patch crossing what its filter saw, or itself: more faces to avoid cannot help it.
        if not len(context_crossings(ctx, points, patch.faces)):
            box = patch_box(points)
            box += np.array([[-1.0], [1.0]]) * OBSTACLE_MARGIN * float(np.linalg.norm(box[1] - box[0]))
            near = face_boxes_near(V, F, box[None])[0] if grid is None else grid.near(box)[0]
            wider = hole_context(V, F, loop, incidence, rings=rings, index=index, obstacles=near)
            outcome, _ = fill_one(fill, wider, fill_kwargs, left)
            if not isinstance(outcome, str) and not _mesh_crossings(V, F, wider.loop, outcome, grid=grid)[0]:
                outcome.info["obstacle_faces"] = len(wider.obstacle_faces)
                return outcome, (0, crossed[1]), seconds + time.perf_counter() - t0
    except FILL_ERRORS:
        pass
    return patch, crossed, seconds + time.perf_counter() - t0


def _json_safe(info):
    out = {}
    for key, value in info.items():
        if isinstance(value, np.generic):
            value = value.item()
        elif isinstance(value, np.ndarray):
            value = value.tolist()
        out[key] = value
    return out
