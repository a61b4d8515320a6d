"""Developing a hole's border loop into the plane (fallback unfolding, not in any of the papers).

A loop the curve-unfolding annealing (Brunton et al. 2009, Sec. 3.1) cannot flatten -- one
wrapped around a tube or a knob projects onto itself from every side -- is laid out instead
with its 3D edge lengths and, at each vertex, the angle the surrounding surface leaves open.
Used by the curve-unfolding filter and by the LS-SVM filter's fallback initial patch.
"""
from __future__ import annotations

import numpy as np

from .segments import is_simple_polygon
from .triangulate import polygon_perimeter, polygon_signed_area

__all__ = ["boundary_gap_angles", "enclosed_curvature", "develop_loop", "developed_area", "close_lengths",
           "simple_development", "simple_developments"]


def boundary_gap_angles(vertices, faces, k):
    """Angle the hole leaves open at each loop vertex: 2 pi minus the mesh's corner angles there.

    Parameters
    ----------
    vertices : (n, 3) float64  local vertices, loop first
    faces : (f, 3) int  faces containing at least every face incident to the loop
    k : int  loop size

    Returns
    -------
    gap : (k,) float64 radians, in (0, 2 pi) for a manifold border vertex
    """
    from .quality import corner_angles

    faces = np.asarray(faces, np.int64)
    A = corner_angles(vertices, faces)
    total = np.bincount(faces.ravel(), weights=A.ravel(), minlength=len(vertices))[:k]
    return 2.0 * np.pi - total


def enclosed_curvature(gap_angles):
    """Gaussian curvature of the missing surface, from the angles the surface leaves open at the loop.

    Gauss-Bonnet for the disc the loop bounds: its total curvature is 2 pi minus the loop's
    geodesic turning, sum (pi - gap_i) (:func:`develop_loop` spreads this excess along the loop
    to close its polygon). On a mesh, the angle defects of the vertices the hole removed and of
    its loop's vertices. 0 on a developable surface, across a crease too; about
    2 pi (1 - cos t) for a spherical cap of angular radius t; negative on a saddle.

    Parameters
    ----------
    gap_angles : (m,) float64  from :func:`boundary_gap_angles`

    Returns
    -------
    float  radians
    """
    gap_angles = np.asarray(gap_angles, np.float64)
    return float(gap_angles.sum() - (len(gap_angles) - 2) * np.pi)


def develop_loop(P, gap_angles, relax=0.0):
    """Planar polygon with the loop's edge lengths and the surface's angles at its vertices.

    Not in the paper: the fallback unfolding used when annealing finds no simple projection
    (loops wrapped around a tube or a knob). The polygon turns by pi - gap_angle at each
    vertex, the opening the surrounding surface leaves, shifted equally so the turns sum to
    2 pi (the Gaussian curvature of the missing surface spread along the loop), walks the
    3D edge lengths, and is closed by the smallest relative change of the edge lengths
    (least squares, no edge reversed: :func:`close_lengths`). Like the surface's own
    development it keeps the loop's concavities; it is counter-clockwise when the loop is in
    patch orientation.

    ``relax`` = r in [0, 1] blends the turns towards the regular polygon's, turn_i =
    (1 - r) (pi - alpha_i) + r 2 pi / m. r = 1 gives the convex polygon with the loop's edge
    lengths, a planar loop of E_PE = 0 (the global minimiser of Sec. 3.1's energy); small r
    only damps the zig-zag of a scan or grid border, which is what makes the development of
    a long loop wrapped around a tube touch itself at a narrow waist (see
    :func:`simple_development`).

    Parameters
    ----------
    P : (m, 3) float64  loop in patch orientation
    gap_angles : (m,) float64  from :func:`boundary_gap_angles`
    relax : float  blend r towards uniform turning (0: the plain development)

    Returns
    -------
    Q : (m, 2) float64  (check simplicity with :func:`.segments.is_simple_polygon`)
    """
    P = np.asarray(P, np.float64)
    m = len(P)
    alpha = np.clip(np.asarray(gap_angles, np.float64), 0.05, 2.0 * np.pi - 0.05)
    alpha = alpha + ((m - 2) * np.pi - alpha.sum()) / m
    turn = (1.0 - relax) * (np.pi - alpha) + relax * (2.0 * np.pi / m)
    theta = np.concatenate([[0.0], np.cumsum(turn[1:])])  # direction of edge i = (p_i, p_{i+1})
    lengths = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)
    directions = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    edges = close_lengths(lengths, directions)[:, None] * directions
    return np.concatenate([[[0.0, 0.0]], np.cumsum(edges, axis=0)[:-1]])


