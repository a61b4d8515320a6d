"""Metrics of a filled hole against its ground truth and its surroundings.

Distances (seeded area samples of one surface at their exact distance from the other, both
ways; exact closest points), normal deviation, triangle quality 2r/R (Field; Hu et al. Sec. IV), density match (edge ratio),
dihedral continuity across the hole border, creases of the removed surface kept or lost
(:func:`crease_metrics`), intersections and changed originals.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..core.holes import boundary_loops, nonmanifold_edges
from ..geometry.intersections import faces_intersecting
from ..geometry.quality import edge_lengths, face_areas, face_normals, triangle_quality
from ..geometry.topology import face_adjacency
from ..meshlab import mesh_files

__all__ = ["CREASE_ANGLE", "QUALITY_BINS", "assign_patches", "border_dihedrals", "closest_faces",
           "closest_point_on_triangles", "compact_mesh", "corner_quality_bound", "crease_metrics", "edge_dihedrals", "fan_triangle_quality", "hausdorff_one_way", "hole_metrics",
           "mesh_checks", "patch_metrics", "point_to_surface_distances", "sample_surface"]

QUALITY_BINS = np.linspace(0.0, 1.0, 21)
CREASE_ANGLE = 30.0  # degrees: an edge of the removed surface whose dihedral angle exceeds this is a crease


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
    float in (0, 1]; 1.0 when the loop has no convex corner.
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
    if not convex.any():
        return 1.0
    theta = _angle_between(to_prev, to_next)[convex]
    la, lb = np.linalg.norm(to_prev, axis=1)[convex], np.linalg.norm(to_next, axis=1)[convex]
    ratio = np.maximum(la, lb) / np.maximum(np.minimum(la, lb), 1e-300)
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


def sample_surface(V, F, count, seed=0):
    """Points spread uniformly by area over a triangle surface, from a seeded generator.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int
    count : int
    seed : int

    Returns
    -------
    (count, 3) float64  (empty when the surface has no area)
    """
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    T = V[F]
    area = face_areas(V, F)
    total = area.sum()
    if not total > 0:
        return np.empty((0, 3))
    rng = np.random.default_rng(seed)
    face = rng.choice(len(T), size=count, p=area / total)
    # Uniform in a triangle: sqrt of the first variate spreads samples evenly by area.
    s, t = np.sqrt(rng.random(count)), rng.random(count)
    return (T[face, 0] * (1 - s)[:, None] + T[face, 1] * (s * (1 - t))[:, None]
            + T[face, 2] * (s * t)[:, None])


def point_to_surface_distances(X, V, F):
    """Unsigned distance from each point to the nearest point of a triangle surface.

    Exact: MeshLab's per-vertex distance filter (a uniform grid over the faces), with the
    points as a vertex-only mesh.

    Parameters
    ----------
    X : (q, 3) float64, V : (n, 3) float64, F : (m, 3) int

    Returns
    -------
    (q,) float64
    """
    return mesh_files.point_to_surface_distances(X, V, F)


def hausdorff_one_way(src_V, src_F, dst_V, dst_F, samples=20000, seed=0):
    """Distances from surface src to surface dst, sampled uniformly by area over src.

    Only face samples are taken: the mean is then the surface mean of the distance, the
    same for a surface however it is triangulated. (With vertex and edge samples added, as
    in MeshLab's Hausdorff filter by default, a coarse patch whose edges are mostly border
    edges, at distance 0 from the ground truth that shares the border, scores better than
    the same surface split into more triangles.)

    The samples come from a seeded generator (:func:`sample_surface`) and the distances are
    exact (:func:`point_to_surface_distances`), so a figure depends only on the two
    surfaces. MeshLab's own Hausdorff sampler draws from a process-wide generator that
    cannot be seeded, which made a hole's figure shift by about 1% with the number of
    samplings run before it.

    Returns
    -------
    dict with ``mean``, ``rms``, ``max`` (absolute units; NaN when src has no area).
    """
    d = point_to_surface_distances(sample_surface(src_V, src_F, samples, seed), dst_V, dst_F)
    if len(d) == 0:
        return {"mean": float("nan"), "rms": float("nan"), "max": float("nan")}
    return {"mean": float(d.mean()), "rms": float(np.sqrt(np.mean(d ** 2))), "max": float(d.max())}


def compact_mesh(V, F):
    """Keep only the vertices F uses, F reindexed.

    Parameters
    ----------
    V : (n, 3) float, F : (m, 3) int

    Returns
    -------
    V' : (u, 3), the u vertices F uses, in index order
    F' : (m, 3) int64 indices into V'
    """
    used = np.unique(np.asarray(F).ravel())
    remap = np.full(len(V), -1, np.int64)
    remap[used] = np.arange(len(used))
    return np.asarray(V)[used], remap[np.asarray(F)]


def assign_patches(F_new, loop_vertex_sets):
    """Split new faces into per-hole patches.

    Parameters
    ----------
    F_new : (q, 3) int  new faces (global indices)
    loop_vertex_sets : list of (k_i,) int  boundary vertices of each hole

    Returns
    -------
    list of (q_i,) int64 arrays: positions in F_new of the faces of each hole's patch
    """
    q = len(F_new)
    if q == 0:
        return [np.zeros(0, np.int64) for _ in loop_vertex_sets]
    n_comp, label = connected_components(face_adjacency(F_new), directed=False)
    owner = np.full(n_comp, -1)
    for h, verts in enumerate(loop_vertex_sets):
        touching = np.isin(F_new, verts).any(axis=1)
        owner[np.unique(label[touching])] = h
    return [np.flatnonzero(owner[label] == h) for h in range(len(loop_vertex_sets))]


def mesh_checks(V0, F0, V1, F1, return_hits=False):
    """Whole-mesh checks after a fill: originals unchanged, manifoldness, boundary left, intersections.

    Returns
    -------
    dict with ``originals_changed`` (moved original vertices + changed original faces),
    ``nonmanifold_edges``, ``boundary_edges_left``, ``intersecting_new_faces``,
    ``new_faces``, ``new_vertices``; with ``return_hits`` also the (h,) int64 indices into F1
    of the intersecting new faces as a second value.
    """
    n0, m0 = len(V0), len(F0)
    moved = int(np.count_nonzero(np.any(V1[:n0] != V0, axis=1))) if len(V1) >= n0 else n0
    changed = int(np.count_nonzero(np.any(F1[:m0] != F0, axis=1))) if len(F1) >= m0 else m0
    new = np.arange(m0, len(F1))
    hits = faces_intersecting(V1, F1, new, np.arange(len(F1))) if len(new) else np.zeros(0, np.int64)
    out = {"originals_changed": moved + changed, "nonmanifold_edges": int(len(nonmanifold_edges(F1))),
           "boundary_edges_left": int(sum(lp.edge_count for lp in boundary_loops(F1))),
           "intersecting_new_faces": int(len(hits)), "new_faces": int(len(F1) - m0),
           "new_vertices": int(len(V1) - n0)}
    return (out, np.asarray(hits, np.int64)) if return_hits else out


def patch_metrics(V0, F0, V1, patch_faces, loop_vertices, ground_truth=None, diag=None):
    """Metrics of one hole's patch.

    Parameters
    ----------
    V0, F0 : mesh with holes;  V1 : vertices of the filled mesh
    patch_faces : (q, 3) int  the patch faces (global indices into V1)
    loop_vertices : (k,) int  the hole's boundary vertices
    ground_truth : (V, F) of the removed surface, optional
    diag : float  length for the per-mille figures (bounding-box diagonal)

    Returns
    -------
    dict: ``faces``, ``quality_mean/min/share07``, ``quality_values``, ``edge_ratio`` (mean new
    edge length / mean length of the mesh edges around the hole), and with ground truth
    ``dist_patch_to_gt_{mean,rms,max}`` and ``dist_gt_to_patch_{...}``, each also ``_permille``.
    """
    out = {"faces": int(len(patch_faces))}
    if len(patch_faces) == 0:
        return out
    q = triangle_quality(V1, patch_faces)
    out.update(quality_mean=float(q.mean()), quality_min=float(q.min()),
               quality_share07=float((q >= 0.7).mean()), quality_values=q)
    near = np.flatnonzero(np.isin(F0, loop_vertices).any(axis=1))
    old_len = edge_lengths(V0, F0[near]).mean() if len(near) else np.nan
    out["edge_ratio"] = float(edge_lengths(V1, patch_faces).mean() / old_len)
    if ground_truth is not None:
        pV, pF = compact_mesh(V1, patch_faces)
        gV, gF = ground_truth
        for name, (a, b) in {"patch_to_gt": ((pV, pF), (gV, gF)), "gt_to_patch": ((gV, gF), (pV, pF))}.items():
            for key, value in hausdorff_one_way(a[0], a[1], b[0], b[1]).items():
                out[f"dist_{name}_{key}"] = value
                if diag:
                    out[f"dist_{name}_{key}_permille"] = 1000.0 * value / diag
    return out


def closest_point_on_triangles(X, A, B, C):
    """Closest point to X[i] on triangle (A[i], B[i], C[i]) (Ericson, Real-Time Collision Detection 5.1.5).

    Parameters
    ----------
    X, A, B, C : (N, 3) float64

    Returns
    -------
    (N, 3) float64
    """
    ab, ac, ap = B - A, C - A, X - A
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    bp = X - B
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    cp = X - C
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    denom = va + vb + vc
    safe = np.where(np.abs(denom) > 1e-300, denom, 1.0)
    v, w = vb / safe, vc / safe
    out = A + v[:, None] * ab + w[:, None] * ac  # inside the face
    # Edge and vertex regions, later assignments taking precedence in Voronoi order.
    t_ab = np.clip(d1 / np.where(d1 - d3 != 0, d1 - d3, 1.0), 0, 1)
    sel = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    out[sel] = (A + t_ab[:, None] * ab)[sel]
    t_ac = np.clip(d2 / np.where(d2 - d6 != 0, d2 - d6, 1.0), 0, 1)
    sel = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    out[sel] = (A + t_ac[:, None] * ac)[sel]
    e43, e56 = d4 - d3, d5 - d6
    t_bc = np.clip(e43 / np.where(e43 + e56 != 0, e43 + e56, 1.0), 0, 1)
    sel = (va <= 0) & (e43 >= 0) & (e56 >= 0)
    out[sel] = (B + t_bc[:, None] * (C - B))[sel]
    out[(d1 <= 0) & (d2 <= 0)] = A[(d1 <= 0) & (d2 <= 0)]
    out[(d3 >= 0) & (d4 <= d3)] = B[(d3 >= 0) & (d4 <= d3)]
    out[(d6 >= 0) & (d5 <= d6)] = C[(d6 >= 0) & (d5 <= d6)]
    return out


def _dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def closest_faces(X, V, F, candidates=32):
    """Nearest point of a triangle surface for each query point.

    Exact against all faces for small problems; otherwise exact against the ``candidates``
    faces with the nearest centroids (enough on the regular, fine surfaces compared here).

    Parameters
    ----------
    X : (q, 3) float64
    V : (n, 3) float64, F : (t, 3) int

    Returns
    -------
    distance : (q,) float64, face : (q,) int64, point : (q, 3) float64
    """
    X = np.asarray(X, np.float64)
    T = np.asarray(V, np.float64)[np.asarray(F, np.int64)]
    if len(X) * len(F) <= 2_000_000 or len(F) <= candidates:
        cand = np.broadcast_to(np.arange(len(F)), (len(X), len(F)))
    else:
        _, cand = cKDTree(T.mean(axis=1)).query(X, k=candidates)
    q, k = cand.shape
    rows = np.repeat(np.arange(q), k)
    flat = cand.ravel()
    P = closest_point_on_triangles(X[rows], T[flat, 0], T[flat, 1], T[flat, 2])
    d = np.linalg.norm(P - X[rows], axis=1).reshape(q, k)
    best = np.argmin(d, axis=1)
    face = cand[np.arange(q), best]
    return d[np.arange(q), best], face.astype(np.int64), P.reshape(q, k, 3)[np.arange(q), best]


def border_dihedrals(V, F_mesh, halfedges, mesh_faces, F_patch):
    """Angle between the normals of the two faces meeting at each hole-border edge, degrees.

    0 means the patch continues the surface without a crease.

    Parameters
    ----------
    V : (n, 3) float64  vertices of the filled mesh (originals first)
    F_mesh : (m, 3) int  faces of the mesh with holes
    halfedges : (b, 2) int  the hole's boundary half-edges, in the direction of their mesh face
    mesh_faces : (b,) int  the mesh face owning each half-edge
    F_patch : (q, 3) int  patch faces (indices into V)

    Returns
    -------
    (b,) float64, NaN where no patch face holds the edge
    """
    F_patch = np.asarray(F_patch, np.int64)
    out = np.full(len(halfedges), np.nan)
    if len(F_patch) == 0 or len(halfedges) == 0:
        return out
    n = int(max(len(V), F_patch.max() + 1))
    a = F_patch.ravel()
    b = np.roll(F_patch, -1, axis=1).ravel()
    keys = a * n + b
    order = np.argsort(keys)
    # The patch traverses each border edge opposite to the mesh face.
    want = halfedges[:, 1].astype(np.int64) * n + halfedges[:, 0]
    pos = np.clip(np.searchsorted(keys[order], want), 0, len(keys) - 1)
    found = keys[order][pos] == want
    patch_face = order[pos] // 3
    n_mesh = face_normals(V, np.asarray(F_mesh)[mesh_faces])
    n_patch = face_normals(V, F_patch[patch_face])
    cos = np.clip(_dot(n_mesh, n_patch), -1.0, 1.0)
    out[found] = np.degrees(np.arccos(cos[found]))
    return out


def edge_dihedrals(V, F):
    """The interior edges of a triangle surface with their signed dihedral angles.

    The angle of an edge is the angle between the normals of its two faces (0 = flat), positive
    where the surface is convex there (the second face bends away from the first face's normal
    side) and negative where it is concave. Edges with one face, or more than two, are left out.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int  consistently oriented

    Returns
    -------
    edges : (e, 2) int64  vertex pairs
    angles : (e,) float64  signed dihedral angles, degrees in [-180, 180]
    """
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64).reshape(-1, 3)
    if not len(F):
        return np.zeros((0, 2), np.int64), np.zeros(0)
    n = int(max(len(V), F.max() + 1))
    a, b = F.ravel(), np.roll(F, -1, axis=1).ravel()
    face = np.repeat(np.arange(len(F)), 3)
    key, twin = a * n + b, b * n + a
    order = np.argsort(key)
    pos = np.clip(np.searchsorted(key[order], twin), 0, len(key) - 1)
    found = (key[order][pos] == twin) & (a < b)
    unique, counts = np.unique(np.minimum(a, b) * n + np.maximum(a, b), return_counts=True)
    manifold = np.isin(np.minimum(a, b) * n + np.maximum(a, b), unique[counts == 2])
    i = np.flatnonzero(found & manifold)
    f, g = face[i], face[order[pos[i]]]
    normals = face_normals(V, F)
    cos = np.clip(_dot(normals[f], normals[g]), -1.0, 1.0)
    angle = np.degrees(np.arccos(cos))
    centroid = V[F].mean(axis=1)
    sign = np.where(_dot(centroid[g] - centroid[f], normals[f]) > 0, -1.0, 1.0)
    return np.stack([a[i], b[i]], axis=1), sign * angle


def _point_segment_distance(X, A, B):
    ab = B - A
    t = np.clip(_dot(X - A, ab) / np.maximum(_dot(ab, ab), 1e-300), 0.0, 1.0)
    return np.linalg.norm(X - (A + t[:, None] * ab), axis=1)


def crease_metrics(gt_V, gt_F, patch_V, patch_F, angle=CREASE_ANGLE):
    """How well a patch reproduces the creases of the surface it replaces.

    The creases are the interior edges of the ground truth (the removed surface: both faces
    removed) whose signed dihedral angle theta_e (:func:`edge_dihedrals`) exceeds ``angle`` in
    magnitude. For each such edge e, of length L_e and midpoint m_e, the patch's angle there,
    phi_e, is the signed dihedral angle closest to theta_e among the patch's interior edges that
    pass within L_e of m_e (its best-matching fold there, so a crease the patch moves by less than
    an edge still counts), or 0 when none does (m_e then lies over the inside of flat patch
    faces). The edge's error is |theta_e - phi_e|: 0 when the patch has the crease, |theta_e|
    when it is flat there (a cap), more when it only folds the other way. Means are weighted by
    L_e. Creases along the hole border are measured by ``border_dihedral_excess_deg``
    instead (:func:`hole_metrics`).

    Parameters
    ----------
    gt_V : (n, 3) float64, gt_F : (r, 3) int  the removed surface
    patch_V : (p, 3) float64, patch_F : (q, 3) int  the patch
    angle : float  crease threshold, degrees

    Returns
    -------
    dict, empty when the ground truth has no crease; otherwise ``crease_edges`` (count),
    ``crease_length`` (sum of L_e), ``crease_gt_deg`` and ``crease_patch_deg`` (weighted means of
    |theta_e| and |phi_e|), ``crease_error_mean_deg`` (weighted mean error) and
    ``crease_error_max_deg``.
    """
    gt_V, patch_V = np.asarray(gt_V, np.float64), np.asarray(patch_V, np.float64)
    g_edges, g_angle = edge_dihedrals(gt_V, gt_F)
    sharp = np.abs(g_angle) > angle
    if not sharp.any():
        return {}
    g_edges, theta = g_edges[sharp], g_angle[sharp]
    A, B = gt_V[g_edges[:, 0]], gt_V[g_edges[:, 1]]
    length = np.linalg.norm(B - A, axis=1)
    mid = 0.5 * (A + B)
    p_edges, p_angle = edge_dihedrals(patch_V, patch_F)
    phi = np.zeros(len(theta))
    if len(p_edges):
        PA, PB = patch_V[p_edges[:, 0]], patch_V[p_edges[:, 1]]
        half = 0.5 * np.linalg.norm(PB - PA, axis=1)
        tree = cKDTree(0.5 * (PA + PB))
        reach = length + half.max()
        for k, candidates in enumerate(tree.query_ball_point(mid, reach)):
            if not candidates:
                continue
            c = np.asarray(candidates, np.int64)
            d = _point_segment_distance(np.broadcast_to(mid[k], (len(c), 3)), PA[c], PB[c])
            c = c[d <= length[k]]
            if len(c):
                phi[k] = p_angle[c[np.argmin(np.abs(p_angle[c] - theta[k]))]]
    error = np.abs(theta - phi)
    w = length / length.sum()
    return {"crease_edges": int(len(theta)), "crease_length": float(length.sum()),
            "crease_gt_deg": float(np.sum(w * np.abs(theta))), "crease_patch_deg": float(np.sum(w * np.abs(phi))),
            "crease_error_mean_deg": float(np.sum(w * error)), "crease_error_max_deg": float(error.max())}


def hole_metrics(V0, F0, V1, patch_faces, loop_vertices, border, ground_truth=None, diag=None, analytic=None):
    """All metrics of one hole's patch (those needing ground truth only when it is given).

    Parameters
    ----------
    V0 : (n, 3) float64, F0 : (m, 3) int  the mesh with holes
    V1 : (n + p, 3) float64  vertices of the filled mesh (originals first)
    patch_faces : (q, 3) int  this hole's patch (indices into V1)
    loop_vertices : (k,) int  the hole's boundary vertices
    border : ((k, 2) int, (k,) int)  the hole's boundary half-edges in F0 and their faces
    ground_truth : ((n + g, 3) float64, (r, 3) int), optional
        The removed surface, indexed like V1 (originals first, then g interior vertices).
    diag : float  bounding-box diagonal for per-mille figures
    analytic : callable, optional  (N, 3) points -> (N,) distances to the exact surface

    Returns
    -------
    metrics : dict of scalars (and ``quality_hist``, counts over QUALITY_BINS); with ground truth
        also the crease figures of :func:`crease_metrics` (when the removed surface has a crease) and the sums for Xie & Zou's Eq. 17 over the new vertices SP_i: ``eq17_distance_sum``
        (sum of E_i), ``eq17_distance_max`` and ``eq17_abs_coordinate_max`` (max |SP_ij|)
    arrays : dict with ``quality`` (q,) and, with ground truth, ``face_distance`` (q,) (distance
        of each face centroid to the ground truth)
    """
    patch_faces = np.asarray(patch_faces, np.int64)
    arrays = {}
    gt_compact = compact_mesh(*ground_truth) if ground_truth is not None else None
    metrics = patch_metrics(V0, F0, V1, patch_faces, loop_vertices, gt_compact, diag)
    if len(patch_faces) == 0:
        return metrics, arrays
    q = metrics.pop("quality_values")
    arrays["quality"] = q
    metrics["quality_max"] = float(q.max())
    metrics["quality_hist"] = np.histogram(q, QUALITY_BINS)[0].tolist()
    used = np.unique(patch_faces.ravel())
    metrics["new_vertices"] = int(np.count_nonzero(used >= len(V0)))
    angles = border_dihedrals(V1, F0, border[0], border[1], patch_faces)
    metrics["border_dihedral_mean_deg"] = float(np.nanmean(angles)) if np.isfinite(angles).any() else None
    metrics["border_dihedral_max_deg"] = float(np.nanmax(angles)) if np.isfinite(angles).any() else None
    if ground_truth is not None:
        gV, gF = ground_truth
        gt_angles = border_dihedrals(gV, F0, border[0], border[1], gF)
        metrics["gt_border_dihedral_mean_deg"] = float(np.nanmean(gt_angles))
        both = np.isfinite(angles) & np.isfinite(gt_angles)
        metrics["border_dihedral_excess_deg"] = float(np.mean(np.abs(angles[both] - gt_angles[both]))) if both.any() else None
        centroids = V1[patch_faces].mean(axis=1)
        dist, face, _ = closest_faces(centroids, gV, gF)
        arrays["face_distance"] = dist
        n_patch = face_normals(V1, patch_faces)
        n_gt = face_normals(gV, np.asarray(gF)[face])
        deviation = np.degrees(np.arccos(np.clip(_dot(n_patch, n_gt), -1.0, 1.0)))
        area = face_areas(V1, patch_faces)
        metrics["normal_dev_mean_deg"] = float(np.sum(deviation * area) / max(area.sum(), 1e-300))
        metrics["normal_dev_max_deg"] = float(deviation.max())
        metrics.update(crease_metrics(gV, gF, V1, patch_faces))
        new = used[used >= len(V0)]
        if len(new):  # the parts of Xie & Zou's Eq. 17 (pooled over holes by the report)
            e, _, _ = closest_faces(V1[new], gV, gF)
            metrics.update(eq17_distance_sum=float(e.sum()), eq17_distance_max=float(e.max()),
                           eq17_abs_coordinate_max=float(np.abs(V1[new]).max()))
    if analytic is not None:
        new = used[used >= len(V0)]
        if len(new):
            d = np.abs(analytic(V1[new]))
            metrics["analytic_dist_mean"] = float(d.mean())
            metrics["analytic_dist_max"] = float(d.max())
            if diag:
                metrics["analytic_dist_mean_permille"] = 1000.0 * float(d.mean()) / diag
    return metrics, arrays
