"""The patch of Xu et al.'s filter: its Laplacian, the initial advancing-front patch and the safeguards.

Xu, Li and Tan, CCTA 2013. The normalised cotangent Laplacian (Sec. 2.1, Eq. 1-6) serves the
training set and the Poisson equation; the initial patch is the advancing front method's
(Sec. 3.2, :mod:`meshlab_holefill.algorithms.xu2013.advancing_front`). Beyond the paper, needed to close
every benchmark hole and meet the quality target: planar and ear-cutting fallbacks for holes
the 3D advancing front cannot cover, Delaunay edge swaps, tangential smoothing after the
Poisson solve, and the checks against the surrounding mesh.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ._laplacian_kernels import edge_weight_rows, with_unit_diagonal
from .advancing_front import advancing_front_triangulation
from ...geometry.caps import split_loop_caps
from ...geometry.flips import folds, relax_edges
from ...core.crossings import context_crossings
from ...core.least_bend import least_bend_triangulations
from ...geometry.development import boundary_gap_angles, develop_loop, enclosed_curvature, simple_development
from ...geometry.laplacian import (cotangent_laplacian, cotangent_weights, tangential_umbrella_smoothing,
                                   vertices_near)
from ...geometry.quality import triangle_quality, unique_edges
from ...geometry.refine import refine_patch
from ...geometry.segments import polygon_edges_touch
from ...geometry.topology import boundary_edges_and_chords
from ...errors import HoleFillError

__all__ = ["normalized_cotangent_laplacian", "reference_normals", "planar_boundaries", "harmonic_lift",
           "initial_patches", "relax_patch", "folds", "solve_folds", "repair_slivers", "context_hits"]


def normalized_cotangent_laplacian(V, F, n=None, cotangents=None):
    """Laplacian matrix with normalised cotangent weights (Sec. 2.1, Eq. 1-3, 5-6).

    L_ii = -1, L_ij = w_ij = omega_ij / sum_j omega_ij with omega_ij = cot alpha_ij + cot beta_ij,
    so (L V)_i = sum_j w_ij (v_j - v_i) = delta_i (Eq. 1, 7). Cotangent weights of edges
    opposite obtuse angles can be negative; they are raised to 1e-3 times the mean weight so
    that every row is a convex combination (the paper does not treat them): the Poisson
    system then stays diagonally dominant (solvable, and its solution has no fold-over
    from weights of the wrong sign).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int
    n : int, optional  matrix size (default len(V))
    cotangents : (m, 3) float64, optional  the faces' corner cotangents, instead of those of V

    Returns
    -------
    L : (n, n) CSR float64  (rows of vertices without neighbours are zero)
    """
    n = len(V) if n is None else n
    C = cotangent_weights(V, F) if cotangents is None else cotangents
    ok, indptr, cols, half_sums = edge_weight_rows(np.asarray(F, np.int64), 0.5 * C, n)
    if not ok:
        return _normalized_from_sparse(V, F, n, C)
    weights, has = _normalized_weights(np.repeat(np.arange(n), np.diff(indptr)), 2.0 * half_sums, n)
    indptr, indices, data = with_unit_diagonal(indptr, cols, weights, has)
    return sp.csr_matrix((data, indices.astype(np.int32), indptr.astype(np.int32)), shape=(n, n))


def _normalized_weights(rows, w, n):
    """w_ij of Eq. 5-6 from omega_ij (entries of row ``rows``), the floor raised; and which rows have a positive sum."""
    floor = 1e-3 * np.abs(w).mean() if len(w) else 0.0
    w = np.maximum(w, floor)
    total = np.bincount(rows, weights=w, minlength=n)
    return w / total[rows], total > 0


def _normalized_from_sparse(V, F, n, cotangents):
    """:func:`normalized_cotangent_laplacian` by scipy's sparse algebra, for meshes the compiled rows refuse."""
    C = cotangent_laplacian(V, F, n, cotangents).tocoo()
    off = C.row != C.col
    rows, cols = C.row[off], C.col[off]
    weights, has = _normalized_weights(rows, 2.0 * C.data[off], n)
    W = sp.csr_matrix((weights, (rows, cols)), shape=(n, n))
    return (W - sp.diags(has.astype(np.float64))).tocsr()


