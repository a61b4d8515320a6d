"""HPDE step 6 (Xie and Zou 2013, Sec. 4.6): planar triangulation of the boundary and prediction points.

The boundary and prediction points are projected to the PCA plane of the boundary, or, for a
segmented boundary, to the two fitted planes unfolded into one about their common line
(Fig. 1); Triangle's constrained Delaunay triangulation keeps every boundary edge and its
topology is applied to the 3D points. The loop's development, then a disc, are the fallback
layouts beyond the paper for holes no plane can flatten; fold-overs are handled in :mod:`.folds`.
"""
from __future__ import annotations

import numpy as np
import triangle
from scipy.spatial import cKDTree

from ...geometry.development import boundary_gap_angles, simple_development
from ...geometry.pca import fit_plane, plane_frame
from ...geometry.topology import interior_edges, undirected_keys
from ...geometry.triangulate import polygon_signed_area, triangulate_polygon
from ...errors import HoleFillError
from . import _triangulation_kernels as _kernels
from . import folds
from . import sections

__all__ = ["PlaneMap", "points_in_polygon", "distance_to_polygon", "disc_coordinates", "development_coordinates",
           "inside_boundary", "lateral_offsets", "triangulate_planar", "edge_sliver_apexes", "triangulate_projection",
           "split_forbidden_edges", "fitting_plane", "plane_map_for", "loop_development", "triangulate_layout"]

EDGE_CLEARANCE = 0.35  # beyond the paper: a sliver apex nearer than this * L to a loop edge of length L ...
LONG_EDGE = 2.0  # ... longer than this * EdgeLen is left out (triangulate_planar)
CLEARANCE = 0.25  # prediction points nearer than this * EdgeLen to the projected boundary are left out
STANDING_PLANE_COS = 0.5  # a PCA plane whose normal is further than 60 deg from the surface's stands across it
# Triangle's switches of triangulate_polygon without refinement (polygon kept, quiet, no boundary Steiner points)
CDT_SWITCHES = "pQY"


class PlaneMap:
    """Map of 3D points to the triangulation plane (Sec. 4.6, Fig. 1).

    One plane: orthogonal projection to the plane (centroid c, unit normal n). Two planes
    alpha, beta (segmented boundary): a point goes to the plane whose half-plane (bounded by
    the common line of the two planes, on the side of its own base points) is nearer in angle
    around that line; beta is unfolded about the line into alpha's plane.

    Attributes
    ----------
    segmented : bool
    """

    def __init__(self, centroid, normal, second=None):
        self.segmented = second is not None
        if not self.segmented:
            n = normal / np.linalg.norm(normal)
            self.origin = np.asarray(centroid, np.float64)
            self.u, self.v = plane_frame(n)
            self.normal = n
            return
        (c1, n1), (c2, n2) = (centroid, normal), second
        h = np.cross(n1, n2)
        h /= np.linalg.norm(h)
        # A point on both planes, nearest the middle of the two centroids.
        A = np.stack([n1, n2, h])
        mid = 0.5 * (c1 + c2)
        self.origin = np.linalg.solve(A, np.array([n1 @ c1, n2 @ c2, h @ mid]))
        w1 = np.cross(n1, h)
        w1 *= 1.0 if (c1 - self.origin) @ w1 >= 0 else -1.0
        w2 = np.cross(n2, h)
        w2 *= 1.0 if (c2 - self.origin) @ w2 >= 0 else -1.0
        self.h, self.w1, self.w2 = h, w1, w2
        self.n1 = np.cross(h, w1)  # frame normals of the two half-planes in the unfolded layout
        self.n2 = np.cross(h, -w2)

    def side(self, X):
        """(q,) bool: True where a point belongs to the second plane (beta)."""
        if not self.segmented:
            return np.zeros(len(X), bool)
        D = X - self.origin
        return D @ self.w2 > D @ self.w1

    def to_2d(self, X):
        """2D coordinates of 3D points, (q, 2)."""
        D = np.asarray(X, np.float64) - self.origin
        if not self.segmented:
            return np.stack([D @ self.u, D @ self.v], axis=1)
        beta = self.side(X)
        y = np.where(beta, -(D @ self.w2), D @ self.w1)
        return np.stack([D @ self.h, y], axis=1)

    def reference_normals(self, X, F, orientation):
        """Expected normal direction of each face (orientation of the planar triangulation), (m, 3).

        ``orientation`` is +1 for a counter-clockwise boundary polygon, -1 otherwise. Faces with
        corners on both planes get the sum of the two plane normals.
        """
        if not self.segmented:
            return np.repeat((orientation * self.normal)[None, :], len(F), axis=0)
        beta = self.side(X)[F]
        share = beta.mean(axis=1)[:, None]
        N = (1.0 - share) * self.n1 + share * self.n2
        return orientation * N


