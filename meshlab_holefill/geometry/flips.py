"""Edge relaxation by edge swaps: the circumsphere (Delaunay-like) criterion of Pfeifle and Seidel."""
from __future__ import annotations

import numpy as np

from . import _flip_kernels as K
from .quality import cross_rows, face_normals
from .sets import isin_ints
from .topology import interior_edges

__all__ = ["circumcenters", "folds", "min_angle_scores", "relax_edges"]


def circumcenters(V, F):
    """Circumcentres and circumradii of 3D triangles.

    Returns
    -------
    centers : (m, 3) float64
    radii : (m,) float64   (inf for degenerate triangles)
    """
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    a, b = B - A, C - A
    axb = cross_rows(a, b)
    denom = 2.0 * np.einsum("ij,ij->i", axb, axb)
    num = cross_rows(np.einsum("ij,ij->i", a, a)[:, None] * b - np.einsum("ij,ij->i", b, b)[:, None] * a, axb)
    with np.errstate(divide="ignore", invalid="ignore"):
        offset = num / denom[:, None]
    centers = A + offset
    radii = np.linalg.norm(offset, axis=1)
    bad = ~(denom > 0)
    radii[bad] = np.inf
    centers[bad] = A[bad]
    return centers, radii


def _triangle_normals(P, Q, R):
    return cross_rows(Q - P, R - P)


def _angle_at(P, Q, R):
    """Angle at P of the triangles (P, Q, R), row-wise."""
    u, w = Q - P, R - P
    return np.arctan2(np.linalg.norm(cross_rows(u, w), axis=1), np.einsum("ij,ij->i", u, w))


def min_angle_scores(V, old1, old2, new1, new2):
    """Smallest corner angle of a pair of triangles before and after the swap of their edge.

    The swap test of Xie and Zou (2013) Sec. 4.7, Fig. 5(c)-(d): an edge P_1 P_2 with opposite
    vertices Q_1, Q_2 becomes Q_1 Q_2 when the smallest angle of P_1 Q_1 Q_2, P_2 Q_1 Q_2
    exceeds that of P_1 P_2 Q_1, P_1 P_2 Q_2. Scorer of ``criterion="min_angle"`` in
    :func:`relax_edges`.

    Parameters
    ----------
    V : (n, 3) float64
    old1, old2 : (s, 3) int  the current pair of faces of each edge
    new1, new2 : (s, 3) int  the pair after the swap

    Returns
    -------
    old, new : (s,) float64  smallest angle (radians) of each pair
    """
    # The corner angles of quality.corner_angles, their arctan2 arguments compiled (same bits).
    faces = np.stack([old1, old2, new1, new2]).astype(np.int64, copy=False)
    sines, cosines = K.pair_angle_parts(np.ascontiguousarray(V, np.float64), faces)
    angles = np.arctan2(sines, cosines)
    # Pairwise minima of the three corners: the values of .min(axis=2), whose reduction along
    # a last axis of three runs one short inner loop per face (about 20 times slower). The
    # angles are never -0 (arctan2 of a norm); a NaN's sign bit is the reduction's own, so
    # with a NaN it decides.
    smallest = np.minimum(np.minimum(angles[..., 0], angles[..., 1]), angles[..., 2])
    if np.isnan(smallest).any():
        smallest = angles.min(axis=2)
    return np.minimum(smallest[0], smallest[1]), np.minimum(smallest[2], smallest[3])


def fixed_edge_keys(fixed_edges, n):
    """Sorted distinct undirected keys (k,) int64 of the edges no swap may touch ((p, 2) int or None)."""
    E = np.ascontiguousarray(np.asarray(() if fixed_edges is None else fixed_edges, np.int64).reshape(-1, 2))
    return K.fixed_keys(E, n)