def reference_normals(ctx):
    """Normals orienting the front angles: each boundary vertex's surface normal plus the hole's mean normal.

    The surface normal alone tilts the front out of the hole on strongly curved holes; the
    hole's mean normal (unit vector area of the boundary) alone lets fronts on holes that wrap
    around a tube take the outside for the inside. Their normalised sum worked on every
    benchmark hole where either alone failed on some.

    Returns
    -------
    (k, 3) float64 unit vectors
    """
    P = ctx.points - ctx.points[0]  # about a loop vertex: raw coordinates far from the origin cancel to noise
    vector_area = 0.5 * np.cross(P, np.roll(P, -1, axis=0)).sum(axis=0)
    norm = np.linalg.norm(vector_area)
    N = ctx.loop_normals + (vector_area / norm if norm > 0 else 0.0)
    length = np.linalg.norm(N, axis=1, keepdims=True)
    return np.where(length > 1e-12, N / np.maximum(length, 1e-300), ctx.loop_normals)


def planar_boundaries(ctx, gaps=None):
    """Simple planar polygons for the boundary, for holes the 3D advancing front cannot cover.

    Not in the paper. The development of the boundary (its edge lengths, and at each vertex
    the angle the surrounding surface leaves open; :func:`geometry.development.develop_loop`), then the
    projection on the best-fitting plane; those that are simple polygons are returned. Where the
    plain development touches itself (a long loop wrapped round a tube, narrow at its waist), the
    least relaxed simple one is taken (:func:`geometry.development.simple_development`, as curve
    unfolding's fallback): the benchmark's torus hole of 211 edges, filled from the ear cutting
    before, 1.47 -> 0.65 per mille of the diagonal from the ground truth; cow.obj subdivided twice,
    ``scripts/large_holes.py --seeds 3``'s 372-edge hole, which failed, closes (8.87; CGAL 9.73);
    ``--seeds 1,2``'s 308-edge cow hole 0.70 -> 0.85 (CGAL 0.76), the other 23 unchanged.

    Parameters
    ----------
    ctx : HoleContext
    gaps : (k,) float64, optional  :func:`geometry.development.boundary_gap_angles` of the loop, when known

    Returns
    -------
    list of (name, (k, 3) float64 with z = 0, counter-clockwise seen from +z)
    """
    from ...geometry.pca import fit_plane, project_to_plane

    k = ctx.size
    gaps = boundary_gap_angles(ctx.vertices, ctx.faces, k) if gaps is None else gaps
    c, n, _, _ = fit_plane(ctx.points)
    vector_area = np.cross(ctx.points, np.roll(ctx.points, -1, axis=0)).sum(axis=0)
    developed = develop_loop(ctx.points, gaps)
    if not (np.all(np.isfinite(developed)) and not polygon_edges_touch(developed)):
        # The plain development touches itself (a long loop round a narrow waist): the least relaxed simple one.
        h = np.linalg.norm(ctx.points - np.roll(ctx.points, -1, axis=0), axis=1).mean()
        relaxed, _ = simple_development(ctx.points, gaps, 1e-5 * h)
        developed = developed if relaxed is None else relaxed
    candidates = [("developed", developed),
                  ("projected", project_to_plane(ctx.points, c, n if n @ vector_area >= 0 else -n))]
    out = []
    for name, Q in candidates:
        if np.all(np.isfinite(Q)) and not polygon_edges_touch(Q):
            area = 0.5 * float(Q[:, 0] @ np.roll(Q[:, 1], -1) - Q[:, 1] @ np.roll(Q[:, 0], -1))
            if area > 0:
                out.append((name, np.column_stack([Q, np.zeros(k)])))
    return out


