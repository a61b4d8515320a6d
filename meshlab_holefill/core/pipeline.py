"""The pipeline every hole-filling filter shares: find holes, fill each, validate, merge.

An algorithm only provides ``fill(ctx, **params) -> Patch`` on one :class:`HoleContext`;
this module does the rest of the filter contract (DESIGN.md): hole selection by size and
selection, all-or-nothing per hole, patch validation, the optional self-intersection
check, bit-exact originals, attributes, and the result dictionary.
"""
from __future__ import annotations

import hashlib
import time

import numpy as np

from ..geometry.intersections import faces_intersecting
from .holes import OUTLINE_RATIO, boundary_loops, edge_summary, hole_context, outline_ratios, vertex_face_incidence
from ..meshlab.meshset_io import check_manifold_edges, current_mesh_arrays, extend_attributes, refine_mesh_arrays, replace_current_mesh
from .patch import HoleFillError, merge_patches, validate_patch
from .parameters import ParamSpec

COMMON_PARAMS = [
    ParamSpec("maxholesize", "int", 1000,
              "Largest hole to close, as its number of boundary edges; larger holes are skipped "
              "(MeshLab's Close Holes uses 30; these algorithms target large holes, hence 1000).",
              minimum=3, mlx_name="MaxHoleSize", display="Max size to be closed"),
    ParamSpec("selected", "bool", False,
              "Close only holes with at least one selected border face.",
              mlx_name="Selected", display="Close holes with selected faces"),
    ParamSpec("newfaceselected", "bool", True,
              "Select the new faces after filling (the original selection is kept).",
              mlx_name="NewFaceSelected", display="Select the newly created faces"),
    ParamSpec("selfintersection", "bool", True,
              "Reject a patch that intersects the existing mesh or itself; the hole is then reported failed.",
              mlx_name="SelfIntersection", display="Prevent creation of selfIntersecting faces"),
]


def face_boxes_near(V, F, boxes):
    """Mesh faces whose bounding box overlaps at least one of ``boxes``, found in one pass.

    The self-intersection check needs, per patch, the mesh faces near it. Scanning every
    face's box per hole costs O(m) per hole (0.2 s per hole at 3.6M faces); instead every
    vertex gets an outcode (Cohen-Sutherland: one bit per side of the union of the patch
    boxes it lies beyond), a face misses the union box exactly when its three vertices share
    a bit, and only the few faces left get their boxes for the per-patch test. The outcodes
    cost one byte per vertex and one gather of bytes per face (no (m, 3, 3) float temporary).

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    boxes : (h, 2, 3) float
        Lower and upper corners of the query boxes (already padded).

    Returns
    -------
    near : (c,) int64
        Candidate face indices (overlapping the union box).
    lo, hi : (c, 3) float
        Their boxes, for the per-patch test.
    """
    union_lo, union_hi = boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)
    code = np.zeros(len(V), np.uint8)
    for axis in range(3):
        code |= (V[:, axis] < union_lo[axis]).astype(np.uint8) << (2 * axis)
        code |= (V[:, axis] > union_hi[axis]).astype(np.uint8) << (2 * axis + 1)
    near = np.flatnonzero((code[F[:, 0]] & code[F[:, 1]] & code[F[:, 2]]) == 0)
    corners = V[F[near]]
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    return near, lo, hi


