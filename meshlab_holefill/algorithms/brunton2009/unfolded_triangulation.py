"""Curve unfolding, Sec. 3.2-3.3 (Brunton et al. 2009): the unfolded polygon triangulated and embedded.

The simple planar polygon from the unfolding (Sec. 3.1, :mod:`.unfolding`) gets a constrained
Delaunay triangulation without Steiner points (Sec. 3.2, Shewchuk's Triangle), is scaled so
its perimeter is the loop's and refined after Chew to angles in [30, 120] degrees and edges
at most twice the surrounding ones (Sec. 3.3), and is embedded in space by the energies of
:mod:`.embedding`. The filter around these steps is :mod:`.curve_unfolding`.
"""
from __future__ import annotations

import numpy as np

from ...geometry.triangulate import polygon_perimeter, triangulate_polygon
from ...errors import HoleFillError
from .embedding import embed_patch

__all__ = ["constrained_delaunay", "scale_to_loop", "refine_planar", "triangulate_and_embed"]

MIN_ANGLE_DEGREES = 30.0  # Sec. 3.3 after Chew: every angle in [30, 120] degrees
MAX_CHORD_ROUNDS = 8  # re-triangulations that break chords duplicating mesh edges


def constrained_delaunay(Q, forbidden_chords=()):
    """Constrained Delaunay triangulation of the unfolded polygon (Sec. 3.2).

    Shewchuk's Triangle, every polygon edge kept, no Steiner point. A chord joining two
    boundary vertices that already share a mesh edge would make a non-manifold edge; only
    then is a Steiner point put at its midpoint (and the polygon re-triangulated).

    Parameters
    ----------
    Q : (m, 2) float64  simple polygon, either orientation
    forbidden_chords : (c, 2) int  polygon-vertex pairs that must not become edges

    Returns
    -------
    points : (m + s, 2) float64  polygon first; s = 0 unless a chord had to be broken
    F : (t, 3) int64  oriented like Q (hence like the loop)
    """
    return _triangulate_avoiding(Q, forbidden_chords)


def scale_to_loop(Q, P):
    """Scale the planar polygon so that its perimeter is the 3D loop's (Sec. 3.3).

    Planar and spatial edge lengths cannot all match (the planar polygon has other angles),
    so one global factor, the perimeter ratio, makes planar lengths 3D lengths on average;
    the polygon is also centred on its vertex centroid.

    Parameters
    ----------
    Q : (m, 2) float64  planar polygon
    P : (m, 3) float64  the loop in space

    Returns
    -------
    Qs : (m, 2) float64
    scale : float
    """
    Q = np.asarray(Q, np.float64)
    scale = polygon_perimeter(P) / polygon_perimeter(Q)
    return (Q - Q.mean(axis=0)) * scale, scale


def refine_planar(Q, edge_length, forbidden_chords=()):
    """Quality refinement of the planar triangulation after Chew (Sec. 3.3).

    Triangle's Delaunay refinement (Chew / Ruppert) with minimum angle 30 degrees, so every
    angle is in [30, 120] degrees, and maximum area sqrt(3)/4 edge_length^2 (the equilateral
    triangle of the surrounding edge length): with angles >= 30 degrees that area bounds the
    edges by 1.73 edge_length, within the paper's "at most twice as long as the edges of the
    mesh surrounding the hole". No Steiner point goes on the boundary (switch Y), so the
    boundary stays the loop; next to a boundary edge longer than the bound or an input angle
    below 30 degrees the angle bound cannot always be met.

    Parameters
    ----------
    Q : (m, 2) float64  polygon scaled to the loop's perimeter
    edge_length : float  mean edge length of the mesh around the hole
    forbidden_chords : (c, 2) int  see :func:`constrained_delaunay`

    Returns
    -------
    points : (m + s, 2) float64  polygon vertices first, then the interior Steiner points
    F : (t, 3) int64  oriented like Q
    """
    max_area = np.sqrt(3.0) / 4.0 * edge_length ** 2
    return _triangulate_avoiding(Q, forbidden_chords, max_area=max_area, min_angle=MIN_ANGLE_DEGREES)


def _triangulate_avoiding(Q, forbidden_chords, **options):
    """Triangulate Q, inserting chord midpoints until no forbidden chord is an edge."""
    Q = np.asarray(Q, np.float64)
    k = len(Q)
    forbidden = np.sort(np.asarray(forbidden_chords, np.int64).reshape(-1, 2), axis=1)
    extra = np.zeros((0, 2))
    for _ in range(MAX_CHORD_ROUNDS):
        points, F = triangulate_polygon(Q, extra_points=extra, **options)
        if len(forbidden) == 0:
            return points, F
        n = len(points)
        E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
        hit = forbidden[np.isin(forbidden[:, 0] * n + forbidden[:, 1], E[:, 0] * n + E[:, 1])]
        if len(hit) == 0:
            return points, F
        extra = np.concatenate([points[k:], 0.5 * (Q[hit[:, 0]] + Q[hit[:, 1]])])
    raise HoleFillError("triangulation keeps joining boundary vertices that already share a mesh edge")


def _sub_loop_chords(forbidden_edges, keep, k):
    """Forbidden loop chords (loop indices < k) renumbered to positions in the sub-loop ``keep``."""
    position = np.full(k, -1)
    position[keep] = np.arange(len(keep))
    fe = position[np.asarray(forbidden_edges, np.int64).reshape(-1, 2)]
    return fe[(fe >= 0).all(axis=1)]


def triangulate_and_embed(ctx, Q, keep, ears, energy, refinement, tangential=False):
    """Sec. 3.2-3.3 for the sub-loop ``keep`` of the hole (the whole loop when nothing is clipped).

    Scale the planar polygon to the loop's perimeter, triangulate it (CDT, Sec. 3.2) or
    triangulate and refine it (Sec. 3.3), and embed the result with the chosen energy.

    Parameters
    ----------
    ctx : HoleContext
    Q : (k, 2) float64  planar polygon of the whole loop
    keep : (r,) int64  loop indices of the sub-loop still to fill, in order
    ears : list of (3,) int  faces already clipped off (loop indices)
    energy : {'area', 'area_interior', 'fairing'}  see :func:`.embedding.embed_patch`
    refinement : bool
    tangential : bool  follow the solve by :func:`.embedding.tangential_relaxation`

    Returns
    -------
    vertices : (s, 3) float64  new vertices
    faces : (t, 3) int64  patch faces in Patch numbering (loop index i < k, new vertex k + j)
    """
    k = ctx.size
    Qs, _ = scale_to_loop(Q[keep], ctx.points[keep])
    chords = _sub_loop_chords(ctx.forbidden_edges, keep, k)
    if refinement:
        points, F = refine_planar(Qs, float(np.mean(ctx.edge_scale)), chords)
    else:
        points, F = constrained_delaunay(Qs, chords)
    s = len(points) - len(keep)
    ear_faces = np.asarray(ears, np.int64).reshape(-1, 3)
    X = embed_patch(ctx, s, F, energy=energy, boundary=keep, extra_faces=ear_faces, tangential=tangential)
    to_patch = np.concatenate([keep, k + np.arange(s)])
    return X, np.concatenate([ear_faces, to_patch[F]])