def harmonic_lift(D, F, P):
    """3D positions for a patch triangulated in a plane: harmonic map with the planar cotangent weights.

    Parameters
    ----------
    D : (n, 3) float64  planar patch vertices, boundary first
    F : (m, 3) int64
    P : (k, 3) float64  3D boundary

    Returns
    -------
    X : (n, 3) float64  with X[:k] = P
    """
    k = len(P)
    X = np.zeros_like(D)
    X[:k] = P
    if len(D) == k:
        return X
    L = normalized_cotangent_laplacian(D, F)
    free = np.arange(len(D)) >= k
    X[free] = spla.splu(L[free][:, free].tocsc()).solve(-(L[free][:, ~free] @ P))
    return X


# A lifted layout whose interior edges are on average this much longer than in the plane is
# refined (refine_layout): 20 % is well above the few per cent a nearly flat hole's lift adds.
LIFT_STRETCH = 1.2


def lift_stretch(X, D, F, k):
    """How much more a lift stretches the layout's interior edges than its boundary edges.

    The mean length of the patch's interior edges in 3D over their mean length in the plane,
    divided by the same ratio of the boundary edges: 1 when the lift keeps the front's density
    relative to the boundary (a flat loop, whatever its scale), above 1 when the patch spans
    more surface than its layout.

    Parameters
    ----------
    X : (n, 3) float64  lifted patch, boundary first
    D : (n, 3) float64  the planar layout it was lifted from
    F : (m, 3) int64
    k : int  boundary vertices

    Returns
    -------
    float  (1 when the patch has no interior edge)
    """
    E = unique_edges(F)
    inner = (E >= k).any(axis=1)
    if not inner.any():
        return 1.0

    def lengths(Y, edges):
        return np.linalg.norm(Y[edges[:, 0]] - Y[edges[:, 1]], axis=1).sum()

    ring = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    inner_ratio = lengths(X, E[inner]) / max(lengths(D, E[inner]), 1e-300)
    boundary_ratio = lengths(X, ring) / max(lengths(D, ring), 1e-300)
    return float(inner_ratio / boundary_ratio)


def refine_layout(D, F, k, forbidden_edges, edge_length):
    """Split a planar layout's faces down to ``edge_length`` (beyond the paper).

    A development shrinks the missing surface where the loop encloses much Gaussian
    curvature (a cap around the end of a bone), and the front, which keeps the boundary's
    edge length in the plane, then leaves the lifted patch with too few, stretched
    triangles. :func:`initial_patches` refines such layouts, by the ratio
    :func:`lift_stretch` measures (``edge_length`` = the layout's mean boundary edge over
    that ratio), before lifting them again: faces split at their centroids
    and Delaunay swaps in the plane (:func:`geometry.refine.refine_patch`, Hu et al.'s
    density rule with a uniform scale), the boundary and ``forbidden_edges`` kept. Measured on
    bone.ply's 60-edge cut hole (the benchmark's, around the bone's end): 5.23 -> 4.41 per mille
    of the diagonal, edge ratio 1.39 -> 1.04, minimum quality 0.290 -> 0.366.

    Parameters
    ----------
    D : (n, 3) float64  planar layout, z = 0, boundary first
    F : (m, 3) int64
    k : int  boundary vertices
    forbidden_edges : (p, 2) int  boundary pairs that must not be joined
    edge_length : float  the planar edge length wanted

    Returns
    -------
    D : (n2, 3) float64  (``D`` first)
    F : (m2, 3) int64
    """
    fixed = boundary_edges_and_chords(k, forbidden_edges)
    D2, F2, _, _ = refine_patch(D, F, np.full(len(D), float(edge_length)), fixed_edges=fixed)
    return D2, F2


