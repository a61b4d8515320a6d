"""Fold-overs of an HPDE patch (Sec. 4.6 "detect and handle"): detection, repair, last resort.

A fold-over is a face turned against its projection plane after the mapping back (the
paper's case), or two neighbouring patch faces, or a patch face and the mesh face across a
loop edge, bent by more than FOLD_ANGLE. Edge swaps and a local relaxation repair what
they can; the caller drops prediction points left on folds. When every layout folds, the
loop alone is triangulated with Liepa's weights (beyond the paper).
"""
from __future__ import annotations

import itertools

import numpy as np

from ...geometry.flips import fixed_edge_keys, relax_edges
from ...core.crossings import context_crossings
from ...errors import HoleFillError
from ...geometry.dihedral_triangulation import least_bend_splits, split_triangles
from ...geometry.intersections import faces_intersecting
from ...geometry.quality import face_normals
from ...geometry.topology import interior_edges
from ._fold_kernels import fold_swap_rounds, fold_swap_scores, folded_faces
from .optimisation import adjacency

__all__ = ["crossing_triangles", "loop_triangulation", "fold_overs", "local_folds", "local_folds_numpy",
           "unfold_by_swaps", "unfold_by_swaps_numpy", "repair_folds", "intersects_surroundings", "boundary_ears",
           "border_normals"]

# Neighbouring patch faces whose normals differ by more than this are a fold-over.
FOLD_ANGLE = np.radians(150.0)


#: Loops up to this size are triangulated by :func:`loop_triangulation` (it tests all C(k, 3) triangles).
LOOP_TRIANGULATION_SIZE = 60


def crossing_triangles(ctx, max_size=LOOP_TRIANGULATION_SIZE):
    """Set of loop triples (i, m, j), i < m < j, whose triangle crosses the surrounding rings.

    All C(k, 3) candidate triangles are tested at once against the context's faces (for
    :func:`loop_triangulation`); empty for loops longer than ``max_size``.
    """
    k = ctx.size
    if k > max_size or k < 3:
        return set()
    T = np.fromiter(itertools.chain.from_iterable(itertools.combinations(range(k), 3)), np.int64).reshape(-1, 3)
    surrounding_points, surrounding_faces = ctx.surroundings()
    X = np.concatenate([ctx.points, surrounding_points[k:]])
    allF = np.concatenate([T, surrounding_faces])
    hits = faces_intersecting(X, allF, np.arange(len(T)), np.arange(len(T), len(allF)))
    return set(map(tuple, T[np.asarray(hits, np.int64)].tolist()))


def loop_triangulation(P, border_normals, forbidden_edges=(), max_size=LOOP_TRIANGULATION_SIZE, blocked=frozenset()):
    """Triangulation of the loop alone minimising (largest dihedral angle, area), as Liepa (2003).

    Last resort beyond the paper, used only when every HPDE attempt folds (slit-like or
    crumpled natural holes, where no base point keeps a correspondence): dynamic programming
    over the O(k^3) triangulations of the polygon, the dihedral angle of a triangle taken
    against its neighbours in the triangulation and, on a loop edge, against the mesh face
    across it (none where its row of ``border_normals`` is zero); chords that duplicate a mesh
    edge and ``blocked`` triangles are not used. The programme is the compiled one of
    :func:`meshlab_holefill.geometry.dihedral_triangulation.least_bend_splits` (bends compared as
    1 - cos, the same order as the angles).

    Parameters
    ----------
    P : (k, 3) float64  loop points (patch orientation)
    border_normals : (k, 3) float64  unit normal of the mesh face on loop edge (i, i+1) (0 rows: unknown)
    forbidden_edges : (p, 2) int
    max_size : int  larger loops are refused (the blocked triangles are all C(k, 3) of them)
    blocked : set of (i, m, j), i < m < j  triangles not to use (they cross the mesh)

    Returns
    -------
    F : (k - 2, 3) int64, or None when impossible
    worst : float  largest dihedral angle (radians) of the result
    """
    k = len(P)
    if k > max_size:
        return None, np.inf
    banned = np.array(sorted(blocked), np.int64).reshape(-1, 3)
    try:
        split, worst = least_bend_splits(P, border_normals, forbidden_edges, banned)
    except HoleFillError:
        return None, np.inf
    if not np.isfinite(worst):
        return None, np.inf
    return split_triangles(split), float(np.arccos(np.clip(1.0 - worst, -1.0, 1.0)))