def points_in_polygon(Q, X):
    """Even-odd rule: which 2D points lie inside the closed polygon Q, (q,) bool.

    Compiled (:func:`._triangulation_kernels.points_in_polygon`): the (q, k) numpy arrays of
    the crossings cost more than the test on the suite's large holes.
    """
    return _kernels.points_in_polygon(np.ascontiguousarray(Q, np.float64), np.ascontiguousarray(X, np.float64))


def distance_to_polygon(Q, X):
    """Distance of 2D points to the edges of the closed polygon Q, (q,).

    Compiled (:func:`._triangulation_kernels.distance_to_polygon`, the same numbers as the
    (q, k) numpy expression, 4 % of the filter's time on the benchmark suite's holes).
    """
    return _kernels.distance_to_polygon(np.ascontiguousarray(Q, np.float64), np.ascontiguousarray(X, np.float64))


def disc_coordinates(loop_arc, perimeter, base_count, pair_a, pair_b, fraction, offsets=None):
    """Fallback embedding of the boundary and prediction points in a disc (beyond the paper).

    Used only when neither the PCA plane nor the two unfolded planes give a simple boundary
    polygon without fold-overs (holes wrapping round a thin part, Sec. 6 "more intermediate
    planes are needed"). Boundary points go to the circle of circumference BudLen by arc
    length; a prediction point at fraction t along the chord of pair (a, b) goes to the same
    fraction of the straight chord between the images of BP_a and BP_b. The pairs of a chain
    are nested, so these chords never cross and the layout mirrors the section structure.
    ``offsets`` (the lateral offset of each loop vertex from the smoothed boundary curve,
    positive into the hole) move the loop vertices radially, so that the teeth of a zigzag
    loop keep their convex or concave turn in the disc.

    Parameters
    ----------
    loop_arc : (k,) float64  arc length of each loop vertex from loop vertex 0
    perimeter : float  BudLen
    base_count : int  n (BP_j sits at arc length j BudLen / n)
    pair_a, pair_b : (q,) int64  base points of the pair of each prediction point
    fraction : (q,) float64
    offsets : (k,) float64, optional

    Returns
    -------
    Q : (k, 2) float64  counter-clockwise circle polygon
    X : (q, 2) float64
    """
    radius = perimeter / (2 * np.pi)
    circle = lambda angle: radius * np.stack([np.cos(angle), np.sin(angle)], axis=-1)  # noqa: E731
    Q = circle(2 * np.pi * np.asarray(loop_arc) / perimeter)
    if offsets is not None:
        Q *= (1.0 - np.asarray(offsets) / radius)[:, None]
    A = circle(2 * np.pi * np.asarray(pair_a) / base_count)
    B = circle(2 * np.pi * np.asarray(pair_b) / base_count)
    t = np.asarray(fraction)[:, None]
    return Q, (1 - t) * A + t * B