def developed_area(P, gap_angles):
    """Area of the missing surface, estimated from the loop and the surface around it.

    The area the plain development (:func:`develop_loop`, relax 0) encloses at the loop's
    perimeter, or the loop's vector area |sum p_i x p_(i+1)| / 2 when that is larger: every
    surface spanning the loop has at least the vector area, which is the estimate when the
    development is degenerate (a loop of four vertices folded about a diagonal develops to
    almost nothing). The curve-unfolding filter compares its planar domains with it: a domain enclosing many
    times this area embeds as a patch bulging far out of the surface.

    Parameters
    ----------
    P : (m, 3) float64  loop
    gap_angles : (m,) float64  from :func:`boundary_gap_angles`

    Returns
    -------
    float
    """
    P = np.asarray(P, np.float64)
    Q = P - P[0]  # about a loop vertex: raw coordinates far from the origin cancel to noise
    vector_area = 0.5 * float(np.linalg.norm(np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0)))
    D = develop_loop(P, gap_angles)
    if not np.all(np.isfinite(D)):
        return vector_area
    # at the loop's perimeter, as the unfolded domains are measured (the closure may shorten edges)
    scale = polygon_perimeter(P) / polygon_perimeter(D)
    return max(vector_area, abs(polygon_signed_area(D)) * scale ** 2)


# develop_loop's closure keeps every edge at least this share of its length: only a margin
# against reversal (a positive length is what keeps the corners' sides), not a shape target.
MIN_CLOSURE_RATIO = 0.02


def close_lengths(lengths, directions, min_ratio=None):
    """Edge lengths closing a polygon of given edge directions, by the smallest relative change.

    Minimises sum_i (dl_i / l_i)^2 subject to sum_i (l_i + dl_i) d_i = 0 (one 2 x 2 solve, the
    change dl_i = -l_i^2 d_i . lambda) and l_i + dl_i >= min_ratio l_i: the plain least-squares
    closure puts most of the change on the longest edges and can make one negative when the
    turns leave a wide gap, which reverses that edge and turns the polygon's corners at its ends
    inside out (a sharp corner of the surface becomes reflex in the plane and its neighbour
    sharp, so the planar triangulation fans the wrong vertex; measured on the benchmark's cow.obj
    cut hole 1, 68 edges, closure gap 35 % of the perimeter: a 0.14-long edge reversed to -0.07).
    The bound is solved by an active set of this convex quadratic programme: clamp the edges
    whose change falls below the bound, solve again for the others, until the set is stable
    (its KKT point, the minimiser). Unchanged (bit-identical) when no edge reaches the bound;
    if the free edges cannot close the polygon the unconstrained closure is returned.

    Parameters
    ----------
    lengths : (m,) float64  edge lengths l_i > 0
    directions : (m, 2) float64  unit edge directions d_i
    min_ratio : float, optional  default MIN_CLOSURE_RATIO

    Returns
    -------
    (m,) float64  closed lengths
    """
    min_ratio = MIN_CLOSURE_RATIO if min_ratio is None else min_ratio
    weights = lengths ** 2
    low = (min_ratio - 1.0) * lengths  # smallest change allowed
    lam = np.linalg.solve((directions.T * weights) @ directions, lengths @ directions)
    change = -weights * (directions @ lam)
    clamped = change < low
    if not clamped.any():
        return lengths + change
    for _ in range(len(lengths)):
        free = ~clamped
        normal = (directions[free].T * weights[free]) @ directions[free]
        if free.sum() < 2 or np.linalg.cond(normal) > 1e12:
            break
        gap = lengths @ directions + low[clamped] @ directions[clamped]
        trial = -weights * (directions @ np.linalg.solve(normal, gap))
        below = trial < low
        if np.array_equal(below, clamped):
            return lengths + np.where(clamped, low, trial)
        clamped = below
    return lengths + change


RELAX_LADDER = (0.0, 0.05, 0.1, 0.2, 0.3, 0.5)  # blends tried by simple_development, least first


def simple_development(P, gap_angles, eps, ladder=RELAX_LADDER):
    """The least relaxed development of the loop that is a simple polygon (fallback, not in the paper).

    Tries :func:`develop_loop` with ``relax`` = 0, 0.05, 0.1, 0.2, 0.3, 0.5 and returns the
    first polygon with clearance d_MD > eps. The ladder stops at 0.5: more relaxed polygons
    are nearly convex and lose the concavities Sec. 3.1 wants preserved (embedded patches
    then fold over the surrounding mesh). Measured on the benchmark's torus hole of 211
    edges wrapped 255 degrees around the tube: the plain development touches itself at its
    waist, 0.05 is simple and its patch crosses nothing.

    Parameters
    ----------
    P : (m, 3) float64  loop in patch orientation
    gap_angles : (m,) float64
    eps : float  absolute clearance
    ladder : sequence of float

    Returns
    -------
    Q : (m, 2) float64 or None  None when no blend of the ladder is simple
    relax : float or None
    """
    return next(_simple_developments(P, gap_angles, eps, ladder), (None, None))


def simple_developments(P, gap_angles, eps, ladder=RELAX_LADDER):
    """Every development of the ladder that is a simple polygon, least relaxed first.

    The repair step (:func:`meshlab_holefill.algorithms.brunton2009.curve_unfolding.repair_crossings`) tries them as alternative
    planar domains when the first patch crosses the surrounding mesh.

    Parameters
    ----------
    P, gap_angles, eps, ladder : see :func:`simple_development`

    Returns
    -------
    list of ((m, 2) float64, float)  polygon and its blend ``relax``
    """
    return list(_simple_developments(P, gap_angles, eps, ladder))


def _simple_developments(P, gap_angles, eps, ladder):
    for r in ladder:
        Q = develop_loop(P, gap_angles, relax=r)
        if np.all(np.isfinite(Q)) and is_simple_polygon(Q, eps):
            yield Q, r
