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
quality rises without folding, crossing the mesh more or breaking the patch.
"""
from __future__ import annotations

import numpy as np

from ...core.patch import Patch, validate_patch
from ...errors import HoleFillError
from ...geometry.flips import folds
from ...geometry.laplacian import vertices_near
from ...geometry.quality import triangle_quality
from ..hu2012.tangential_smoothing import tangential_smoothing

__all__ = ["SLIVER_FLOOR", "SLIVER_ROUNDS", "repair_slivers"]

SLIVER_FLOOR = 0.3  # triangles below this quality are repaired (the benchmark's "poor" triangles)
SLIVER_ROUNDS = 10  # rounds of moves, splits and collapses (as Hu et al.'s smoothing option)
SLIVER_RINGS = 2  # rings of vertices around the poor triangles that may move


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
    each round. The round of best minimum quality is kept when it beats the input's, the patch
    does not fold where it did not (a dihedral over 120 degrees or a degenerate face), it is a
    valid disc closing the loop, and it crosses the mesh no more than before
    (``count_crossings``). Tangential moves leave the shape: the vertices stay on the surface
    to second order.

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
    if len(q) == 0 or q.min() >= floor or len(vertices) == 0:
        return vertices, faces, 0
    start_min, folded = float(q.min()), folds(X, F)
    best = None
    V, G = X, F
    for r in range(1, rounds + 1):
        qv = triangle_quality(V, G)
        if qv.min() >= floor:
            break
        region = vertices_near(G, len(V), qv < floor, rings)
        region[:k] = False
        if not region.any():
            break
        V, G, _ = tangential_smoothing(V, G, region, 1, fixed=ctx.forbidden_edges, allowed=_quality_improving,
                                       criterion="angles", split=True)
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
    if count_crossings(V[k:], G) > count_crossings(np.asarray(vertices, np.float64), F):
        return vertices, faces, 0
    return V[k:], G, r