def initial_patches(ctx, merge_factor, failures):
    """Initial patches by the advancing front method (Sec. 3.2), then fallbacks, lazily.

    First the paper's 3D advancing front (:func:`advancing_front_triangulation`, steps in the
    plane of the two front edges) with :func:`reference_normals` and the surrounding mesh as
    obstacles. Beyond the paper, for holes it cannot cover (its front grows, i.e. runs out of
    the hole: holes wrapped around a tube, or much larger than the curvature radius) or whose
    result cannot be repositioned clear of the mesh: the same advancing front on each of
    :func:`planar_boundaries`, lifted to 3D by :func:`harmonic_lift` (and, where the lift stretches the
    layout's edges by more than ``LIFT_STRETCH``, refined by that ratio and lifted again,
    :func:`refine_layout`); then Hu et al.'s
    minimum-angle ear cutting refined to the boundary's density; last, for jagged borders whose
    faces tilt every way (noisy scans), the loop's least-bend triangulations
    (:func:`meshlab_holefill.core.least_bend.least_bend_triangulations`) refined alike. The caller
    takes the first that works out.

    Parameters
    ----------
    ctx : HoleContext
    merge_factor : float
    failures : list  reasons of the strategies that failed are appended to it

    Yields
    ------
    X : (k + p, 3) float64  boundary then new vertices
    F : (q, 3) int64
    stats : dict  the triangulation's counts and ``domain`` ('3d', 'developed', 'projected', 'ears', 'least bend'), for
        the developed layout ``enclosed_curvature`` (radians, :func:`geometry.development.enclosed_curvature`),
        and for a refined layout ``lift_stretch`` and ``lift_refined`` (vertices added)
    layout : (k + p, 3) float64 or None  the planar patch the front built, z = 0 (the planar domains;
        None where the front or the ear cutting built the patch in 3D)
    """
    P = ctx.points
    try:
        new_vertices, F, stats = advancing_front_triangulation(
            P, ctx.forbidden_edges, merge_factor, reference_normal=reference_normals(ctx),
            obstacles=ctx.surroundings())
        stats["domain"] = "3d"
        yield np.concatenate([P, new_vertices]), F, stats, None
    except HoleFillError as exc:
        failures.append(f"3d advancing front: {exc}")
    gaps = boundary_gap_angles(ctx.vertices, ctx.faces, len(P))
    for name, D in planar_boundaries(ctx, gaps):
        try:
            new_vertices, F, stats = advancing_front_triangulation(D, ctx.forbidden_edges, merge_factor,
                                                                   reference_normal=(0.0, 0.0, 1.0))
        except HoleFillError as exc:
            failures.append(f"{name} advancing front: {exc}")
            continue
        stats["domain"] = name
        if name == "developed":
            stats["enclosed_curvature"] = enclosed_curvature(gaps)
        layout = np.concatenate([D, new_vertices])
        X = harmonic_lift(layout, F, P)
        stretch = lift_stretch(X, layout, F, len(P))
        if stretch > LIFT_STRETCH:
            before, planar_edge = len(layout), np.linalg.norm(D - np.roll(D, -1, axis=0), axis=1).mean()
            layout, F = refine_layout(layout, F, len(P), ctx.forbidden_edges, planar_edge / stretch)
            X = harmonic_lift(layout, F, P)
            stats.update(lift_stretch=stretch, lift_refined=len(layout) - before)
        yield X, F, stats, layout
    from ..hu2012.min_angle_triangulation import min_angle_triangulation

    try:
        F0 = min_angle_triangulation(P, ctx.loop_normals, ctx.forbidden_edges)
    except HoleFillError as exc:
        failures.append(f"ear cutting: {exc}")
    else:
        X, F, _, info = refine_patch(P, F0, ctx.edge_scale, fixed_edges=_fixed_edges(ctx))
        yield X, F, {"domain": "ears", **info}, None
    for F0 in least_bend_triangulations(ctx):
        X, F, _, info = refine_patch(P, F0, ctx.edge_scale, fixed_edges=_fixed_edges(ctx))
        yield X, F, {"domain": "least bend", **info}, None


