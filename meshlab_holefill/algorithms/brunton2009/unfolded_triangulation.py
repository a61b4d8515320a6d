"""Curve unfolding, Sec. 3.2-3.3 (Brunton et al. 2009): the unfolded polygon triangulated and embedded.

The simple planar polygon from the unfolding (Sec. 3.1, :mod:`.unfolding`) gets a constrained
Delaunay triangulation without Steiner points (Sec. 3.2, Shewchuk's Triangle), is scaled so
its perimeter is the loop's and refined after Chew to angles in [30, 120] degrees and edges
at most twice the surrounding ones (Sec. 3.3), and is embedded in space by the energies of
:mod:`.embedding`. The filter around these steps is :mod:`.curve_unfolding`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...geometry.quality import edge_lengths
from ...geometry.triangulate import polygon_perimeter, triangulate_polygon
from ...errors import HoleFillError
from ._sampling_kernels import best_candidates
from .embedding import embed_patch, relax_patch

__all__ = ["constrained_delaunay", "scale_to_loop", "area_bound", "refine_planar", "surrounding_edge_length",
           "triangulate_and_embed", "sample_patch", "resample_patch", "PlanarPatch", "DENSITIES"]

MIN_ANGLE_DEGREES = 30.0  # Sec. 3.3 after Chew: every angle in [30, 120] degrees
MAX_CHORD_ROUNDS = 8  # re-triangulations that break chords duplicating mesh edges
DENSITIES = ("surrounding", "twice", "equilateral")  # area bound of the refinement, see triangulate_and_embed
DENSITY_TOLERANCE = 0.03  # 'surrounding': mean patch edge within 3 % of the surrounding mean edge ends the correction
MAX_DENSITY_CORRECTIONS = 2  # 'surrounding': re-refinements with the corrected area bound


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


def area_bound(edge_length, density="surrounding"):
    """Triangle's area bound for the Sec. 3.3 refinement with surrounding edge length ``edge_length``.

    ``'twice'`` and ``'surrounding'``: e^2 / sqrt(3), the largest area at which every triangle
    whose angles are at least 30 degrees has its edges at most twice e (the flattest such
    triangle, 30-30-120, of longest edge c has area c^2 / (4 sqrt(3))): the paper's "edge lengths
    at most twice as long as the edges of the mesh surrounding the hole" exactly.
    ``'equilateral'``: sqrt(3)/4 e^2, the equilateral triangle of edge e (edges at most 1.73 e),
    the reading used before; Chew's refinement then leaves a mean edge of 0.82 e (see
    :func:`triangulate_and_embed`).
    """
    if density == "equilateral":
        return np.sqrt(3.0) / 4.0 * edge_length ** 2
    return edge_length ** 2 / np.sqrt(3.0)


def refine_planar(Q, edge_length, forbidden_chords=(), max_area=None):
    """Quality refinement of the planar triangulation after Chew (Sec. 3.3).

    Triangle's Delaunay refinement (Chew / Ruppert) with minimum angle 30 degrees, so every
    angle is in [30, 120] degrees, and maximum area ``max_area`` (default
    :func:`area_bound` ``(edge_length, 'twice')`` = edge_length^2 / sqrt(3): with angles >= 30
    degrees that area bounds the edges by 2 edge_length, the paper's "at most twice as long as
    the edges of the mesh surrounding the hole"). No Steiner point goes on the boundary
    (switch Y), so the boundary stays the loop; next to a boundary edge longer than the bound
    or an input angle below 30 degrees the angle bound cannot always be met.

    Parameters
    ----------
    Q : (m, 2) float64  polygon scaled to the loop's perimeter
    edge_length : float  mean edge length of the mesh around the hole
    forbidden_chords : (c, 2) int  see :func:`constrained_delaunay`
    max_area : float, optional  Triangle's area bound (overrides the one from ``edge_length``)

    Returns
    -------
    points : (m + s, 2) float64  polygon vertices first, then the interior Steiner points
    F : (t, 3) int64  oriented like Q
    """
    if max_area is None:
        max_area = area_bound(edge_length, "twice")
    return _triangulate_avoiding(Q, forbidden_chords, max_area=max_area, min_angle=MIN_ANGLE_DEGREES)


def surrounding_edge_length(ctx):
    """Mean edge length of the faces around the hole: each face touching a loop vertex, its three edges.

    The surrounding density that the patch's mean edge (each patch face's three edges) is
    compared with, as the benchmark's edge ratio (``evaluation.metrics.patch_metrics``) does.
    """
    near = ctx.faces[(ctx.faces < ctx.size).any(axis=1)]
    if len(near) == 0:
        return float(np.mean(ctx.edge_scale))
    return float(edge_lengths(ctx.vertices, near).mean())


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


def sample_patch(points, F, X, targets):
    """Positions on a placed patch of planar points given in its planar domain (barycentric in the plane).

    Parameters
    ----------
    points : (n, 2) float64  planar vertices of the placed patch
    F : (t, 3) int  its faces
    X : (n, 3) float64  their positions in space
    targets : (p, 2) float64  points inside the domain

    Returns
    -------
    (p, 3) float64  each target's position in the planar triangle that holds it, mapped by that
    triangle's barycentric coordinates (the nearest triangle, coordinates clamped, for a point
    on no triangle within rounding)
    """
    from scipy.spatial import cKDTree

    points, F, X = np.asarray(points, np.float64), np.asarray(F, np.int64), np.asarray(X, np.float64)
    targets = np.asarray(targets, np.float64).reshape(-1, 2)
    if len(targets) == 0:
        return np.zeros((0, 3))
    A, B, C = points[F[:, 0]], points[F[:, 1]], points[F[:, 2]]
    tree = cKDTree((A + B + C) / 3.0)
    best_w = np.full((len(targets), 3), np.nan)
    best_score = np.full(len(targets), -np.inf)
    best_face = np.zeros(len(targets), np.int64)
    for kk in (8, 32, len(F)):
        todo = np.flatnonzero(best_score < -1e-9)
        if len(todo) == 0:
            break
        kq = min(kk, len(F))
        _, cand = tree.query(targets[todo], k=kq)
        cand = np.asarray(cand, np.int64).reshape(len(todo), kq)
        # each point's candidate of largest smallest barycentric coordinate, kept where it beats the point's best
        best_candidates(targets, todo, cand, A, B, C, best_score, best_face, best_w)
        if kq == len(F):
            break
    w = np.clip(best_w, 0.0, None)
    w /= w.sum(axis=1, keepdims=True)
    return np.einsum("ij,ijk->ik", w, X[F[best_face]])


def _sub_loop_chords(forbidden_edges, keep, k):
    """Forbidden loop chords (loop indices < k) renumbered to positions in the sub-loop ``keep``."""
    position = np.full(k, -1)
    position[keep] = np.arange(len(keep))
    fe = position[np.asarray(forbidden_edges, np.int64).reshape(-1, 2)]
    return fe[(fe >= 0).all(axis=1)]


def triangulate_and_embed(ctx, Q, keep, ears, energy, refinement, tangential=False, density="surrounding",
                          record=None):
    """Sec. 3.2-3.3 for the sub-loop ``keep`` of the hole (the whole loop when nothing is clipped).

    Scale the planar polygon to the loop's perimeter, triangulate it (CDT, Sec. 3.2) or
    triangulate and refine it (Sec. 3.3), and embed the result with the chosen energy.

    The refinement's area bound (``density``): ``'twice'``: e^2 / sqrt(3) with e the
    :func:`surrounding_edge_length`, the paper's bound read exactly (edges at most 2 e,
    :func:`area_bound`); ``'equilateral'`` and ``'surrounding'``: sqrt(3)/4 (mean of
    ``ctx.edge_scale``)^2, the reading used before (edges at most 1.73 times the surrounding
    ones). With ``'surrounding'`` this patch gives the shape and the filter samples it at the
    surrounding density afterwards (:func:`resample_patch`); ``record`` (a list) then gets
    the planar triangulation appended, for :func:`resample_patch`.

    Parameters
    ----------
    ctx : HoleContext
    Q : (k, 2) float64  planar polygon of the whole loop
    keep : (r,) int64  loop indices of the sub-loop still to fill, in order
    ears : list of (3,) int  faces already clipped off (loop indices)
    energy : {'area', 'area_interior', 'fairing'}  see :func:`.embedding.embed_patch`
    refinement : bool
    tangential : bool  follow the solve by :func:`.tangential_relaxation.tangential_relaxation`
    density : {'surrounding', 'twice', 'equilateral'}
    record : list, optional  gets a :class:`PlanarPatch` appended

    Returns
    -------
    vertices : (s, 3) float64  new vertices
    faces : (t, 3) int64  patch faces in Patch numbering (loop index i < k, new vertex k + j)
    """
    k = ctx.size
    Qs, _ = scale_to_loop(Q[keep], ctx.points[keep])
    chords = _sub_loop_chords(ctx.forbidden_edges, keep, k)
    if not refinement:
        points, F = constrained_delaunay(Qs, chords)
    else:
        # Refined in units of the bound's edge (polygon / e, bound / e^2), as resample_patch does:
        # Triangle then sees the same numbers in any unit (an absolute bound of 1e-14 refined a
        # hole of a mesh in kilometres differently from the same hole in metres).
        e = surrounding_edge_length(ctx) if density == "twice" else float(np.mean(ctx.edge_scale))
        unit = e if e > 0 else 1.0
        points, F = refine_planar(Qs / unit, None, chords,
                                  max_area=area_bound(1.0, "twice" if density == "twice" else "equilateral"))
        points = points * unit
        points[:len(Qs)] = Qs  # the polygon's own vertices, unchanged by the round trip
    s = len(points) - len(keep)
    ear_faces = np.asarray(ears, np.int64).reshape(-1, 3)
    X = embed_patch(ctx, s, F, energy=energy, boundary=keep, extra_faces=ear_faces, tangential=tangential)
    to_patch = np.concatenate([keep, k + np.arange(s)])
    faces = np.concatenate([ear_faces, to_patch[F]])
    if record is not None:
        record.append(PlanarPatch(Qs, chords, np.asarray(keep, np.int64), ear_faces, points, F, faces))
    return X, faces


@dataclass
class PlanarPatch:
    """A patch's planar domain and triangulation, as :func:`triangulate_and_embed` built it."""

    polygon: np.ndarray  # (r, 2) the sub-loop's planar polygon, scaled to the loop
    chords: np.ndarray  # (c, 2) forbidden chords in sub-loop positions
    keep: np.ndarray  # (r,) loop indices of the sub-loop
    ear_faces: np.ndarray  # (e, 3) ears clipped before, loop indices
    points: np.ndarray  # (r + s, 2) planar vertices: the sub-loop, then the Steiner points
    F: np.ndarray  # (t, 3) planar faces (indices into points)
    faces: np.ndarray  # (e + t, 3) the patch faces in Patch numbering, as returned