def relax_edges(V, F, fixed_edges=None, max_rounds=200, allowed=None, criterion="sphere", normal_cos=0.0, *,
                compiled=True):
    """Swap interior edges until every one passes the swap test (default: circumsphere, Hu et al. Sec. III.C).

    For an interior edge (a, b) with triangles (a, b, c) and (b, a, d) the test passes when
    d lies outside the circumsphere of (a, b, c) and c outside that of (b, a, d); otherwise
    the edge is swapped to (c, d), provided (c, d) passes the same test (on a non-planar quad
    both diagonals may fail it). A swap is refused when it would fold the surface (a new
    triangle facing against the old pair), create a duplicate edge, or touch a fixed edge.
    Swaps are applied in rounds of non-adjacent edges (vectorised).

    With ``criterion="angles"`` the test is made on the two triangles unfolded into one
    plane around their common edge (the intrinsic Delaunay test): the edge fails it when the
    angles opposite it at c and d add up to more than pi. On a planar quad this is the
    circumcircle test; on a strongly folded one the two circumsphere tests can both pass
    for the worse diagonal (a sliver between spikes of a jagged border keeps its edge).
    As with the sphere test, a swap is made only when the new edge passes the test.

    With ``criterion="min_angle"`` an edge is swapped when that raises the smallest angle of
    its two triangles (Xie and Zou 2013, Sec. 4.7; :func:`min_angle_scores`). A callable
    criterion generalises this: ``criterion(V, old1, old2, new1, new2) -> (old, new)`` scores
    (higher is better) each edge's current pair of faces old1[i], old2[i] and the swapped pair
    new1[i] = (a, d, c), new2[i] = (b, c, d); the edge is swapped when ``new > old + 1e-9``.
    The strict gain is the anti-cycling rule of these scored tests (no swap can be undone); a
    scorer rules an edge out by returning ``new = -inf``. Scored swaps are greedy: when swaps
    compete for a face (or would create the same edge) the one of highest priority is made and
    the others wait for the next round, where they are scored again on the new faces. The
    priority is the gain ``new - old`` unless the scorer returns it as a third array
    ``(old, new, priority)`` (higher first).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64, consistently oriented
    fixed_edges : (p, 2) int, optional
        Edges that must not be swapped (and must not be created).
    max_rounds : int
    allowed : callable, optional
        ``allowed(V, F, A, B, replaced) -> (s,) bool`` for candidate swaps whose new
        triangles are A[i] = (a, d, c) and B[i] = (b, c, d), replacing faces replaced[i] of the
        current faces F; lets the caller refuse swaps that would leave the hole (e.g. through
        the surrounding mesh).
    criterion : {"sphere", "angles", "min_angle"} or callable
        The circumsphere test in space (default), the unfolded (opposite-angle) test, the
        minimum-angle gain, or a scorer as described above.
    normal_cos : float or None
        A swap is refused when a new triangle's normal makes a cosine of at most this with the
        mean normal of the replaced pair (0: no fold; 0.5: neither new triangle turns by 60
        degrees or more, which keeps the shape of a bent quad). None skips the test, for a
        scorer that judges folds itself.
    compiled : bool
        With ``criterion="sphere"`` or ``"angles"`` and ``normal_cos=0``, or ``criterion="min_angle"``
        without ``allowed``, run the rounds compiled (:mod:`._flip_kernels`, the same swaps as the
        numpy rounds); False runs numpy only.

    Returns
    -------
    F : (m, 3) int64
        Relaxed faces (same count).
    swaps : int
    """
    F = np.array(F, np.int64)
    n = len(V)
    fixed = fixed_edge_keys(fixed_edges, n)
    scorer = min_angle_scores if criterion == "min_angle" else criterion if callable(criterion) else None
    if compiled and isinstance(criterion, str) and criterion in ("angles", "sphere") and normal_cos == 0.0:
        V = np.ascontiguousarray(V, np.float64)
        return _relax_compiled(V, F, fixed, max_rounds, allowed, criterion)
    if compiled and criterion == "min_angle" and allowed is None and normal_cos is not None:
        return _relax_min_angle_compiled(np.ascontiguousarray(V, np.float64), F, fixed, max_rounds, float(normal_cos))
    return _relax_numpy(V, F, fixed, max_rounds, allowed, criterion, normal_cos, scorer)