def development_coordinates(Q, base, pair_a, pair_b, fraction):
    """Fallback layout of the prediction points on the loop's development (beyond the paper).

    Tried after the paper's plane layout, beside the disc (:func:`disc_coordinates`): the loop is
    laid out with its edge lengths and the surrounding surface's angles
    (:func:`geometry.development.simple_development`), which keeps a long strip a strip where
    the disc rounds it, and is the surface's own layout on a developable one. BP_j goes to the
    same place on its edge of the developed polygon, and a prediction point at fraction t along
    the chord of pair (a, b) to the same fraction of the straight chord between their images.
    Unlike the disc's, a chord may leave a non-convex polygon: such points are left out by
    :func:`triangulate_planar`'s inside test, as on the plane layouts.

    Parameters
    ----------
    Q : (k, 2) float64  the developed loop (simple, counter-clockwise)
    base : sections.BasePoints
    pair_a, pair_b : (q,) int64  base points of the pair of each prediction point
    fraction : (q,) float64

    Returns
    -------
    X : (q, 2) float64
    """
    k = len(Q)
    images = Q[base.edge] + base.t[:, None] * (Q[(base.edge + 1) % k] - Q[base.edge])  # (n, 2) BP_j
    t = np.asarray(fraction)[:, None]
    return (1 - t) * images[np.asarray(pair_a)] + t * images[np.asarray(pair_b)]


def inside_boundary(X, BP, inward, clearance):
    """3D inside test for the disc layout: X lies on the hole side of its nearest base point, (q,) bool.

    A point is kept when it is at least ``clearance`` from every base point and its offset
    from the nearest base point has a positive component along that point's into-hole
    direction (:func:`.sections.boundary_frames`).
    """
    if len(X) == 0:
        return np.zeros(0, bool)
    dist, j = cKDTree(BP).query(X)
    return (dist > clearance) & (np.einsum("ij,ij->i", X - BP[j], inward[j]) > 0)


def lateral_offsets(P, normals, window=2):
    """Offset of each loop vertex from the loop smoothed over +-window vertices, into the hole, (k,).

    The into-hole direction at vertex i is normal x tangent of the smoothed loop (patch
    orientation: the hole is on the left).
    """
    k = len(P)
    S = sum(np.roll(P, s, axis=0) for s in range(-window, window + 1)) / (2 * window + 1)
    t = np.roll(S, -1, axis=0) - np.roll(S, 1, axis=0)
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-300)
    inward = np.cross(normals, t)
    return np.einsum("ij,ij->i", P - S, inward) if k > 2 * window else np.zeros(k)


def triangulate_planar(loop_points, predicted, Q, X, clearance, edge_clearance=0.0, stats=None, long_edge=0.0):
    """Constrained triangulation of the boundary and prediction points laid out in 2D (Sec. 4.6).

    Triangle keeps every boundary edge and inserts the prediction points; the topology is
    then applied to the 3D points. Reading: prediction points whose 2D image falls outside
    the boundary polygon or within ``clearance`` of it are left out (Triangle would
    otherwise put slivers on the kept boundary edges; the paper's decimation merges such
    points with the boundary later), as are exact duplicates.

    Parameters
    ----------
    loop_points : (k, 3) float64
    predicted : (q, 3) float64
    Q : (k, 2) float64  2D boundary polygon (must be simple)
    X : (q, 2) float64  2D images of the prediction points
    clearance : float
    edge_clearance : float
        Beyond the paper: a prediction point that the triangulation makes the apex of a
        triangle on a boundary edge longer than ``long_edge`` (2D length L) is left out, and
        the points retriangulated, when it is nearer than this share of L to that edge (their
        number goes to ``stats["edge_cleared"]`` when a dict is given). On loop edges much
        longer than the prediction spacing (range-scan borders, 2-4 EdgeLen) such an apex
        makes a sliver (apex angle ~145 degrees, 2r/R ~ 0.15) that neither the decimation nor
        the swaps of Sec. 4.7 can remove. With 0.35 the apex is at least 0.35 L from the edge
        (2r/R ~ 0.6 for a centred apex). 0 = only ``clearance``.
    stats : dict, optional
    long_edge : float  (2D length)

    Returns
    -------
    V : (k + q', 3) float64  loop points then the kept prediction points
    F : (t, 3) int64  faces oriented like the loop (patch orientation)
    orientation : int  +1 when the 2D polygon is counter-clockwise
    kept : (q',) int64  indices of the kept prediction points (V[k:] = predicted[kept])
    """
    k = len(loop_points)
    orientation = 1 if polygon_signed_area(Q) > 0 else -1
    keep = np.ones(len(X), bool)
    if len(X):
        keep = points_in_polygon(Q, X) & (distance_to_polygon(Q, X) > clearance)
        if keep.sum() > 1:
            idx = np.flatnonzero(keep)
            for i, j in cKDTree(X[idx]).query_pairs(1e-9 * clearance):  # relative: any unit
                keep[idx[max(i, j)]] = False
    L = np.linalg.norm(np.roll(Q, -1, axis=0) - Q, axis=1)
    unused_rounds = cleared = 0
    _, T = triangulate_polygon(Q, extra_points=X[keep])
    checked = True  # T is triangulate_polygon's (validated, oriented); later rounds take Triangle's own faces
    while True:
        idx = np.flatnonzero(keep)
        used = np.zeros(k + len(idx), bool)
        used[T.ravel()] = True
        if not used.all():
            unused_rounds += 1
            if unused_rounds >= 3:
                raise HoleFillError("triangulation left prediction points unused")
            keep[idx[~used[k:]]] = False
        else:
            drop = edge_sliver_apexes(np.concatenate([Q, X[keep]]), T, k, L, long_edge, edge_clearance)
            if len(drop) == 0:
                break
            keep[idx[drop - k]] = False
            cleared += len(drop)
        T, checked = _retriangulation(Q, X[keep])
    if not checked:
        _, T = triangulate_polygon(Q, extra_points=X[keep])
    if stats is not None:
        stats["edge_cleared"] = int(cleared)
    V = np.concatenate([loop_points, predicted[keep]])
    return V, T, orientation, np.flatnonzero(keep)


