"""Guards that keep a patch inside its hole: hole-sector tests and crossing checks.

A triangulation step or an edge swap must not make a boundary vertex send an edge out of the
hole, through the surrounding mesh. :func:`inside_hole_sector` and :class:`LoopSectors` test
the direction of such an edge in the tangent plane of the vertex (the hole side is the sector
swept counter-clockwise from the next boundary vertex to the previous one, the loop being in
patch orientation); :func:`patch_crossings` and :func:`swaps_crossing` test new triangles
against the surrounding faces of a HoleContext and the rest of the patch;
:func:`patch_guard` combines them as the veto hook of :func:`geometry.flips.relax_edges`.
"""
from __future__ import annotations

import numpy as np

from ...geometry.flips import fixed_edge_keys, relax_edges
from ...geometry.sets import unique_ints
from ...geometry.intersections import intersecting_pairs, intersecting_pairs_with_fixed
from ...geometry.quality import cross_rows
from ._relax_kernels import SETTLED, STOPPED, relax_rounds
from ._sector_kernels import sector_contains, swaps_in_sectors

__all__ = ["sector_angle", "inside_hole_sector", "LoopSectors", "patch_crossings", "patch_guard", "swaps_crossing",
           "relax_in_sectors"]


def sector_angle(apex, normal, reference, directions):
    """Angles of directions about ``normal``, counter-clockwise from (reference - apex), in [0, 2 pi).

    Parameters
    ----------
    apex, normal, reference : (3,) float64
    directions : (d, 3) float64
    """
    n = normal / max(np.linalg.norm(normal), 1e-300)
    u = reference - apex
    u = u - np.dot(u, n) * n
    u /= max(np.linalg.norm(u), 1e-300)
    w = np.cross(n, u)
    D = np.atleast_2d(directions)
    return np.mod(np.arctan2(D @ w, D @ u), 2 * np.pi)


def inside_hole_sector(apex, normal, prev_point, next_point, targets, margin=1e-9):
    """True where the segment from a boundary vertex to each target starts into the hole.

    With the loop in patch orientation the hole side at a vertex is the sector swept
    counter-clockwise (about the vertex normal, in its tangent plane) from the next
    boundary vertex to the previous one. Used to refuse diagonals and swapped edges that
    would leave a boundary vertex on the wrong side, through the surrounding mesh.

    Parameters
    ----------
    apex, normal, prev_point, next_point : (3,) float64
    targets : (d, 3) float64

    Returns
    -------
    (d,) bool
    """
    limit = sector_angle(apex, normal, next_point, prev_point - apex)[0]
    phi = sector_angle(apex, normal, next_point, np.atleast_2d(targets) - apex)
    return (phi > margin) & (phi < limit - margin)