def _relax_min_angle_compiled(V, F, fixed, max_rounds, normal_cos):
    """The ``criterion="min_angle"`` rounds of :func:`relax_edges` (no ``allowed``) compiled around numpy's arctan2.

    Each round: the edge table and scored faces (:func:`._flip_kernels.min_angle_round_faces`),
    numpy's ``arctan2`` of their corners (as :func:`min_angle_scores`), then the choice and the
    swaps (:func:`._flip_kernels.min_angle_round_swaps`); the same swaps as the numpy rounds. A
    round the compiled code cannot decide (a directed edge repeats, an angle is NaN) and those
    after it run in numpy.
    """
    total = 0
    for done in range(max_rounds):
        fine, he, tw, start, half, tip, faces, sines, cosines = K.min_angle_round_faces(V, F)
        status = K.UNSURE
        if fine:
            if len(he) == 0:
                break
            status, swaps = K.min_angle_round_swaps(V, F, he, tw, start, half, tip, faces, np.arctan2(sines, cosines),
                                                    fixed, normal_cos)
        if status == K.UNSURE:
            F, more = _relax_numpy(V, F, fixed, max_rounds - done, None, "min_angle", normal_cos, min_angle_scores)
            return F, total + more
        if status != K.CANDIDATES:
            break
        total += swaps
    return F, total


def _relax_compiled(V, F, fixed, max_rounds, allowed, criterion):
    """The rounds of :func:`relax_edges` by :mod:`._flip_kernels`; a round they cannot decide runs in numpy."""
    total = 0
    for _ in range(max_rounds):
        status, abcd, f1f2, ok, new_key = K.swap_candidates(V, F, fixed, criterion == "sphere")
        if status == K.UNSURE:
            F, swaps, more = _relax_numpy(V, F, fixed, 1, allowed, criterion, 0.0, None, rounds_left=True)
            total += swaps
            if not more:
                break
            continue
        if status != K.CANDIDATES:
            break
        cand = np.flatnonzero(ok)
        if allowed is not None and len(cand):
            abcd_c = abcd[cand]  # the new triangles (a, d, c) and (b, c, d)
            cand = cand[allowed(V, F, abcd_c[:, [0, 3, 2]], abcd_c[:, [1, 2, 3]], f1f2[cand])]
        if len(cand) == 0:
            break
        total += K.apply_swaps(F, cand, abcd, f1f2, new_key)
    return F, total


def _relax_numpy(V, F, fixed, max_rounds, allowed, criterion, normal_cos, scorer, rounds_left=False):
    """The rounds of :func:`relax_edges` in numpy; with ``rounds_left`` also whether the last round
    swapped (False: it stopped as relax_edges stops)."""
    n = len(V)
    total = 0
    more = False
    for _ in range(max_rounds):
        more = False
        E, f1, c1, f2, c2 = interior_edges(F, n)
        if len(E) == 0:
            break
        c = F[f1, (c1 + 2) % 3]
        d = F[f2, (c2 + 2) % 3]
        a, b = E[:, 0], E[:, 1]
        inside, priority = _failing_edges(V, F, a, b, c, d, f1, f2, criterion, scorer)
        ok = np.zeros(len(E), bool)
        s = np.flatnonzero(inside)
        if len(s) == 0:
            break
        a_, b_, c_, d_ = a[s], b[s], c[s], d[s]
        passes = _new_edge_passes(V, a_, b_, c_, d_, criterion, scorer)
        keeps_orientation = _keeps_orientation(V, a_, b_, c_, d_, normal_cos)
        lo, hi = np.minimum(c, d), np.maximum(c, d)
        new_key = lo * n + hi
        # Undirected keys of the current edges; min/max of the two columns rather than a row-wise
        # sort, which numpy runs as one small sort per row.
        u, w = F.ravel(), F[:, [1, 2, 0]].ravel()
        existing = np.minimum(u, w) * n + np.maximum(u, w)
        ok_s = passes & keeps_orientation & (c_ != d_) & ~isin_ints(new_key[s], existing)
        if len(fixed):
            old_key = np.minimum(a_, b_) * n + np.maximum(a_, b_)
            ok_s &= ~isin_ints(old_key, fixed) & ~isin_ints(new_key[s], fixed)
        ok[s] = ok_s
        cand = np.flatnonzero(ok)
        if allowed is not None and len(cand):
            cand = cand[allowed(V, F, np.stack([a[cand], d[cand], c[cand]], axis=1),
                                np.stack([b[cand], c[cand], d[cand]], axis=1),
                                np.stack([f1[cand], f2[cand]], axis=1))]
        if len(cand) == 0:
            break
        chosen = _independent_swaps(cand, f1, f2, priority, new_key, len(F), scorer is not None)
        F[f1[chosen]] = np.stack([a[chosen], d[chosen], c[chosen]], axis=1)
        F[f2[chosen]] = np.stack([b[chosen], c[chosen], d[chosen]], axis=1)
        total += len(chosen)
        more = True
    return (F, total, more) if rounds_left else (F, total)