def _retriangulation(Q, X):
    """(faces, checked): the triangulation of one of triangulate_planar's rounds with fewer points.

    Which points a round leaves out depends only on which triangles Triangle makes, so the
    rounds take Triangle's faces as they come (``checked`` False: unoriented), without
    triangulate_polygon's checks of the input (the first round made them: a subset of its
    points has no repeated point either) and of the output edges, which cost as much as
    Triangle on a large hole (104 rounds on a 274-edge hole); the last round's faces come from
    triangulate_polygon. Where Triangle fails, drops or moves a point or loses a loop edge,
    triangulate_polygon is called and raises its error as before (``checked`` True).
    """
    k = len(Q)
    pts = np.concatenate([Q, X]) if len(X) else Q
    segments = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    try:
        out = triangle.triangulate({"vertices": pts, "segments": segments}, CDT_SWITCHES)
    except Exception:  # noqa: BLE001  (triangulate_polygon below reports it)
        out = {}
    P, T = out.get("vertices"), out.get("triangles")
    if P is not None and T is not None and len(T) and len(P) == len(pts) and np.array_equal(P, pts):
        T = np.asarray(T, np.int64)
        if _has_loop_edges(T, k):
            return T, False
    return triangulate_polygon(Q, extra_points=X)[1], True


def _has_loop_edges(T, k):
    """True when every loop edge (i, i + 1 mod k) is an edge of a face of T."""
    seen = np.zeros(k, bool)
    for c in range(3):
        u, w = T[:, c], T[:, (c + 1) % 3]
        loop = (u < k) & (w < k)
        fwd = loop & (w == (u + 1) % k)
        bwd = loop & (u == (w + 1) % k)
        seen[u[fwd]] = True
        seen[w[bwd]] = True
    return bool(seen.all())


def edge_sliver_apexes(Y, T, k, L, long_edge, edge_clearance):
    """Prediction points that are the apex of a triangle on a long loop edge, too near to it.

    A triangle of T on loop edge (i, i + 1) with L[i] > ``long_edge`` whose apex is a
    prediction point (index >= k) nearer than ``edge_clearance`` * L[i] to the edge (2D
    points Y, loop first). Returns the sorted unique apex indices (>= k).
    """
    if edge_clearance <= 0 or len(T) == 0 or not np.any(L > long_edge):
        return np.zeros(0, np.int64)
    out = []
    for c in range(3):
        u, w, apex = T[:, c], T[:, (c + 1) % 3], T[:, (c + 2) % 3]
        fwd = (u < k) & (w < k) & (w == (u + 1) % k)
        bwd = (u < k) & (w < k) & (u == (w + 1) % k)
        e = np.where(fwd, u, w)
        hit = (fwd | bwd) & (apex >= k)
        hit[hit] &= L[e[hit]] > long_edge
        if not hit.any():
            continue
        a, b, p = Y[u[hit]], Y[w[hit]], Y[apex[hit]]
        d = b - a
        t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0, 1)
        near = np.linalg.norm(p - (a + t[:, None] * d), axis=1) < edge_clearance * L[e[hit]]
        out.append(apex[hit][near])
    return np.unique(np.concatenate(out)) if out else np.zeros(0, np.int64)