class LoopSectors:
    """The hole sector of every loop vertex, for vectorised :func:`inside_hole_sector` tests.

    Parameters
    ----------
    points : (k, 3) float64  loop points, patch orientation
    normals : (k, 3) float64
    """

    def __init__(self, points, normals):
        P = np.asarray(points, np.float64)
        N = np.asarray(normals, np.float64)
        N = N / np.maximum(np.linalg.norm(N, axis=1), 1e-300)[:, None]
        u = np.roll(P, -1, axis=0) - P
        u -= np.einsum("ij,ij->i", u, N)[:, None] * N
        u /= np.maximum(np.linalg.norm(u, axis=1), 1e-300)[:, None]
        self.points, self.u, self.w = np.ascontiguousarray(P), u, cross_rows(N, u)  # np.cross's bits
        self.limit = self._angle(np.arange(len(P)), np.roll(P, 1, axis=0))

    def _angle(self, i, targets):
        D = targets - self.points[i]
        return np.mod(np.arctan2(np.einsum("ij,ij->i", D, self.w[i]), np.einsum("ij,ij->i", D, self.u[i])),
                      2 * np.pi)

    def contains(self, i, targets, margin=1e-9):
        """(s,) bool: does the segment from loop vertex i[j] to targets[j] start into the hole?

        Compiled (:func:`._sector_kernels.sector_contains`); an angle too close to a bound to
        decide there is decided by :meth:`contains_numpy`, so the answer is always its answer.
        """
        i = np.ascontiguousarray(i, np.int64)
        T = np.ascontiguousarray(np.atleast_2d(targets), np.float64)
        if len(i) == 0 and T.size == 0:
            return np.zeros(0, bool)
        if T.shape == (len(i), 3) and len(i) and 0 <= i.min() and i.max() < len(self.points):
            inside, sure = sector_contains(self.points, self.u, self.w, self.limit, i, T, float(margin))
            if sure:
                return inside
        return self.contains_numpy(i, targets, margin)

    def swaps_allowed(self, V, B):
        """(s,) bool: does the new edge (B[r, 1], B[r, 2]) of each swap start into the hole at its loop ends?

        Both ends in one compiled pass (:func:`._sector_kernels.swaps_in_sectors`); when an
        angle there is too close to a bound, :meth:`contains_numpy` end by end, so the answer
        is always the numpy code's.
        """
        B = np.asarray(B)
        V = np.asarray(V)
        if B.dtype == np.int64 and B.ndim == 2 and B.shape[1] == 3 and V.dtype == np.float64 and V.ndim == 2 \
                and V.shape[1] == 3:
            ok, sure = swaps_in_sectors(self.points, self.u, self.w, self.limit, np.ascontiguousarray(V),
                                        np.ascontiguousarray(B), 1e-9)
            if sure:
                return ok
        k = len(self.points)
        c, d = B[:, 1], B[:, 2]
        ok = np.ones(len(B), bool)
        for end, other in ((c, d), (d, c)):
            on_loop = end < k
            ok[on_loop] &= self.contains_numpy(end[on_loop], V[other[on_loop]])
        return ok

    def contains_numpy(self, i, targets, margin=1e-9):
        """:meth:`contains` in numpy (the reference of the compiled test)."""
        i = np.asarray(i, np.int64)
        phi = self._angle(i, np.atleast_2d(targets))
        return (phi > margin) & (phi < self.limit[i] - margin)


def patch_crossings(ctx, patch_points, patch_faces, faces=None):
    """Patch faces (or the given subset of candidate faces) that intersect the HoleContext's surrounding faces.

    Parameters
    ----------
    ctx : HoleContext
    patch_points : (k + p, 3) float64  loop points then new vertices
    patch_faces : (q, 3) int           faces in patch numbering
    faces : (s, 3) int, optional       faces to test instead of ``patch_faces``

    Returns
    -------
    (t,) int64 sorted indices into the tested faces
    """
    surrounding_points, surrounding_faces = ctx.surroundings()
    k, n_local = ctx.size, len(surrounding_points)
    test = np.asarray(patch_faces if faces is None else faces, np.int64).reshape(-1, 3)
    if len(test) == 0 or len(surrounding_faces) == 0:
        return np.zeros(0, np.int64)
    X = np.concatenate([surrounding_points, np.asarray(patch_points)[k:]])
    local = np.where(test >= k, test - k + n_local, test)
    allF = np.concatenate([local, surrounding_faces])
    # The two face sets are disjoint, so every pair has its tested face first: faces_intersecting's
    # answer, without its membership tests for pairs listed the other way round.
    pairs = intersecting_pairs_with_fixed(X, allF, np.arange(len(local)), ctx.surrounding_bounds, len(local))
    return unique_ints(pairs[:, 0])


def patch_guard(ctx, check_intersections=False, sectors=None):
    """Veto for edge swaps that would push a patch out of its hole or through itself.

    Returns ``allowed(V, F, A, B, replaced) -> (s,) bool`` (the ``allowed`` hook of
    :func:`geometry.flips.relax_edges`), where V, F are the current patch (loop vertices
    first, as in a Patch) and A[i], B[i] the two triangles a swap would create in place of
    faces replaced[i]. A swap is refused when its new edge leaves a boundary vertex outside
    its hole sector (:class:`LoopSectors`) and, with ``check_intersections``, when a new
    triangle intersects the surrounding faces or the rest of the patch (slower: one
    intersection query per round of swaps). ``sectors``: the loop's :class:`LoopSectors`, when
    the caller has them.
    """
    if sectors is None:
        sectors = LoopSectors(ctx.points, ctx.loop_normals)

    def allowed(V, F, A, B, replaced):
        ok = sectors.swaps_allowed(V, B)
        if not check_intersections or not ok.any():
            return ok
        idx = np.flatnonzero(ok)
        ok[idx] &= ~swaps_crossing(ctx, V, F, A[idx], B[idx], replaced[idx])
        return ok

    return allowed