def solve_folds(X, F, fixed, before=None):
    """Does the Poisson solve fold the patch (:func:`geometry.flips.folds` without the fixed triangles)?

    A triangle of boundary vertices only keeps its place whatever the solve does: a fold
    between two such triangles (the front bridges a narrow stretch of the hole with them) is
    the initial patch's. Judging the solve by it threw the solve away on bone.ply's 72-edge hole
    wrapped around the knob (holes cut with ``scripts/benchmark.py --seed 1 --holes 6``): the
    patch's mean distance to the ground truth is 9.9 per mille of the bounding-box diagonal
    with the solve, 19.4 without. So is a fold that the patch had before the solve (``before``,
    its positions then): a fan of triangles from one free vertex to a narrow notch of the
    boundary (gap angles of 314, 45 and 312 degrees on airplane.obj Loop-subdivided once,
    ``scripts/large_holes.py``'s airplane1_s1 hole 0, 296 edges) is folded in the lifted patch
    already, and every solve was thrown away for it: 9.60 per mille from the ground truth
    without the solve, 5.92 with it (CGAL's Liepa fill 4.89). :func:`.poisson_reconstruction.unfold`
    asks first for a patch without any fold, then for one without folds of the solve's own.

    Parameters
    ----------
    X : (n, 3) float64, F : (m, 3) int64, fixed : (n,) bool
    before : (n, 3) float64, optional  the positions before the solve

    Returns
    -------
    bool  a triangle with a free vertex is degenerate, or it meets a neighbour at a dihedral
        angle over 120 degrees that it did not meet at before
    """
    return folds(X, F, fixed, before)


def _ear_guard(k):
    """``allowed`` test of :func:`relax_edges` for a patch whose first k vertices are the hole boundary.

    Refuses a swap that creates a triangle of three boundary vertices (an ear) and lowers
    the minimum quality of the two triangles. On a curved patch the circumsphere test can
    prefer the diagonal that cuts off an ear at a wide border corner (face000's 19-edge hole:
    quality 0.28 with an angle of 134 degrees at the corner); no later step can repair it,
    as its vertices are fixed. Other swaps are left to the circumsphere test.
    """
    def allowed(V, F, A, B, replaced):
        ear = (A < k).all(axis=1) | (B < k).all(axis=1)
        ok = ~ear
        if ear.any():
            old = triangle_quality(V, F[replaced[ear].ravel()]).reshape(-1, 2).min(axis=1)
            new = np.minimum(triangle_quality(V, A[ear]), triangle_quality(V, B[ear]))
            ok[ear] = new >= old
        return ok
    return allowed


def relax_patch(X, F, ctx):
    """Delaunay edge swaps on the patch (beyond the paper, needed for the quality target).

    Run on the advancing-front patch (the fronts leave thin triangles where they meet) and
    after the Poisson solve (which moves vertices along the surface as well as across it).
    The boundary edges and the mesh's chords between boundary vertices never swap, nor does
    an edge whose swap would cut off an ear of lower quality (:func:`_ear_guard`); whether
    the result stays clear of the surrounding mesh is checked once at the end of :func:`fill`.

    Returns
    -------
    F : (q, 3) int64
    swaps : int
    """
    if len(F) < 2:
        return F, 0
    return relax_edges(X, F, _fixed_edges(ctx), allowed=_ear_guard(ctx.size))


def _fixed_edges(ctx):
    """Edges no swap may touch: the hole boundary and the mesh's chords between boundary vertices."""
    return boundary_edges_and_chords(ctx.size, ctx.forbidden_edges)