def _failing_edges(V, F, a, b, c, d, f1, f2, criterion, scorer):
    """The swap test on every interior edge (a, b) with opposite corners c, d: which fail it, and their priority.

    Of the swaps competing for a face the one of highest priority is made: by default the
    highest edge index, for scored criteria the largest gain (or the scorer's priority).

    Returns
    -------
    inside : (e,) bool  edges failing the test (candidates for a swap)
    priority : (e,) int64  (for scored criteria, 0 on the edges that pass)
    """
    priority = np.arange(len(a))
    # The remaining tests run only on the edges that fail this one: most edges pass it.
    if scorer is not None:
        scores = scorer(V, F[f1], F[f2], np.stack([a, d, c], axis=1), np.stack([b, c, d], axis=1))
        old_s, new_s = scores[:2]
        inside = new_s > old_s + 1e-9
        # Ranked among the failing edges only (few): only candidates' priorities are compared,
        # and a stable sort of a subset keeps their order in the sort of all edges.
        s = np.flatnonzero(inside)
        gain = scores[2] if len(scores) > 2 else new_s - old_s
        order = np.argsort(-gain[s], kind="stable")
        priority = np.zeros(len(a), np.int64)
        priority[s[order]] = np.arange(len(s), 0, -1)
    elif criterion == "angles":
        inside = _angle_at(V[c], V[a], V[b]) + _angle_at(V[d], V[a], V[b]) > np.pi * (1 + 1e-9)
    else:
        # Circumspheres once per face (row-wise, so the same values as per edge).
        cc, r = circumcenters(V, F)
        cc1, r1, cc2, r2 = cc[f1], r[f1], cc[f2], r[f2]
        # Strictly inside (relative margin) so that cocircular quads do not flip forever.
        inside = (np.linalg.norm(V[d] - cc1, axis=1) < r1 * (1 - 1e-9)) | \
                 (np.linalg.norm(V[c] - cc2, axis=1) < r2 * (1 - 1e-9))
    return inside, priority


def _new_edge_passes(V, a_, b_, c_, d_, criterion, scorer):
    """Whether the new edge (c, d) passes the test (on a non-planar quad both diagonals can fail it).

    Swapping only when the new edge passes rules out swapping back and forth; a scored
    criterion's strict gain already does.
    """
    if scorer is not None:
        return np.ones(len(a_), bool)
    if criterion == "angles":
        return _angle_at(V[a_], V[d_], V[c_]) + _angle_at(V[b_], V[c_], V[d_]) <= np.pi * (1 + 1e-9)
    cc3, r3 = circumcenters(V, np.stack([a_, d_, c_], axis=1))
    cc4, r4 = circumcenters(V, np.stack([b_, c_, d_], axis=1))
    return (np.linalg.norm(V[b_] - cc3, axis=1) >= r3 * (1 - 1e-9)) & \
           (np.linalg.norm(V[a_] - cc4, axis=1) >= r4 * (1 - 1e-9))