def patch_intersections(patch_points, patch_faces, mesh_V, mesh_F, candidates, loop):
    """Indices of patch faces that intersect the existing mesh near the hole, or the patch itself.

    Parameters
    ----------
    patch_points : (k + p, 3) float
        Loop points then new vertices (``Patch.all_points``).
    patch_faces : (q, 3) int
        In loop-local numbering.
    mesh_V, mesh_F : arrays of the mesh.
    candidates : tuple ``(near, lo, hi)`` from :func:`face_boxes_near`
        Mesh faces that may be near any patch; those overlapping this patch's box are tested.
    loop : (k,) int
        Mesh vertex ids of the loop (shared vertices are not intersections).
    """
    near_all, face_lo, face_hi = candidates
    lo, hi = patch_points.min(axis=0), patch_points.max(axis=0)
    pad = 1e-9 * float(np.linalg.norm(hi - lo))
    near = near_all[np.all(face_hi >= lo - pad, axis=1) & np.all(face_lo <= hi + pad, axis=1)]
    used = np.unique(mesh_F[near].ravel()) if len(near) else np.zeros(0, np.int64)
    # Local vertex array: loop vertices keep their loop-local numbers so shared vertices
    # between patch and mesh faces are recognised as shared.
    others = np.setdiff1d(used, loop)
    k, p = len(loop), len(patch_points) - len(loop)
    X = np.concatenate([patch_points, mesh_V[others]])
    ids = np.concatenate([loop, others])
    sorter = np.argsort(ids)
    local_mesh = sorter[np.searchsorted(ids, mesh_F[near], sorter=sorter)].reshape(-1, 3)
    local_mesh = np.where(local_mesh >= k, local_mesh + p, local_mesh)
    allF = np.concatenate([patch_faces, local_mesh])
    q = len(patch_faces)
    hits = faces_intersecting(X, allF, np.arange(q), np.arange(len(allF)))
    return hits


def _patch_box(points):
    lo, hi = points.min(axis=0), points.max(axis=0)
    pad = 1e-9 * float(np.linalg.norm(hi - lo))
    return np.stack([lo - pad, hi + pad])


def close_holes(ms, fill, params, *, algorithm_params=(), rings=3, prepare=None):
    """Run one hole-filling algorithm on every eligible hole of the current mesh.

    Parameters
    ----------
    ms : pymeshlab.MeshSet
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
        ``edge_weights``, ``face_parents`` (see :func:`meshset_io.refine_mesh_arrays`) and
        ``split_counts``. When a hole with a refined border fails, the holes are filled
        again without it, so its border is left as it was.

    Returns
    -------
    dict
        ``closed_holes``, ``new_faces``, ``new_vertices``, ``skipped_holes``,
        ``failed_holes``, ``holes`` (per-hole dicts) and ``seconds``; with ``prepare`` also
        ``split_boundary_edges`` (new faces and vertices then count the patches only; the
        split faces' second children are rows m .. m + split_boundary_edges - 1).
    """
    t_start = time.perf_counter()
    arrays = current_mesh_arrays(ms)
    V, F = arrays.V, arrays.F
    he, he_faces, bad_edges = edge_summary(F)
    check_manifold_edges(F, arrays.label, bad_edges)
    loops = boundary_loops(F, (he, he_faces))
    selected_faces = arrays.face_attrs["selected"].ravel() > 0
    report, todo = [], []
    for i, loop in enumerate(loops):
        entry = {"hole": i, "boundary_edges": loop.edge_count, "pinched": bool(loop.pinched)}
        if not loop.closed:
            entry.update(status="skipped", reason="open boundary chain (inconsistent face orientation)")
        elif len(loop) < 3:
            entry.update(status="skipped", reason="degenerate loop with fewer than 3 edges")
        elif len(loop) > params["maxholesize"]:
            entry.update(status="skipped", reason=f"too large ({len(loop)} > maxholesize {params['maxholesize']})")
        elif params["selected"] and not selected_faces[loop.border_faces].any():
            entry.update(status="skipped", reason="not selected")
        else:
            todo.append(i)
        report.append(entry)
    fill_kwargs = {name: params[name] for name in algorithm_params}
    base = (arrays, list(loops), [dict(entry) for entry in report])
    fills = {}  # hole -> outcome of its fill, reused by a later pass while its surroundings are the same
    while True:
        arrays, V, F, V2, F2, done_loops, patches, refinement, report = _fill_holes(
            base, todo, params, fill, fill_kwargs, rings, prepare, fills)
        # A hole whose border was refined and which then failed would leave its split border
        # faces behind: fill again with that hole left out, so nothing of it is changed.
        undo = [i for i in todo if report[i]["status"] == "failed" and report[i].get("split_boundary_edges")]
        if not undo:
            break
        for i in undo:
            base[2][i] = dict(report[i], split_boundary_edges=0)
        todo = [i for i in todo if i not in undo]
    n_new_faces = len(F2) - len(F)
    if n_new_faces or refinement is not None:
        if n_new_faces:
            vattrs, fattrs, wedge = extend_attributes(arrays, V2, F2, done_loops,
                                                      [len(p.vertices) for p in patches])
        else:  # borders refined, no hole closed
            vattrs, fattrs, wedge = arrays.vertex_attrs, arrays.face_attrs, arrays.wedge_texcoords
        select = np.arange(len(F), len(F2)) if params["newfaceselected"] else None
        replace_current_mesh(ms, arrays, V2, F2, vattrs, fattrs, wedge, select_faces=select)
    statuses = [h["status"] for h in report]
    result = {
        "closed_holes": statuses.count("closed"),
        "new_faces": int(n_new_faces),
        "new_vertices": int(len(V2) - len(V)),
        "skipped_holes": statuses.count("skipped"),
        "failed_holes": statuses.count("failed"),
        "holes": report,
        "seconds": time.perf_counter() - t_start,
    }
    if prepare is not None:
        result["split_boundary_edges"] = int(len(refinement.edge_weights)) if refinement is not None else 0
    return result