def repair_slivers(X, F, fixed, ctx, floor=0.3, rings=2, iterations=20, rounds=3):
    """Local tangential smoothing around the triangles of quality below ``floor`` (beyond the paper).

    The Poisson solve (Sec. 3.4) can squeeze the row of triangles along a stretch of the
    border: on face000's 227-edge hole it pulls inner vertices to within a fraction of an
    edge of the boundary edges and turns the patch back against the border faces there
    (angle up to 150 degrees at the inner vertex, quality 0.04-0.15). The global
    tangential smoothing (:func:`geometry.laplacian.tangential_umbrella_smoothing`, 3 steps)
    and the swaps lift them to 0.22 only, and a
    boundary edge cannot be swapped. Here the inner vertices of the triangles below
    ``floor``, with ``rings`` rings of neighbours, get ``iterations`` further tangential
    steps (the others stay put) and the patch is swapped again (:func:`relax_patch`); a round
    is kept only when it raises the patch's minimum quality and does not fold it, and at most
    ``rounds`` rounds run while the minimum stays below ``floor``. Patches without such
    triangles are returned unchanged. Measured with the square Dirichlet system
    (``poisson_boundary='dirichlet'``): face000's 227-edge hole 0.216 -> 0.340 (mean 0.918 ->
    0.918): 34 vertices moved, by at most 0.35 mean boundary edge lengths; the other benchmark
    holes have no such triangle. With the boundary's Laplacian rows (the default) the solve
    does not squeeze that row (0.340 without a repair) and no benchmark hole needs one.

    A poor triangle of loop vertices only (a cap of a loop-only least-bend patch) is out of
    reach of any move: it is split first (:func:`_split_loop_caps`), which counts as a round kept.

    Parameters
    ----------
    X : (n, 3) float64, F : (m, 3) int64, fixed : (n,) bool (the hole boundary)
    ctx : HoleContext  (for the swaps' fixed edges)

    Returns
    -------
    X : (n, 3) float64
    F : (m, 3) int64
    repaired : int  rounds kept
    """
    q = triangle_quality(X, F)
    kept = 0
    if len(q) and q.min() < floor:
        X, F, fixed, split = _split_loop_caps(X, F, np.asarray(fixed, bool), ctx.size, floor)
        if split:
            q, kept = triangle_quality(X, F), 1
    for _ in range(rounds):
        if len(q) == 0 or q.min() >= floor:
            break
        region = vertices_near(F, len(X), q < floor, rings)
        region &= ~np.asarray(fixed, bool)
        if not region.any():
            break
        Y = tangential_umbrella_smoothing(X, F, ~region, iterations)
        G, _ = relax_patch(Y, F, ctx)
        qn = triangle_quality(Y, G)
        if qn.min() <= q.min() or folds(Y, G):
            break
        X, F, q = Y, G, qn
        kept += 1
    return X, F, kept


def _split_loop_caps(X, F, fixed, k, floor):
    """:func:`geometry.caps.split_loop_caps` on the patch (its first ``k`` vertices the loop's), kept unless
    the split patch folds.

    A small slit-like hole filled by its loop-only least-bend patch (a range scan's 9-edge hole
    whose chords mostly duplicate mesh edges) can keep a cap: a loop vertex almost on the chord
    of two others (quality 0.002, angle 177 degrees), the swap of that chord being a mesh edge.
    The split's vertex is an inner vertex the repair's later rounds may move.

    Returns
    -------
    X, F, fixed, split : the patch (with the new inner vertices appended, not fixed) and whether it was split
    """
    Y, G = split_loop_caps(X, F, k, floor)
    if len(Y) == len(X) or folds(Y, G):
        return X, F, fixed, False
    return Y, G, np.concatenate([fixed, np.zeros(len(Y) - len(X), bool)]), True


def context_hits(X, F, ctx):
    """Patch faces (indices into F) crossing another patch face or the HoleContext's surrounding faces.

    :func:`meshlab_holefill.core.crossings.context_crossings`. The patch's own crossings count
    since a solve that continues a steep wall into the hole can fold the patch over itself
    near the border (bunny.obj with its lowest tenth cut off by height, a nearly planar
    231-edge loop: 149 crossing pairs within the patch, none with the mesh); the filter
    would only learn of it when the pipeline rejects the patch.

    Parameters
    ----------
    X : (k + p, 3) float64  patch vertices, the hole boundary first (as ``ctx.points``)
    F : (q, 3) int64        patch faces
    ctx : HoleContext
    """
    return context_crossings(ctx, X, F)