def resample_patch(ctx, planar, vertices, tangential=True, finish=None):
    """The patch's shape sampled at the surrounding density (density ``'surrounding'``, beyond the paper's reading).

    Sec. 3.3 refines "to match the resolution of the surrounding mesh", but the embedding's
    shape depends on the refinement: the least-squares mesh of the uniform umbrella is not
    resolution-independent (measured on the benchmark's 157-edge sphere hole, E_AREA, mean
    patch-to-sphere distance per mille for Triangle area bounds 0.1 / 0.2 / 0.43 / 0.58 / 0.8 /
    1.2 e^2: 4.8 / 2.8 / 0.76 / 2.7 / 4.2 / 6.3, bulging out when finer and flattening when
    coarser; on the bunny's 164-edge hole 1.2 / 1.3 / 2.5 / 3.4 / 4.2 / 5.6). Refining to
    the surrounding density and embedding there loses accuracy (bunny hole 2.37 -> 4.15 per
    mille). So the shape is the patch of the reading used before (area bound of the
    equilateral triangle, mean edge 0.82 of the surrounding one, with the swaps and energy
    solves after it), and its planar domain is refined again with the bound
    e^2 / sqrt(3) (:func:`area_bound` 'twice'), each new vertex placed where its planar
    position maps on that patch (:func:`sample_patch`; the patch's vertices keep their planar
    positions through swaps and solves), then relaxed tangentially. The mean patch edge (each
    face's three edges) is compared with the :func:`surrounding_edge_length` e and, off by
    more than 3 %, the bound is divided by the squared ratio and the domain refined again (at
    most twice; the closest kept): this corrects both Chew's refinement's own undershoot
    and the embedding's length change (the domain is developed), measured, not assumed.

    Parameters
    ----------
    ctx : HoleContext
    planar : PlanarPatch  of the patch to sample
    vertices : (s, 3) float64  the patch's new vertices (possibly swapped and solved again since)
    tangential : bool  relax the sampled vertices tangentially
    finish : callable, optional
        ``finish(vertices, faces) -> (vertices, faces)`` applied to each sampled patch before its
        edge ratio is measured (the filter's swaps)

    Returns
    -------
    vertices : (s', 3) float64, faces : (t', 3) int64  in Patch numbering
    """
    k = ctx.size
    keep, ear_faces = planar.keep, planar.ear_faces
    e = surrounding_edge_length(ctx)
    X_fine = np.concatenate([ctx.points[keep], vertices])
    # Refined in units of e (polygon / e, bound / e^2): Triangle then sees the same numbers in any unit.
    unit = e if e > 0 else 1.0
    bound = area_bound(1.0, "twice")
    best = None
    for _ in range(MAX_DENSITY_CORRECTIONS + 1):
        points, F = refine_planar(planar.polygon / unit, None, planar.chords, max_area=bound)
        points = points * unit
        s = len(points) - len(keep)
        interior = sample_patch(planar.points, planar.F, X_fine, points[len(keep):])
        if tangential:
            interior = relax_patch(ctx, interior, F, boundary=keep, extra_faces=ear_faces)
        to_patch = np.concatenate([keep, k + np.arange(s)])
        patch_faces = np.concatenate([ear_faces, to_patch[F]])
        if finish is not None:
            interior, patch_faces = finish(interior, patch_faces)
        r = float(edge_lengths(np.concatenate([ctx.points, interior]), patch_faces).mean() / e) if e > 0 else 1.0
        if best is None or abs(r - 1.0) < abs(best[0] - 1.0):
            best = (r, interior, patch_faces)
        if abs(r - 1.0) <= DENSITY_TOLERANCE:
            break
        bound /= r * r
    return best[1], best[2]
