"""The best minimum triangle quality a patch can reach at its hole's sharpest convex border corner."""
from __future__ import annotations

import numpy as np

__all__ = ["corner_quality_bound", "fan_triangle_quality"]


def corner_quality_bound(V, F, loop, max_fan=12):
    """Best minimum quality 2r/R any non-folding patch can have at the hole's worst convex corner.

    At a border vertex where the mesh wraps by more than half a turn (its face angles sum to
    more than pi), the two border edges, of lengths a <= b, meet at angle theta on the hole
    side. Every patch that does not fold covers that corner with a fan of triangles whose
    angles at the vertex add up to theta and whose spokes grow from a to b. The best such fan
    of k triangles has equal angles theta/k and spokes in geometric progression (ratio
    rho = (b/a)^(1/k)); each triangle then has sides 1, rho at angle theta/k. The corner's
    bound is the best of k = 1..max_fan, the hole's the worst corner's. For a = b it is the
    isosceles fan's max_k 8 sin(theta/2k) sin^2((pi - theta/k)/4), below 0.3 once theta < 9.37
    degrees; a short border edge beside a long one at a sharp corner lowers it further
    (bunny10k_textured.obj's 8-edge hole: theta = 29.8 deg, b/a = 4.15, bound 0.146). Jagged
    scan borders have such corners, so a filter's minimum quality is judged against
    min(0.3, this bound).

    Parameters
    ----------
    V : (n, 3) float
    F : (m, 3) int
    loop : (k,) int  ordered boundary vertices
    max_fan : int  largest fan tried per corner

    Returns
    -------
    float in [0, 1]; 1.0 when the loop has no convex corner, 0.0 when a border edge has no length.
    """
    loop = np.asarray(loop, np.int64)
    at_loop = np.isin(F, loop)
    rows = np.flatnonzero(at_loop.any(axis=1))
    angle_sum = np.zeros(len(V))
    for corner in range(3):
        f = rows[at_loop[rows, corner]]
        a, b, c = V[F[f, corner]], V[F[f, (corner + 1) % 3]], V[F[f, (corner + 2) % 3]]
        np.add.at(angle_sum, F[f, corner], _angle_between(b - a, c - a))
    P = V[loop]
    to_prev, to_next = np.roll(P, 1, axis=0) - P, np.roll(P, -1, axis=0) - P
    convex = angle_sum[loop] > np.pi
    lengths = np.linalg.norm(to_next, axis=1)
    if not np.all(lengths > 0.0):
        # A border edge of no length (coincident vertices, as marching cubes leaves them): the
        # patch's triangle on it is degenerate, whatever the patch.
        return 0.0
    if not convex.any():
        return 1.0
    theta = _angle_between(to_prev, to_next)[convex]
    la, lb = np.roll(lengths, 1)[convex], lengths[convex]
    ratio = np.maximum(la, lb) / np.minimum(la, lb)
    k = np.arange(1, max_fan + 1)[:, None]
    best = fan_triangle_quality(theta[None, :] / k, ratio[None, :] ** (1.0 / k)).max(axis=0)
    return float(min(1.0, best.min()))


def fan_triangle_quality(angle, rho):
    """2r/R of the triangle with sides 1 and ``rho`` enclosing ``angle`` (arrays broadcast).

    2r/R = (b + c - a)(c + a - b)(a + b - c) / (a b c) for sides a, b, c.

    Parameters
    ----------
    angle : float or array  radians
    rho : float or array  length of the second side (the first is 1)

    Returns
    -------
    array of the broadcast shape, in [0, 1]
    """
    c = np.sqrt(np.maximum(1.0 + rho ** 2 - 2.0 * rho * np.cos(angle), 0.0))
    a, b = np.ones_like(c), rho * np.ones_like(c)
    num = (b + c - a) * (c + a - b) * (a + b - c)
    return np.clip(num / np.maximum(a * b * c, 1e-300), 0.0, 1.0)


def _angle_between(u, w):
    cos = np.einsum("ij,ij->i", u, w) / np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1), 1e-300)
    return np.arccos(np.clip(cos, -1.0, 1.0))