def _keeps_orientation(V, a_, b_, c_, d_, normal_cos):
    """Whether both new triangles (a, d, c), (b, c, d) stay within ``normal_cos`` of the old pair's normal."""
    if normal_cos is None:
        return np.ones(len(a_), bool)
    old = _triangle_normals(V[a_], V[b_], V[c_]) + _triangle_normals(V[b_], V[a_], V[d_])
    n1 = _triangle_normals(V[a_], V[d_], V[c_])
    n2 = _triangle_normals(V[b_], V[c_], V[d_])
    if normal_cos == 0.0:
        return (np.einsum("ij,ij->i", n1, old) > 0) & (np.einsum("ij,ij->i", n2, old) > 0)
    old /= np.maximum(np.linalg.norm(old, axis=1, keepdims=True), 1e-300)
    m1 = face_normals(V, np.stack([a_, d_, c_], axis=1))
    m2 = face_normals(V, np.stack([b_, c_, d_], axis=1))
    return (np.einsum("ij,ij->i", m1, old) > normal_cos) & (np.einsum("ij,ij->i", m2, old) > normal_cos)


def _independent_swaps(cand, f1, f2, priority, new_key, face_count, scored):
    """The swaps of one round: an independent set of the candidates, one new edge made once.

    A face takes part in at most one swap per round; a few claiming passes make the set
    nearly maximal, so rounds stay few. Scored swaps take one pass: the losers of a face are
    re-scored next round, strictly greedy by priority; of two scored swaps that would create
    the same edge, the larger gain is made.
    """
    taken = np.zeros(face_count, bool)
    picked = []
    for _ in range(1 if scored else 4):
        cand = cand[~taken[f1[cand]] & ~taken[f2[cand]]]
        if len(cand) == 0:
            break
        claim = np.full(face_count, -1)
        pc = priority[cand]
        np.maximum.at(claim, f1[cand], pc)
        np.maximum.at(claim, f2[cand], pc)
        won = cand[(claim[f1[cand]] == pc) & (claim[f2[cand]] == pc)]
        taken[f1[won]] = taken[f2[won]] = True
        picked.append(won)
    chosen = np.concatenate(picked)
    if scored:
        chosen = chosen[np.argsort(-priority[chosen], kind="stable")]
    _, first = np.unique(new_key[chosen], return_index=True)
    return chosen[first]


def folds(X, F, fixed=None, before=None):
    """Does the patch fold: a degenerate triangle, or two neighbours at a dihedral over 120 degrees?

    With ``fixed`` ((n,) bool), triangles whose three vertices are all fixed are not judged,
    nor pairs of them: only where a step that moves the free vertices can have folded the patch.
    With ``before`` ((n, 3) float64, the same vertices before that step), neither is a pair of
    neighbours that were at over 120 degrees there already: the step did not fold them.
    """
    N = face_normals(X, F, normalize=False)
    area2 = np.linalg.norm(N, axis=1)
    scale = np.ptp(X, axis=0).max() or 1.0
    moved = None if fixed is None else ~np.all(np.asarray(fixed, bool)[F], axis=1)
    degenerate = area2 <= 1e-12 * scale * scale
    if np.any(degenerate if moved is None else degenerate & moved):
        return True
    E, f1, _, f2, _ = interior_edges(F, len(X))
    if moved is None:
        U = N / area2[:, None]
    else:
        U = N / np.maximum(area2, 1e-300)[:, None]
        judged = moved[f1] | moved[f2]
        f1, f2 = f1[judged], f2[judged]
    folded = np.einsum("ij,ij->i", U[f1], U[f2]) < -0.5
    if before is not None and folded.any():
        B = face_normals(before, F, normalize=False)
        B /= np.maximum(np.linalg.norm(B, axis=1), 1e-300)[:, None]
        folded &= np.einsum("ij,ij->i", B[f1], B[f2]) >= -0.5
    return bool(np.any(folded))
