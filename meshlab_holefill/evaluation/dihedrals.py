"""Dihedral angles: across a hole's border, and along the creases of the removed surface (kept or lost)."""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..geometry.quality import face_normals
from .distances import dot_rows

__all__ = ["CREASE_ANGLE", "border_dihedrals", "edge_dihedrals", "crease_metrics"]

CREASE_ANGLE = 30.0  # degrees: an edge of the removed surface whose dihedral angle exceeds this is a crease


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
    cos = np.clip(dot_rows(n_mesh, n_patch), -1.0, 1.0)
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
    cos = np.clip(dot_rows(normals[f], normals[g]), -1.0, 1.0)
    angle = np.degrees(np.arccos(cos))
    centroid = V[F].mean(axis=1)
    sign = np.where(dot_rows(centroid[g] - centroid[f], normals[f]) > 0, -1.0, 1.0)
    return np.stack([a[i], b[i]], axis=1), sign * angle


def _point_segment_distance(X, A, B):
    ab = B - A
    t = np.clip(dot_rows(X - A, ab) / np.maximum(dot_rows(ab, ab), 1e-300), 0.0, 1.0)
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
