"""Quality-improving edge swaps of an embedded curve-unfolding patch (beyond the paper).

The uniform Laplacian of Sec. 3.3 squeezes triangles at border vertices where the surface
leaves a wide opening; :func:`improve_by_swaps` swaps the patch edges whose swap raises the
lower quality of their two triangles and solves the energy again on the new connectivity, up
to ``MAX_SWAP_ROUNDS`` rounds, the best round kept.
"""
from __future__ import annotations

import numpy as np

from ...geometry.flips import relax_edges
from ...geometry.quality import triangle_quality
from .crossing_repair import CrossingCounts
from .embedding import embed_patch, relax_patch

__all__ = ["MAX_SWAP_ROUNDS", "improve_by_swaps"]

MAX_SWAP_ROUNDS = 4  # rounds of quality-improving edge swaps, each followed by a new energy solve


def _quality_improving(V, F, A, B, replaced):
    """Swap filter for :func:`relax_edges`: the new pair's lower quality beats the old pair's."""
    old = np.minimum(triangle_quality(V, F[replaced[:, 0]]), triangle_quality(V, F[replaced[:, 1]]))
    new = np.minimum(triangle_quality(V, A), triangle_quality(V, B))
    return new > old + 1e-9


def improve_by_swaps(ctx, vertices, faces, energy, rounds=MAX_SWAP_ROUNDS, crossings=None, tangential=False,
                     resolve=True, count_crossings=None):
    """Quality-improving edge swaps followed by a new energy solve (beyond the paper, option ``swaps``).

    Sec. 3.3 places the interior vertices by a uniform-Laplacian energy on the connectivity
    of the planar refinement; at border vertices where the surface leaves a wide opening
    (gap angles near 300 degrees) the uniform weights pull interior vertices onto the border
    and squeeze triangles that were well shaped in the plane (measured: planar quality 0.98,
    spatial 0.14). Each round swaps the interior patch edges that fail the circumsphere test
    and whose swap raises the lower quality of their two triangles (no fold, no duplicate
    edge, never an edge the mesh already has, :func:`relax_edges`), then solves the energy
    again on the new connectivity, so the result still minimises E_AREA / E_DF exactly (then
    relaxes tangentially if ``tangential``, as the first embedding did). The round with the
    best minimum quality (then mean) that crosses nothing new is kept. A patch of loop vertices
    only (a small hole) is swapped the same way, with nothing to solve: a range scan's 8-edge hole
    whose domain triangulation left a 0.017 sliver gets 0.786, its corners' bound.

    Parameters
    ----------
    ctx : HoleContext
    vertices : (s, 3) float64  new vertices
    faces : (t, 3) int64  patch faces in Patch numbering (loop index i < k, new vertex k + j)
    energy : {'area', 'area_interior', 'fairing'}  see :func:`.embedding.embed_patch`
    rounds : int
    crossings : int, optional  faces of the given patch crossing the mesh (computed when needed)
    tangential : bool  see :func:`.embedding.embed_patch`
    resolve : bool
        Solve the energy again after each round (default). False keeps the vertices where they
        are (a patch sampled from the energy's shape on a finer refinement, density
        'surrounding': a new solve on the coarser connectivity would change the shape) and only
        relaxes them tangentially on the new connectivity if ``tangential``.
    count_crossings : callable, optional
        ``(vertices, faces) -> int``, the patch's faces crossing the mesh (default: the length of
        :func:`.crossing_repair.crossing_faces`; the filter passes one that remembers the patches it counted).

    Returns
    -------
    vertices : (s, 3) float64
    faces : (t, 3) int64
    swaps : int  edge swaps in the kept result
    """
    s = len(vertices)

    def score(X, F):
        q = triangle_quality(X, F)
        return float(q.min()), float(q.mean())

    start = score(np.concatenate([ctx.points, vertices]), faces)
    X, F, total = np.concatenate([ctx.points, vertices]), faces, 0
    better = []  # rounds scoring above the input: (score, round, interior, faces, swaps so far)
    for r in range(rounds):
        F, swapped = relax_edges(X, F, fixed_edges=ctx.forbidden_edges, allowed=_quality_improving)
        if swapped == 0:
            break
        total += swapped
        if s and resolve:
            interior = embed_patch(ctx, s, F, energy=energy, tangential=tangential)
        elif s and tangential:
            interior = relax_patch(ctx, X[ctx.size:], F)
        else:  # kept in place; a patch of loop vertices only is changed by the swaps alone
            interior = X[ctx.size:]
        X = np.concatenate([ctx.points, interior])
        sc = score(X, F)
        if sc > start:
            better.append((sc, r, interior, F, total))
    return _best_round(ctx, better, vertices, faces, crossings, count_crossings)


def _best_round(ctx, better, vertices, faces, crossings, count_crossings):
    """The swaps' kept round: the earliest of the best score among the rounds crossing no more than the input.

    That is the round the running best (a round kept when it scores above the best so far and
    crosses no more than the input) ends on; taken best first, a patch's crossings are counted
    only until one passes (the input's only when that round crosses something), which spares the
    crossing tests of the rounds passed over (the most costly step after the solves).
    """
    if count_crossings is None:
        count_crossings = CrossingCounts(ctx)
    for sc, _, interior, F, total in sorted(better, key=lambda b: (b[0][0], b[0][1], -b[1]), reverse=True):
        n = count_crossings(interior, F)
        if n == 0 or n <= (crossings if crossings is not None else count_crossings(vertices, faces)):
            return interior, F, total
    return vertices, faces, 0