def triangulate_projection(loop_points, predicted, plane_map, clearance, edge_clearance=0.0, stats=None,
                           long_edge=0.0):
    """:func:`triangulate_planar` on the projection of the points by a :class:`PlaneMap`."""
    X = plane_map.to_2d(predicted) if len(predicted) else np.zeros((0, 2))
    return triangulate_planar(loop_points, predicted, plane_map.to_2d(loop_points), X, clearance, edge_clearance,
                              stats, long_edge)


def split_forbidden_edges(V, F, forbidden_edges):
    """Split every patch edge that duplicates a mesh edge between loop vertices at its midpoint.

    The constrained triangulation knows only the loop, so it may join two loop vertices that
    the surrounding mesh already joins (which would make a non-manifold edge); the midpoint
    becomes a new free vertex and the two triangles on the edge become four. Where two such
    edges share a triangle (a fan of chords over a jagged border), the second split finds its
    triangles in the faces as the first split left them.

    Returns
    -------
    V : (n + s, 3) float64
    F : (m + 2 s, 3) int64
    splits : int
    """
    fb = np.asarray(forbidden_edges, np.int64).reshape(-1, 2)
    if len(fb) == 0:
        return V, F, 0
    V = np.array(V, np.float64)
    F = np.array(F, np.int64)
    n = len(V)
    keys = undirected_keys(fb, n)
    E, f1, c1, f2, c2 = interior_edges(F, n)
    hit = np.flatnonzero(np.isin(undirected_keys(E, n), keys)).tolist()
    changed = set()
    new_faces = []
    for i in hit:
        a, b = E[i]
        faces = (f1[i], c1[i], f2[i], c2[i])
        if faces[0] in changed or faces[2] in changed:
            F = np.concatenate([F, np.asarray(new_faces, np.int64).reshape(-1, 3)])
            new_faces = []
            faces = _edge_faces(F, a, b)
        g1, h1, g2, h2 = faces
        c = F[g1, (h1 + 2) % 3]
        d = F[g2, (h2 + 2) % 3]
        w = len(V)
        V = np.vstack([V, 0.5 * (V[a] + V[b])])
        F[g1] = (a, w, c)
        F[g2] = (b, w, d)
        changed.update((g1, g2))
        new_faces += [(w, b, c), (w, a, d)]
    if new_faces:
        F = np.concatenate([F, np.asarray(new_faces, np.int64)])
    return V, F, len(hit)


def _edge_faces(F, a, b):
    """(f1, c1, f2, c2) of the edge a -> b as :func:`..geometry.topology.interior_edges` gives them.

    The face holding the half-edge a -> b with the corner of ``a`` in it, and the face
    holding b -> a with the corner of ``b``.
    """
    after = np.roll(F, -1, axis=1)  # (m, 3): the corner that follows each corner
    f1, c1 = np.argwhere((F == a) & (after == b))[0]
    f2, c2 = np.argwhere((F == b) & (after == a))[0]
    return int(f1), int(c1), int(f2), int(c2)