def relax_in_sectors(sectors, V, F, fixed_edges=None, criterion="sphere", refused=None, max_rounds=200):
    """:func:`geometry.flips.relax_edges` vetoed by the hole-sector test, its rounds compiled.

    The faces and swap count of ``relax_edges(V, F, fixed_edges, allowed=guard, criterion=criterion,
    max_rounds=max_rounds)`` with the guard ``patch_guard(ctx, sectors=sectors)``, or ``refused``
    when given: a hook that agrees with the sector test wherever that allows every candidate
    (:func:`.min_angle_bilateral.relaxation_guard`, which reconsiders the swaps it refuses). The
    rounds run in :func:`._relax_kernels.relax_rounds`; a round it cannot decide, or one the sector
    test refuses a swap of when ``refused`` is given, runs in :func:`relax_edges` with the hook.

    Parameters
    ----------
    sectors : LoopSectors  of the loop, vertices 0 .. k - 1 of V
    V : (n, 3) float64, F : (m, 3) int64  the patch, loop first
    fixed_edges : (p, 2) int, optional
    criterion : {"sphere", "angles"}
    refused : callable ``allowed(V, F, A, B, replaced) -> (s,) bool``, optional
    max_rounds : int

    Returns
    -------
    F : (m, 3) int64
    swaps : int
    settled : bool
        The last round was a compiled one in which the sector test refused nothing: relaxing
        ``F`` again, with the sector test or a ``refused`` hook, makes no swap.
    """
    V = np.ascontiguousarray(V, np.float64)
    F = np.array(F, np.int64)
    guard = refused if refused is not None else (lambda V, F, A, B, replaced: sectors.swaps_allowed(V, B))
    if criterion not in ("sphere", "angles") or F.ndim != 2 or F.shape[1] != 3 or V.ndim != 2 or V.shape[1] != 3:
        return (*relax_edges(V, F, fixed_edges, max_rounds=max_rounds, allowed=guard, criterion=criterion), False)
    fixed = fixed_edge_keys(fixed_edges, len(V))
    total, left = 0, max_rounds
    while left > 0:
        status, swaps, rounds = relax_rounds(V, F, fixed, criterion == "sphere", left, sectors.points, sectors.u,
                                             sectors.w, sectors.limit, 1e-9, refused is not None)
        total, left = total + swaps, left - rounds
        if status in (STOPPED, SETTLED):
            return F, total, status == SETTLED
        F, swaps = relax_edges(V, F, fixed_edges, max_rounds=1, allowed=guard, criterion=criterion)
        total, left = total + swaps, left - 1
        if swaps == 0:
            break
    return F, total, False


def swaps_crossing(ctx, V, F, A, B, replaced):
    """Which edge swaps would make a patch cross the surrounding faces or itself.

    Parameters
    ----------
    ctx : HoleContext
    V : (k + p, 3) float64  the current patch's points (loop first, as in a Patch)
    F : (q, 3) int          the current patch's faces
    A, B : (s, 3) int       the two triangles each swap would create
    replaced : (s, 2) int   the faces of ``F`` each swap replaces (they do not count against it)

    Returns
    -------
    (s,) bool  True where a new triangle intersects the mesh near the hole or the rest of the patch
    """
    s = len(A)
    new = np.concatenate([A, B])
    bad = np.zeros(2 * s, bool)
    bad[patch_crossings(ctx, V, None, faces=new)] = True
    allF = np.concatenate([new, F])
    pairs = intersecting_pairs(V, allF, np.arange(2 * s), np.arange(2 * s, len(allF)))
    if len(pairs):
        q, other = pairs[:, 0], pairs[:, 1] - 2 * s
        own = replaced[q % s]
        bad[q[(other != own[:, 0]) & (other != own[:, 1])]] = True
    return bad[:s] | bad[s:]
