"""Sliver repair of a curve-unfolding patch (beyond the paper; option ``slivers`` of the filter).

Where the slivers come from, measured stage by stage (``scripts/curve_unfolding_stages.py``, minimum
quality 2r/R of the patch): Chew's refinement (Sec. 3.3) keeps angles of 30 degrees or more except
next to the polygon's own sharp corners (planar minimum 0.06-0.5 on face000's natural holes), and
the embedding energy squeezes the triangles on border edges where the surrounding surface leaves a
wide opening (after the solve 0.000-0.03 on 7 of face000's holes); the tangential relaxation and
the swaps lift most of them, and what is left is a cap on a border edge whose inner vertex the
energy pulled almost onto that edge (face000 hole 16: 158 degrees at the inner vertex, quality
0.070). A border edge cannot be swapped or split, so :func:`repair_slivers` moves, splits and
collapses around the poor triangles only, and keeps the result only when the patch's minimum
quality rises without folding, crossing the mesh more or breaking the patch. A round whose moves
make faces cross the mesh is made again without the moves near those faces
(:func:`_withdrawn_near`), so the repair goes on around a fold of the patch instead of stopping there.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ...core.patch import Patch, validate_patch
from ...errors import HoleFillError
from ...geometry.caps import split_loop_caps
from ...geometry.flips import folds
from ...geometry.laplacian import vertices_near
from ...geometry.quality import triangle_quality
from ..hu2012.tangential_smoothing import tangential_smoothing
from .crossing_repair import crossing_faces

__all__ = ["SLIVER_FLOOR", "SLIVER_ROUNDS", "repair_slivers"]

SLIVER_FLOOR = 0.3  # triangles below this quality are repaired (the benchmark's "poor" triangles)
SLIVER_ROUNDS = 10  # rounds of moves, splits and collapses (as Hu et al.'s smoothing option)
SLIVER_RINGS = 2  # rings of vertices around the poor triangles that may move
WITHDRAWALS = 4  # times a round is made again without the moves near the faces it made cross
WITHDRAWN_EDGES = 1.0  # how near (in the crossing faces' longest edge) a withdrawn move started


def _quality_improving(V, F, A, B, replaced):
    old = np.minimum(triangle_quality(V, F[replaced[:, 0]]), triangle_quality(V, F[replaced[:, 1]]))
    new = np.minimum(triangle_quality(V, A), triangle_quality(V, B))
    return new > old + 1e-9


def repair_slivers(ctx, vertices, faces, count_crossings, floor=SLIVER_FLOOR, rounds=SLIVER_ROUNDS,
                   rings=SLIVER_RINGS):
    """Lift the patch's triangles below ``floor`` by local tangential moves, splits and collapses.

    The new vertices within ``rings`` rings of the triangles below ``floor`` (the loop stays)
    get rounds of :func:`..hu2012.tangential_smoothing.tangential_smoothing`: moves toward the
    apexes of equilateral triangles on the opposite edges within the tangent plane, each undone
    when it lowers the smallest quality around the vertex or flips a face; splits of the interior
    edge opposite an obtuse angle of a poor triangle; collapses of a new vertex with no room to
    move; quality-improving swaps (never an edge the mesh already has). The region is taken again
    each round, and no round crosses the mesh with more faces than the input (``count_crossings``):
    one that would is made again without the moves near its crossing faces (:func:`_round_clear_of_mesh`).
    The round of best minimum quality is kept when it beats the input's, the patch does not fold
    where it did not (a dihedral over 120 degrees or a degenerate face) and it is a valid disc
    closing the loop. Tangential moves leave the shape: the vertices stay on the surface to
    second order. A patch of loop vertices only (a loop-only least-bend patch) has nothing to
    move: its caps are split first (:func:`geometry.caps.split_loop_caps`), which counts as the
    first round. (Where the patch has inner vertices, the rounds' own splits of obtuse triangles
    and swaps reach such caps: on face000's 19-edge hole they lift a loop-only 0.28 to 0.40, the
    cap split first to 0.39 only.)

    Measured (``scripts/large_holes.py``, curve unfolding): on airplane1_s1's 296-edge hole, whose
    patch folds near the tail, every round used to cross the mesh there (7, 6, 3, 3 faces), so the
    repair kept nothing and a 0.019 triangle stayed; with the moves near the crossing faces withdrawn
    it reaches 0.347 in five rounds (patch→ground truth 4.58 -> 4.60 per mille). No hole of
    ``scripts/unseen_holes.py`` (seeds 1-6: creased, CAD, real-size and noisy groups) changes.

    Parameters
    ----------
    ctx : HoleContext
    vertices : (s, 3) float64  new vertices
    faces : (t, 3) int64  patch faces in Patch numbering (loop index i < k, new vertex k + j)
    count_crossings : callable  (vertices, faces) -> faces crossing the mesh
    floor : float
    rounds, rings : int

    Returns
    -------
    vertices, faces, rounds : the repaired patch and the number of the round kept (0: unchanged)
    """
    k = ctx.size
    X = np.concatenate([ctx.points, np.asarray(vertices, np.float64)])
    F = np.asarray(faces, np.int64)
    q = triangle_quality(X, F)
    if len(q) == 0 or q.min() >= floor:
        return vertices, faces, 0
    start_min, folded = float(q.min()), folds(X, F)
    start_crossings = count_crossings(X[k:], F)
    best = None
    V, G = (X, F) if len(vertices) else split_loop_caps(X, F, k, floor)
    split = len(V) > len(X)
    if split:  # kept as the first round where it neither folds the patch nor crosses the mesh more
        m = float(triangle_quality(V, G).min())
        if count_crossings(V[k:], G) > start_crossings or not (folded or not folds(V, G)):
            V, G, split = X, F, False
        elif m > start_min + 1e-9:
            best = (m, V.copy(), G.copy(), 1)
    if len(V) == k:
        return vertices, faces, 0
    for r in range(1 + split, rounds + 1 + split):
        qv = triangle_quality(V, G)
        if qv.min() >= floor:
            break
        region = vertices_near(G, len(V), qv < floor, rings)
        region[:k] = False
        made = _round_clear_of_mesh(ctx, V, G, region, start_crossings)
        if made is None or (np.array_equal(made[0], V) and np.array_equal(made[1], G)):
            break  # no round clear of the mesh, or one that changes nothing (the next would be the same)
        V, G = made
        m = float(triangle_quality(V, G).min())
        if m > (best[0] if best is not None else start_min) + 1e-9 and (folded or not folds(V, G)):
            best = (m, V.copy(), G.copy(), r)
    if best is None:
        return vertices, faces, 0
    _, V, G, r = best
    try:
        validate_patch(Patch(vertices=V[k:], faces=G), ctx.points, ctx.forbidden_edges)
    except HoleFillError:
        return vertices, faces, 0
    return V[k:], G, r


def _round_clear_of_mesh(ctx, V, G, region, allowed_crossings):
    """One round of the repair on the ``region`` vertices, crossing the mesh with at most ``allowed_crossings`` faces.

    A round whose patch crosses more is made again without the moves near its crossing faces
    (:func:`_withdrawn_near`), at most ``WITHDRAWALS`` times.

    Returns
    -------
    (V, G) of the round, or None when every try crosses or no vertex is left to move
    """
    k = ctx.size
    for _ in range(WITHDRAWALS + 1):
        if not region.any():
            return None
        Vn, Gn, _ = tangential_smoothing(V, G, region, 1, fixed=ctx.forbidden_edges, allowed=_quality_improving,
                                         criterion="angles", split=True)
        crossing = crossing_faces(ctx, Vn[k:], Gn)
        if len(crossing) <= allowed_crossings:
            return Vn, Gn
        region = region & ~_withdrawn_near(V, Vn, Gn[crossing])
    return None


def _withdrawn_near(V, V_new, crossing):
    """(n,) bool: the vertices of ``V`` (before the round) within ``WITHDRAWN_EDGES`` of the crossing faces'
    longest edge from one of their vertices (``crossing`` (c, 3) faces of ``V_new``, after the round).

    A round renumbers the vertices it splits and collapses, so the moves are found by place: a vertex
    that made a face cross was, before its move, within about an edge of where that face is now.
    """
    corners = V_new[crossing]  # (c, 3, 3)
    longest = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max()
    distance, _ = cKDTree(corners.reshape(-1, 3)).query(V)
    return distance <= WITHDRAWN_EDGES * longest
