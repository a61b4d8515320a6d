"""Does a patch of the min-angle filter cross itself or the hole's surroundings?

The filter asks this after every step that can fold the patch (:mod:`.min_angle_bilateral`). The
surrounding faces are checked by :func:`.hole_guards.patch_crossings`; the patch against itself
only where :func:`embeds_in_projection` cannot show, in linear time, that projecting it onto
its mean plane is one-to-one (most patches).
"""
from __future__ import annotations

import numpy as np

from ...geometry.segments import polygon_edges_touch
from ._projection_kernels import projected_turns
from .hole_guards import patch_crossings

__all__ = ["crosses", "crosses_uncached", "embeds_in_projection"]


def embeds_in_projection(V, F, k, min_sine=1e-6):
    """True when projecting the patch onto its mean plane is one-to-one (so it cannot self-intersect).

    A sufficient test, linear in the patch size, that spares the quadratic-ish exact
    self-intersection query on the usual patch. The patch is a triangulated disk bounded
    by the loop V[:k]. Its projection along the unit area-weighted normal is injective
    when (i) every face keeps its orientation, clearly (sine of the angle between face
    normal and projection direction above ``min_sine``), (ii) the projected loop is a
    simple polygon, and (iii) around every vertex the projected angles add up to the full
    turn (2 pi inside, the polygon's own angle on the loop): a map of a disk that is a
    local homeomorphism and one-to-one on the boundary is one-to-one. Two faces whose
    projections meet only in shared vertices or edges cannot meet elsewhere in space.

    Parameters
    ----------
    V : (n, 3) float64  loop points first
    F : (m, 3) int
    k : int  loop size

    Returns
    -------
    bool  (False means "not shown", not "intersects")
    """
    V = np.asarray(V, np.float64)
    F = np.asarray(F, np.int64)
    e1, e2 = V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]
    C = np.stack([e1[:, 1] * e2[:, 2] - e1[:, 2] * e2[:, 1], e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2],
                  e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]], axis=1)
    n = C.sum(axis=0)
    length = np.linalg.norm(n)
    if not length > 0:
        return False
    n /= length
    if np.any(C @ n <= min_sine * np.linalg.norm(C, axis=1)):
        return False
    u = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    u /= np.linalg.norm(u)
    Q = V @ np.stack([u, np.cross(n, u)], axis=1)
    if polygon_edges_touch(Q[:k]):
        return False
    ok, sure = projected_turns(np.ascontiguousarray(Q), F, k, 1e-6)
    return bool(ok) if sure else _turns_numpy(Q, F, k)


def _turns_numpy(Q, F, k):
    """Condition (iii) of :func:`embeds_in_projection` in numpy (the reference of
    :func:`._projection_kernels.projected_turns`): every vertex of the projection Q used, and its
    corner angles adding up to 2 pi inside and to the loop's own angle on the loop."""
    # Projected corner angles summed per vertex (every face is counter-clockwise now).
    total = np.zeros(len(Q))
    for c in range(3):
        a = Q[F[:, (c + 1) % 3]] - Q[F[:, c]]
        b = Q[F[:, (c + 2) % 3]] - Q[F[:, c]]
        ang = np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], np.einsum("ij,ij->i", a, b))
        total += np.bincount(F[:, c], weights=ang, minlength=len(Q))
    prev, nxt = np.roll(Q[:k], 1, axis=0) - Q[:k], np.roll(Q[:k], -1, axis=0) - Q[:k]
    # Interior angle of the counter-clockwise loop at each vertex, swept from next to prev.
    loop_angle = np.mod(np.arctan2(nxt[:, 0] * prev[:, 1] - nxt[:, 1] * prev[:, 0],
                                   np.einsum("ij,ij->i", nxt, prev)), 2 * np.pi)
    expected = np.concatenate([loop_angle, np.full(len(Q) - k, 2 * np.pi)])
    used = np.zeros(len(Q), bool)
    used[F.ravel()] = True
    return bool(used.all() and np.all(np.abs(total - expected) < 1e-6))


_ANSWERS = []  # the last few (ctx, V bytes, F bytes, answer) of crosses


def crosses(ctx, V, F):
    """Does the patch (V loop-first, F) intersect itself or the surrounding faces?

    The self-intersection query is skipped when :func:`embeds_in_projection` shows the
    patch is one-to-one over its mean plane (most patches; the query is the costly part).
    The answers for the last few patches are kept: with the options the same patch is often
    checked twice (after smoothing and at the end).
    """
    V, F = np.asarray(V), np.asarray(F)
    key = (V.dtype.str, V.shape, V.tobytes(), F.dtype.str, F.shape, F.tobytes())
    for c, k, answer in _ANSWERS:
        if c is ctx and k == key:
            return answer
    answer = crosses_uncached(ctx, V, F)
    _ANSWERS.insert(0, (ctx, key, answer))
    del _ANSWERS[4:]
    return answer


def crosses_uncached(ctx, V, F):
    """:func:`crosses` without the kept answers: the surrounding faces first, then the patch against itself."""
    from ...geometry.intersections import intersecting_pairs

    if len(patch_crossings(ctx, V, F)):
        return True
    if embeds_in_projection(V, F, ctx.size):
        return False
    return bool(len(intersecting_pairs(V, F, np.arange(len(F)), np.arange(len(F)))))