def fold_overs(V, F, reference):
    """Faces folded over relative to the planar triangulation (normal against its reference), (m,) bool."""
    N = face_normals(V, F, normalize=False)
    return np.einsum("ij,ij->i", N, reference) <= 0.0


def local_folds(V, F, border_normals=None, max_angle=FOLD_ANGLE):
    """Faces folded onto a neighbour: normals of two faces sharing an edge differ by more than ``max_angle``.

    The fold-over test that needs no reference plane. With ``border_normals`` (the unit
    normal of the mesh face on each loop edge (i, i+1), i < k) the patch face on a loop edge
    is also compared with the mesh face across it, which catches a patch folding back over
    the surrounding surface. Degenerate faces count as folded.

    Parameters
    ----------
    V : (n, 3) float64  loop vertices first
    F : (m, 3) int64
    border_normals : (k, 3) float64, optional

    Returns
    -------
    (m,) bool

    Compiled (:func:`._fold_kernels.folded_faces`, the answer of :func:`local_folds_numpy`).
    """
    across = np.zeros((0, 3)) if border_normals is None else np.ascontiguousarray(border_normals, np.float64)
    V_arr, F_arr = np.asarray(V, np.float64), np.asarray(F)
    shaped = V_arr.ndim == 2 and V_arr.shape[1] == 3 and F_arr.ndim == 2 and F_arr.shape[1] == 3
    if shaped and F_arr.dtype.kind in "iu" and across.ndim == 2 and across.shape[1] == 3:
        bad, ok = folded_faces(np.ascontiguousarray(V_arr), np.ascontiguousarray(F_arr, np.int64), across,
                               float(np.cos(max_angle)))
        if ok:
            return bad
    return local_folds_numpy(V, F, border_normals, max_angle)


def local_folds_numpy(V, F, border_normals=None, max_angle=FOLD_ANGLE):
    """:func:`local_folds` in numpy (the reference of the compiled test)."""
    N = face_normals(V, F)
    bad = ~np.any(N != 0, axis=1)
    limit = np.cos(max_angle)
    E, f1, _, f2, _ = interior_edges(F, len(V))
    sharp = np.einsum("ij,ij->i", N[f1], N[f2]) < limit
    bad[f1[sharp]] = True
    bad[f2[sharp]] = True
    if border_normals is not None:
        k = len(border_normals)
        a, b = F.ravel(), np.roll(F, -1, axis=1).ravel()
        on_loop = (a < k) & (b == (a + 1) % k)
        face = np.flatnonzero(on_loop) // 3
        bad[face[np.einsum("ij,ij->i", N[face], border_normals[a[on_loop]]) < limit]] = True
    return bad


def unfold_by_swaps(V, F, forbidden_edges=(), border_normals=None, max_rounds=20):
    """Repair folds by edge swaps (reading of Sec. 4.6's "handle fold-overs").

    The agreement of an interior edge is the smallest dot product among its two triangles'
    unit normals and, for a triangle on a loop edge, the normal of the mesh triangle across
    it. An edge with negative agreement (a fold of more than 90 degrees) is swapped when the
    swap raises it and leaves no degenerate triangle. Typical case: a zigzag tooth of the loop
    that is concave on the surface but convex in the projection, where the triangulation puts
    an ear (i-1, i, i+1) facing against the surface. The swap loop is
    :func:`geometry.flips.relax_edges` with this agreement as its scored criterion (worst fold
    first) and without its orientation test, which a folded pair cannot pass. Its rounds run
    compiled (:func:`._fold_kernels.fold_swap_rounds`, the same swaps); a round whose edge table
    the compiled code cannot build (a directed edge repeats) and those after it run in numpy.

    Returns
    -------
    F : (m, 3) int64
    swaps : int
    """
    across = np.zeros((0, 3)) if border_normals is None else np.ascontiguousarray(border_normals, np.float64)
    V = np.ascontiguousarray(V, np.float64)
    F = np.array(F, np.int64)
    fixed = fixed_edge_keys(forbidden_edges, len(V))
    swaps, rounds, unsure = fold_swap_rounds(V, F, fixed, across, max_rounds)
    if not unsure:
        return F, swaps
    F, more = unfold_by_swaps_numpy(V, F, forbidden_edges, border_normals, max_rounds - rounds)
    return F, swaps + more