def _context_key(ctx):
    """Fingerprint of everything a fill can see of its hole: the local vertices and faces.

    The algorithms read only the HoleContext's local arrays (normals, scales and the rest
    derive from these), and they are deterministic, so an equal key means an equal outcome.
    """
    digest = hashlib.sha1()
    for a in (ctx.vertices, ctx.faces, ctx.border_faces, ctx.forbidden_edges, ctx.depth):
        a = np.ascontiguousarray(a)
        digest.update(repr((a.dtype.str, a.shape)).encode())
        digest.update(a.tobytes())
    digest.update(bytes([bool(ctx.pinched)]))
    return digest.digest()


_FILL_ERRORS = (HoleFillError, np.linalg.LinAlgError, ArithmeticError, ValueError, RuntimeError)


def _reason(exc):
    return str(exc) if isinstance(exc, HoleFillError) else f"{type(exc).__name__}: {exc}"


def _fill_or_reason(fill, ctx, fill_kwargs):
    """The hole's validated patch, or the reason it cannot be filled (str)."""
    try:
        patch = fill(ctx, **fill_kwargs)
        validate_patch(patch, ctx.points, ctx.forbidden_edges)
    except _FILL_ERRORS as exc:
        return _reason(exc)
    return patch


def _fill_holes(base, todo, params, fill, fill_kwargs, rings, prepare, fills):
    """One pass of :func:`close_holes` over the holes ``todo``: refine, fill, check, merge.

    ``base`` is (arrays, loops, report entries) of the mesh as given; nothing is written to
    the MeshSet here. ``fills`` maps a hole to (context key, patch or failure reason, seconds)
    of an earlier pass: a hole whose surroundings did not change is not filled again (a
    second pass only undoes the border refinement of holes that failed, and on face000.ply
    with LS-SVM refilling every hole doubled the run).
    """
    arrays, loops, report = base[0], list(base[1]), [dict(entry) for entry in base[2]]
    V, F = arrays.V, arrays.F
    refinement = prepare(V, F, [loops[i] for i in todo], params) if prepare is not None and todo else None
    if refinement is not None:
        arrays = refine_mesh_arrays(arrays, refinement)
        V, F = arrays.V, arrays.F
        for i, loop, count in zip(todo, refinement.loops, refinement.split_counts):
            loops[i] = loop
            report[i]["split_boundary_edges"] = int(count)
    elif prepare is not None:
        for i in todo:
            report[i]["split_boundary_edges"] = 0
    incidence = vertex_face_incidence(F, len(V)) if todo else None
    filled = []  # (hole id, context, patch, seconds) of patches that passed validation
    for i in todo:
        entry = report[i]
        t0 = time.perf_counter()
        try:
            ctx = hole_context(V, F, loops[i], incidence, rings=rings, index=i)
        except _FILL_ERRORS as exc:
            entry.update(status="failed", reason=_reason(exc), seconds=time.perf_counter() - t0)
            continue
        key = _context_key(ctx)
        if i not in fills or fills[i][0] != key:
            fills[i] = (key, _fill_or_reason(fill, ctx, fill_kwargs), time.perf_counter() - t0)
        _, outcome, seconds = fills[i]
        if isinstance(outcome, str):
            entry.update(status="failed", reason=outcome, seconds=seconds)
            continue
        filled.append((i, ctx, outcome, seconds))
    if params["selfintersection"] and filled:
        candidates = face_boxes_near(V, F, np.stack([_patch_box(p.all_points(c.points)) for _, c, p, _ in filled]))
    done_loops, patches, closed_ids, crossing = [], [], [], []
    for i, ctx, patch, seconds in filled:
        entry = report[i]
        if params["selfintersection"]:
            t0 = time.perf_counter()
            hits = patch_intersections(patch.all_points(ctx.points), patch.faces, V, F, candidates, ctx.loop)
            seconds += time.perf_counter() - t0
            if len(hits):
                entry.update(status="failed", reason=f"patch would intersect the mesh ({len(hits)} faces)",
                             seconds=seconds)
                crossing.append((i, ctx.loop))
                continue
        entry.update(status="closed", new_vertices=len(patch.vertices), new_faces=len(patch.faces),
                     seconds=seconds, **_json_safe(patch.info))
        done_loops.append(ctx.loop)
        patches.append(patch)
        closed_ids.append(i)
    if crossing:
        _explain_outlines(V, F, crossing, report)
    V2, F2 = merge_patches(V, F, done_loops, patches)
    # Patches checked one by one can still meet one another: withdraw the later ones.
    checks = ([_crossing_patches] if params["selfintersection"] else []) + [_clashing_patches]
    for check in checks:
        kept = check(V2, F, F2, done_loops, patches, report, closed_ids)
        if len(kept) < len(patches):
            done_loops, patches, closed_ids = ([done_loops[j] for j in kept], [patches[j] for j in kept],
                                               [closed_ids[j] for j in kept])
            V2, F2 = merge_patches(V, F, done_loops, patches)
    return arrays, V, F, V2, F2, done_loops, patches, refinement, report