def fitting_plane(points, normals):
    """The PCA fitting plane of Sec. 4.6 whose normal faces the surface: (centroid, unit normal).

    Reading: the paper takes the plane of the two largest principal directions. A narrow hole
    bent along its length (a strip around a sphere) has its smallest spread across the strip,
    so that plane stands across the surface and the projected loop folds onto itself. Of the
    three principal axes the one nearest to the mean surface normal is used as the normal
    when the paper's normal is more than 60 degrees (``STANDING_PLANE_COS``) from it; for a
    hole that is not bent more than its width the paper's plane is kept.

    Parameters
    ----------
    points : (n, 3) float64  base points
    normals : (n, 3) float64  surface normals at the base points

    Returns
    -------
    centroid : (3,) float64
    normal : (3,) float64  unit, on the side of the surface normals
    """
    c, n, _, axes = fit_plane(points)
    mean = normals.sum(axis=0)
    if np.linalg.norm(mean) > 0:
        mean = mean / np.linalg.norm(mean)
        dots = axes @ mean
        if abs(n @ mean) < STANDING_PLANE_COS and np.abs(dots).max() > abs(n @ mean):
            n = axes[int(np.argmax(np.abs(dots)))]
    if n @ normals.sum(axis=0) < 0:
        n = -n
    return c, n


def plane_map_for(base, normals, seg, segmented):
    """The triangulation plane(s) of Sec. 4.6: the two fitted planes unfolded, or the PCA plane."""
    if segmented:
        (c1, n1), (c2, n2) = seg["planes"]
        if np.linalg.norm(np.cross(n1, n2)) > 1e-6:
            return PlaneMap(c1, n1, (c2, n2))
    return PlaneMap(*fitting_plane(base.points, normals))


def loop_development(ctx, edge_len):
    """The loop's least relaxed simple development (:func:`geometry.development.simple_development`), or None.

    The polygon of the 'development' layout (:func:`development_coordinates`), clearance 1e-5 EdgeLen.
    """
    gaps = boundary_gap_angles(ctx.vertices, ctx.faces, ctx.size)
    return simple_development(ctx.points, gaps, 1e-5 * edge_len)[0]


def triangulate_layout(ctx, base, normals, seg, layout, prediction_result, edge_len, excluded, stats=None,
                       development=None):
    """Step 6 for one layout: 'plane', 'two planes' (Sec. 4.6) or the 'development' and 'disc' fallbacks.

    Parameters
    ----------
    excluded : (q,) bool  prediction points left out (outliers of earlier rounds)
    stats : dict, optional  receives ``edge_cleared`` (points left out by EDGE_CLEARANCE alone)
    development : (k, 2) float64, optional  the 'development' layout's polygon when the caller has it
        (:func:`loop_development`, computed here otherwise)

    Returns
    -------
    V : (k + q', 3) float64,  F : (t, 3) int64,  ids : (q',) int64 prediction point of each V[k:]

    Raises
    ------
    HoleFillError  non-simple layout, or a fold-over after mapping the triangulation back.
    """
    points, owner, fraction, _ = prediction_result
    P = ctx.points
    clearance = CLEARANCE * edge_len
    use = np.flatnonzero(~excluded)
    if layout == "disc":
        # The disc keeps every chord inside; drop points whose chord left the hole in 3D
        # (the 2D inside test of the plane layouts).
        _, inward = sections.boundary_frames(base.points, normals)
        use = use[inside_boundary(points[use], base.points, inward, clearance)]
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])
        offsets = lateral_offsets(P, ctx.loop_normals)
        Q, X = disc_coordinates(arc, base.perimeter, len(base), owner[use, 0], owner[use, 1],
                                           fraction[use], offsets)
        V, F, _, kept = triangulate_planar(P, points[use], Q, X, clearance, EDGE_CLEARANCE, stats,
                                                      LONG_EDGE * edge_len)
    elif layout == "development":
        Q = loop_development(ctx, edge_len) if development is None else development
        if Q is None:
            raise HoleFillError("no development of the loop is a simple polygon")
        X = development_coordinates(Q, base, owner[use, 0], owner[use, 1], fraction[use])
        V, F, _, kept = triangulate_planar(P, points[use], Q, X, clearance, EDGE_CLEARANCE, stats,
                                           LONG_EDGE * edge_len)
    else:
        pmap = plane_map_for(base, normals, seg, layout == "two planes")
        V, F, orientation, kept = triangulate_projection(P, points[use], pmap, clearance, EDGE_CLEARANCE,
                                                                    stats, LONG_EDGE * edge_len)
        if folds.fold_overs(V, F, pmap.reference_normals(V, F, orientation)).any():
            raise HoleFillError(f"fold-over after mapping the {layout} triangulation back to 3D")
    return V, F, use[kept]