def unfold_by_swaps_numpy(V, F, forbidden_edges=(), border_normals=None, max_rounds=20):
    """:func:`unfold_by_swaps` by :func:`geometry.flips.relax_edges` with the fold score as its criterion (the tests' reference)."""
    across = np.zeros((0, 3)) if border_normals is None else np.ascontiguousarray(border_normals, np.float64)

    def agreement_gain(V, old1, old2, new1, new2):
        # _pair_agreement of both pairs, compiled (same bits, _fold_kernels); only folds (negative
        # agreement) are swapped, the worst first, so the swapped pair is scored for them alone.
        faces = (np.ascontiguousarray(f, np.int64) for f in (old1, old2, new1, new2))
        old, new = fold_swap_scores(np.ascontiguousarray(V, np.float64), *faces, across)
        return old, new, -old

    return relax_edges(V, F, forbidden_edges, max_rounds=max_rounds, criterion=agreement_gain, normal_cos=None)


def repair_folds(V, F, n_fixed, forbidden_edges=(), border_normals=None, rounds=5, relax_steps=10):
    """Remove fold-overs: swaps (:func:`unfold_by_swaps`), then local relaxation of what is left.

    A fold that no swap removes is a vertex whose ring is turned over (a spike of the
    prediction); the free vertices of the folded faces and their neighbours are moved
    ``relax_steps`` times to the mean of their neighbours, and the swaps are tried again, for
    at most ``rounds`` rounds. The caller checks :func:`local_folds` afterwards.

    Returns
    -------
    V : (n, 3) float64
    F : (m, 3) int64
    repairs : int  swaps plus relaxed vertices
    """
    V = np.array(V, np.float64)
    repairs = 0
    for _ in range(rounds):
        F, swaps = unfold_by_swaps(V, F, forbidden_edges, border_normals)
        repairs += swaps
        bad = local_folds(V, F, border_normals)
        if not bad.any():
            break
        _, A = adjacency(F, len(V))
        region = np.zeros(len(V), bool)
        region[F[bad].ravel()] = True
        region |= np.asarray(A @ region.astype(np.int8)).ravel() > 0
        region[:n_fixed] = False
        if not region.any():
            break
        deg = np.maximum(np.asarray(A.sum(axis=1)).ravel(), 1)
        Ar = A[region]
        for _ in range(relax_steps):
            V[region] = (Ar @ V) / deg[region, None]
        repairs += int(region.sum())
    return V, F, repairs


def intersects_surroundings(ctx, V, F):
    """Whether the patch crosses itself or the surrounding rings of the context.

    The filter checks the whole mesh afterwards; testing the rings here lets a crossing
    attempt give way to the next layout instead of failing the hole
    (:func:`meshlab_holefill.core.crossings.context_crossings`).
    """
    return len(context_crossings(ctx, V, F)) > 0


def boundary_ears(F, k, span=2):
    """Faces of loop vertices only that lie within a stretch of at most ``span`` loop edges, (m,) bool.

    ``span=2``: the ears, three consecutive loop vertices (i - 1, i, i + 1). A larger span
    also takes the triangles that close a short notch of the loop among themselves.
    """
    on_loop = np.all(F < k, axis=1)
    s = np.sort(np.where(on_loop[:, None], F, 0), axis=1)
    gaps = np.stack([s[:, 1] - s[:, 0], s[:, 2] - s[:, 1], s[:, 0] + k - s[:, 2]], axis=1)
    return on_loop & (k - gaps.max(axis=1) <= span)


def border_normals(ctx):
    """Unit normal of the mesh face on each loop edge, (k, 3), for the fold test across the loop.

    A border face that is itself folded against the surface (normal opposite to the mean
    vertex normal of its loop edge, as in crumpled scan borders) gives no reference: its row
    is zero and the test skips that edge.
    """
    N = face_normals(ctx.vertices, ctx.faces[ctx.border_faces])
    vn = ctx.loop_normals + np.roll(ctx.loop_normals, -1, axis=0)
    N[np.einsum("ij,ij->i", N, vn) <= 0] = 0.0
    return N