def _withdraw(entry, reason):
    """Report a hole whose validated patch is taken back as failed."""
    entry.update(status="failed", reason=reason)
    for name in ("new_vertices", "new_faces"):
        entry.pop(name, None)


def _crossing_patches(V2, F, F2, done_loops, patches, report, closed_ids):
    """Patches each clear of the mesh can still cross one another (two holes close together).

    Only patches whose bounding boxes overlap are tested, face against face. Taken in hole
    order, a patch crossing one already kept is withdrawn and its hole reported failed.

    Returns
    -------
    list of int  positions in ``patches`` of the patches kept
    """
    from ..geometry.intersections import intersecting_pairs

    if len(patches) < 2:
        return list(range(len(patches)))
    sizes = [len(p.faces) for p in patches]
    start = len(F) + np.concatenate([[0], np.cumsum(sizes)])
    boxes = np.stack([_patch_box(V2[np.unique(F2[start[j]:start[j + 1]])]) for j in range(len(patches))])
    overlap = np.all((boxes[:, None, 0] <= boxes[None, :, 1]) & (boxes[None, :, 0] <= boxes[:, None, 1]), axis=2)
    np.fill_diagonal(overlap, False)
    near = np.flatnonzero(overlap.any(axis=1))
    if len(near) == 0:
        return list(range(len(patches)))
    faces = np.concatenate([np.arange(start[j], start[j + 1]) for j in near])
    pairs = intersecting_pairs(V2, F2, faces, faces)
    owner = np.searchsorted(start, pairs, side="right") - 1
    crossing = {tuple(sorted(p)) for p in owner[owner[:, 0] != owner[:, 1]].tolist()}
    kept = []
    for j in range(len(patches)):
        other = next((i for i in kept if (min(i, j), max(i, j)) in crossing), None)
        if other is None:
            kept.append(j)
            continue
        _withdraw(report[closed_ids[j]], f"patch would intersect the patch of hole {closed_ids[other]}")
    return kept


