"""Crossing checks of patches: against the mesh near them, against each other, and at shared vertices.

A patch validated alone (core.patch.validate_patch) can still cross the surrounding mesh,
the patch of a nearby hole, or clash with another patch at a pinched vertex; these checks
find such patches so that the pipeline reports their holes failed instead of merging them.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..errors import HoleFillError
from ..geometry._broad_phase_kernels import boxes_meeting
from ..geometry.intersections import faces_intersecting, intersecting_pairs, intersecting_pairs_with_fixed
from .holes import hole_context, nonmanifold_edges
from ..geometry.sets import isin_ints, positions_ints, unique_ints

__all__ = ["clashing_patches", "context_crossings", "crossing_patches", "face_boxes_near", "load_crossing_kernels",
           "patch_box", "patch_intersections", "surroundings_crossing_themselves", "withdraw"]


def face_boxes_near(V, F, boxes):
    """Mesh faces whose bounding box overlaps at least one of ``boxes``, found in one pass.

    The self-intersection check needs, per patch, the mesh faces near it. Scanning every
    face's box per hole costs O(m) per hole (0.2 s per hole at 3.6M faces); instead every
    vertex gets an outcode (Cohen-Sutherland: one bit per side of the union of the patch
    boxes it lies beyond), a face misses the union box exactly when its three vertices share
    a bit, and only the faces left get their boxes tested against each patch box (the union
    of holes far apart spans much of the mesh). Compiled (:func:`_faces_meeting_boxes`):
    one byte per vertex, no (m, 3, 3) temporary.

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    boxes : (h, 2, 3) float
        Lower and upper corners of the query boxes (already padded).

    Returns
    -------
    near : (c,) int64
        Candidate face indices (overlapping a box), in increasing order.
    lo, hi : (c, 3) float
        Their boxes, for the per-patch test.
    """
    near = _faces_meeting_boxes(np.asarray(V, np.float64), np.asarray(F), np.asarray(boxes, np.float64))
    corners = V[F[near]]
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    return near, lo, hi


def load_crossing_kernels(F):
    """Load the compiled kernels of the mesh crossing check for faces of F's integer type, in this process.

    The box query (:func:`face_boxes_near`) and the triangle tests of
    :func:`patch_intersections`, run on a patch of two triangles, one crossing a mesh face.
    Called before holes are filled, so that neither the first hole's time nor each forked worker
    pays for loading them (about 0.05 s each). A non-contiguous F is left to the checks.
    """
    F = np.asarray(F)
    if F.ndim != 2 or not F.flags.c_contiguous:
        return
    mesh_V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.2, 0.2, -0.5], [0.2, 0.2, 0.5],
                       [0.6, 0.6, 0.5]])
    mesh_F = np.array([[0, 1, 2]], dtype=F.dtype)
    loop = np.array([3, 4, 5])
    points = np.concatenate([mesh_V[loop], [[0.6, 0.6, -0.5]]])
    candidates = face_boxes_near(mesh_V, mesh_F, np.stack([points.min(axis=0), points.max(axis=0)])[None])
    patch_intersections(points, np.array([[0, 1, 2], [0, 2, 3]]), mesh_V, mesh_F, candidates, loop)


@njit(cache=True)
def _faces_meeting_boxes(V, F, boxes):
    """Faces whose bounding box meets one of ``boxes`` (h, 2, 3), in increasing order.

    First the outcodes of the vertices against the union of the boxes (a face wholly beyond
    one of its sides is dropped after three byte reads), then the survivors' boxes against
    each box: ``face_hi >= box_lo`` and ``face_lo <= box_hi`` on every axis.
    """
    lo = boxes[0, 0].copy()
    hi = boxes[0, 1].copy()
    for b in range(1, boxes.shape[0]):
        for axis in range(3):
            lo[axis] = min(lo[axis], boxes[b, 0, axis])
            hi[axis] = max(hi[axis], boxes[b, 1, axis])
    code = np.zeros(V.shape[0], np.uint8)
    for v in range(V.shape[0]):
        c = 0
        for axis in range(3):
            if V[v, axis] < lo[axis]:
                c |= 1 << (2 * axis)
            if V[v, axis] > hi[axis]:
                c |= 1 << (2 * axis + 1)
        code[v] = c
    keep = np.empty(F.shape[0], np.int64)
    count = 0
    for f in range(F.shape[0]):
        if (code[F[f, 0]] & code[F[f, 1]] & code[F[f, 2]]) != 0:
            continue
        for b in range(boxes.shape[0]):
            meets = True
            for axis in range(3):
                a, p, q = V[F[f, 0], axis], V[F[f, 1], axis], V[F[f, 2], axis]
                if max(a, max(p, q)) < boxes[b, 0, axis] or min(a, min(p, q)) > boxes[b, 1, axis]:
                    meets = False
                    break
            if meets:
                keep[count] = f
                count += 1
                break
    return keep[:count].copy()


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
    # the points as boxes of their own: their union box is (lo, hi), grown by pad, the boxes'
    # comparisons in one compiled pass over the candidates of all patches
    near = near_all[boxes_meeting(patch_points, patch_points, face_lo, face_hi, pad)]
    used = unique_ints(mesh_F[near]) if len(near) else np.zeros(0, np.int64)
    # Local vertex array: loop vertices keep their loop-local numbers so shared vertices
    # between patch and mesh faces are recognised as shared.
    others = used[~isin_ints(used, loop)]  # used is already sorted and distinct
    k, p = len(loop), len(patch_points) - len(loop)
    X = np.concatenate([patch_points, mesh_V[others]])
    local_mesh = positions_ints(np.concatenate([loop, others]), mesh_F[near]).reshape(-1, 3)
    local_mesh = np.where(local_mesh >= k, local_mesh + p, local_mesh)
    allF = np.concatenate([patch_faces, local_mesh])
    q = len(patch_faces)
    # weld=False: the patch is joined to the mesh by index; a vertex of another part at the same
    # place is a contact (MeshLab's per-face test reports it), not a shared vertex.
    pairs = intersecting_pairs(X, allF, np.arange(q), np.arange(len(allF)), weld=False)
    # faces_intersecting's answer: a pair of two patch faces is listed once, the smaller first.
    return unique_ints(np.concatenate([pairs[:, 0], pairs[pairs[:, 1] < q, 1]]))


def context_crossings(ctx, points, faces):
    """Patch faces crossing another patch face or the HoleContext's surrounding faces, (t,) int64 sorted.

    A filter's own check before the pipeline's whole-mesh one: it sees only the context's
    rings, so a crossing found here lets the filter try something else instead of failing
    the hole. The patch's own crossings count: a patch can fold over itself near its border
    without any pair of neighbouring triangles folding.

    Parameters
    ----------
    ctx : HoleContext
    points : (k + p, 3) float64  the hole boundary first (as ``ctx.points``), then new vertices
    faces : (q, 3) int  in that numbering
    """
    if len(faces) == 0:
        return np.zeros(0, np.int64)
    k, p = ctx.size, len(points) - ctx.size
    surrounding_points, surrounding_faces = ctx.surroundings()
    X = np.concatenate([points, surrounding_points[k:]])
    context = np.where(surrounding_faces >= k, surrounding_faces + p, surrounding_faces)
    allF = np.concatenate([np.asarray(faces, np.int64), context])
    q = len(faces)
    if not np.array_equal(points[:k], surrounding_points[:k]):  # a loop moved: the kept bounds are not its faces'
        return faces_intersecting(X, allF, np.arange(q), np.arange(len(allF)))
    patch = np.arange(q)
    pairs = intersecting_pairs_with_fixed(X, allF, patch, ctx.surrounding_bounds, q, also=patch)
    # faces_intersecting's answer: a pair of two patch faces is listed once, the smaller first.
    return unique_ints(np.concatenate([pairs[:, 0], pairs[pairs[:, 1] < q, 1]]))


def patch_box(points):
    lo, hi = points.min(axis=0), points.max(axis=0)
    pad = 1e-9 * float(np.linalg.norm(hi - lo))
    return np.stack([lo - pad, hi + pad])


def withdraw(entry, reason):
    """Report a hole whose validated patch is taken back as failed."""
    entry.update(status="failed", reason=reason)
    for name in ("new_vertices", "new_faces"):
        entry.pop(name, None)


def crossing_patches(V2, F, F2, done_loops, patches, report, closed_ids):
    """Patches each clear of the mesh can still cross one another (two holes close together).

    Only patches whose bounding boxes overlap are tested, face against face. Taken in hole
    order, a patch crossing one already kept is withdrawn and its hole reported failed.

    Returns
    -------
    list of int  positions in ``patches`` of the patches kept
    """
    if len(patches) < 2:
        return list(range(len(patches)))
    sizes = [len(p.faces) for p in patches]
    start = len(F) + np.concatenate([[0], np.cumsum(sizes)])
    boxes = np.stack([patch_box(V2[unique_ints(F2[start[j]:start[j + 1]])]) for j in range(len(patches))])
    overlap = np.all((boxes[:, None, 0] <= boxes[None, :, 1]) & (boxes[None, :, 0] <= boxes[:, None, 1]), axis=2)
    np.fill_diagonal(overlap, False)
    near = np.flatnonzero(overlap.any(axis=1))
    if len(near) == 0:
        return list(range(len(patches)))
    faces = np.concatenate([np.arange(start[j], start[j + 1]) for j in near])
    pairs = intersecting_pairs(V2, F2, faces, faces, weld=False)
    owner = np.searchsorted(start, pairs, side="right") - 1
    crossing = {tuple(sorted(p)) for p in owner[owner[:, 0] != owner[:, 1]].tolist()}
    kept = []
    for j in range(len(patches)):
        other = next((i for i in kept if (min(i, j), max(i, j)) in crossing), None)
        if other is None:
            kept.append(j)
            continue
        withdraw(report[closed_ids[j]], f"patch would intersect the patch of hole {closed_ids[other]}")
    return kept


def clashing_patches(V2, F, F2, done_loops, patches, report, closed_ids):
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
    shared = np.concatenate(done_loops) if done_loops else np.zeros(0, np.int64)
    if len(F2) == len(F) or len(unique_ints(shared)) == len(shared):
        return list(range(len(patches)))  # no two patches meet: nothing can clash
    rows = _faces_on_new_edges(len(V2), F, F2, shared)
    sub = np.asarray(F2[rows], np.int64)
    bad = nonmanifold_edges(sub)
    if len(bad) == 0:
        return list(range(len(patches)))
    n = len(V2)
    E = np.sort(np.stack([sub[:, [0, 1]], sub[:, [1, 2]], sub[:, [2, 0]]], axis=1).reshape(-1, 2), axis=1)
    key = E[:, 0] * n + E[:, 1]
    face = np.repeat(rows, 3)
    on_bad = isin_ints(key, bad[:, 0] * n + bad[:, 1])
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
            withdraw(report[closed_ids[j]], "patch clashes with another patch at a shared vertex")
    return keep


def _faces_on_new_edges(n, F, F2, loop_vertices):
    """Rows of F2 that may hold an edge of a new face: the new faces, and the original faces with two loop vertices.

    An edge of a patch joins two loop vertices or touches a new vertex, so only these faces
    can share one; of the rest of the mesh only one byte per corner is read.
    """
    on_loop = np.zeros(n, np.uint8)
    on_loop[loop_vertices] = 1
    hits = on_loop[F[:, 0]] + on_loop[F[:, 1]] + on_loop[F[:, 2]]
    return np.concatenate([np.flatnonzero(hits >= 2), np.arange(len(F), len(F2))])


def surroundings_crossing_themselves(V, F, loop, incidence, rings=2):
    """Faces within ``rings`` rings of a hole's border that already cross another face of those rings.

    A noisy scan can fold its own surface next to a hole (normal noise of about an edge
    length turns triangles over). No patch may cross those faces, and near such folds a
    patch that meets the whole border can seldom avoid them: the count tells the user why a
    hole failed.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int
    loop : BoundaryLoop
    incidence : scipy.sparse.csr_matrix  :func:`.holes.vertex_face_incidence` of F
    rings : int

    Returns
    -------
    int  the number of such faces (0 where the rings cannot be built)
    """
    try:
        ctx = hole_context(V, F, loop, incidence, rings=rings)
    except (HoleFillError, ValueError):
        return 0
    every = np.arange(len(ctx.faces))
    return len(faces_intersecting(ctx.vertices, ctx.faces, every, every))