def _clashing_patches(V2, F, F2, done_loops, patches, report, closed_ids):
    """Patches validated alone can still clash where two holes share a pinched vertex.

    When the merged mesh F2 has non-manifold edges, the patches are taken back in hole
    order and each is kept only if its faces, with the original faces and the patches kept
    so far, leave every such edge with at most two faces; the others are withdrawn and their
    holes reported failed. The first of two clashing patches is kept, and no hole is ever
    left half-filled.

    Returns
    -------
    list of int  positions in ``patches`` of the patches kept
    """
    from .holes import nonmanifold_edges

    shared = np.concatenate(done_loops) if done_loops else np.zeros(0, np.int64)
    if len(F2) == len(F) or len(np.unique(shared)) == len(shared):
        return list(range(len(patches)))  # no two patches meet: nothing can clash
    bad = nonmanifold_edges(F2)
    if len(bad) == 0:
        return list(range(len(patches)))
    n = int(F2.max()) + 1
    E = np.sort(np.stack([F2[:, [0, 1]], F2[:, [1, 2]], F2[:, [2, 0]]], axis=1).reshape(-1, 2), axis=1)
    key = E[:, 0] * n + E[:, 1]
    face = np.repeat(np.arange(len(F2)), 3)
    on_bad = np.isin(key, bad[:, 0] * n + bad[:, 1])
    key, face = key[on_bad], face[on_bad]
    used = {}
    for k in key[face < len(F)].tolist():
        used[k] = used.get(k, 0) + 1
    owner = np.repeat(np.arange(len(patches)), [len(p.faces) for p in patches])
    patch_of = owner[face[face >= len(F)] - len(F)]
    patch_keys = key[face >= len(F)]
    keep = []
    for j in range(len(patches)):
        mine = {}
        for k in patch_keys[patch_of == j].tolist():
            mine[k] = mine.get(k, 0) + 1
        if all(used.get(k, 0) + c <= 2 for k, c in mine.items()):
            keep.append(j)
            for k, c in mine.items():
                used[k] = used.get(k, 0) + c
        else:
            _withdraw(report[closed_ids[j]], "patch clashes with another patch at a shared vertex")
    return keep


def _explain_outlines(V, F, crossing, report):
    """Say so when a rejected loop is the outline of a whole island rather than a hole.

    Range scans hold small fragments whose only border is their outline; capping it lays a
    second sheet over the fragment, which the intersection check rightly refuses. The
    reason then tells the user it is not a hole (holes.outline_ratios).
    """
    ratios = outline_ratios(V, F, [loop for _, loop in crossing])
    for (i, _), ratio in zip(crossing, ratios):
        if ratio >= OUTLINE_RATIO:
            report[i]["reason"] += (f"; the loop outlines its whole component (encloses {ratio:.0%} of its area): "
                                    "an island of the mesh, not a hole")


def _json_safe(info):
    out = {}
    for key, value in info.items():
        if isinstance(value, np.generic):
            value = value.item()
        elif isinstance(value, np.ndarray):
            value = value.tolist()
        out[key] = value
    return out
