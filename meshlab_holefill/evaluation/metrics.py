"""Metrics of a filled hole against its ground truth and its surroundings.

Distances (seeded area samples of one surface at their exact distance from the other, both
ways; exact closest points), normal deviation, triangle quality 2r/R (Field; Hu et al. Sec. IV), density match (edge ratio),
dihedral continuity across the hole border, creases of the removed surface kept or lost
(:func:`crease_metrics`), intersections and changed originals. The distances are computed in
:mod:`.distances`, the dihedral angles in :mod:`.dihedrals`, the quality a hole's corners allow in
:mod:`.quality_bound`; this module offers them under its own name too.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse.csgraph import connected_components

from ..core.holes import boundary_loops, nonmanifold_edges
from ..geometry.intersections import faces_intersecting
from ..geometry.quality import edge_lengths, face_areas, face_normals, triangle_quality
from ..geometry.topology import face_adjacency
from .dihedrals import CREASE_ANGLE, border_dihedrals, crease_metrics, edge_dihedrals
from .distances import (closest_faces, closest_point_on_triangles, dot_rows, hausdorff_one_way,
                        point_to_surface_distances, sample_surface)
from .quality_bound import corner_quality_bound, fan_triangle_quality

__all__ = ["CREASE_ANGLE", "QUALITY_BINS", "assign_patches", "border_dihedrals", "closest_faces",
           "closest_point_on_triangles", "compact_mesh", "corner_quality_bound", "crease_metrics", "edge_dihedrals",
           "fan_triangle_quality", "hausdorff_one_way", "hole_metrics", "mesh_checks", "patch_metrics",
           "point_to_surface_distances", "sample_surface"]

QUALITY_BINS = np.linspace(0.0, 1.0, 21)


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
    loop_vertex_sets : list of (k_i,) int  boundary vertices of each hole, in loop order

    Returns
    -------
    list of (q_i,) int64 arrays: positions in F_new of the faces of each hole's patch

    Each edge-connected component of the new faces goes to the hole of which it holds the most
    border edges (consecutive loop vertices): holes can share vertices (a pinched border, or two
    holes a face apart), which the patch of either touches, but each border edge is one hole's.
    """
    q = len(F_new)
    if q == 0:
        return [np.zeros(0, np.int64) for _ in loop_vertex_sets]
    F_new = np.asarray(F_new, np.int64)
    n_comp, label = connected_components(face_adjacency(F_new), directed=False)
    edges = np.sort(np.stack([F_new, np.roll(F_new, -1, axis=1)], axis=2).reshape(-1, 2), axis=1)  # (3 q, 2)
    size = int(max(F_new.max(), max((int(np.max(v)) for v in loop_vertex_sets if len(v)), default=0))) + 1
    keys, edge_label = edges[:, 0] * size + edges[:, 1], np.repeat(label, 3)
    owner, most = np.full(n_comp, -1), np.zeros(n_comp, np.int64)
    for h, verts in enumerate(loop_vertex_sets):
        verts = np.asarray(verts, np.int64)
        loop_edges = np.sort(np.stack([verts, np.roll(verts, -1)], axis=1), axis=1)  # (k, 2)
        held = np.isin(keys, loop_edges[:, 0] * size + loop_edges[:, 1])
        count = np.bincount(edge_label[held], minlength=n_comp)
        better = count > most
        owner[better], most[better] = h, count[better]
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
        metrics["gt_border_dihedral_mean_deg"] = (float(np.nanmean(gt_angles)) if np.isfinite(gt_angles).any()
                                                  else None)
        both = np.isfinite(angles) & np.isfinite(gt_angles)
        metrics["border_dihedral_excess_deg"] = float(np.mean(np.abs(angles[both] - gt_angles[both]))) if both.any() else None
        centroids = V1[patch_faces].mean(axis=1)
        dist, face, _ = closest_faces(centroids, gV, gF)
        arrays["face_distance"] = dist
        n_patch = face_normals(V1, patch_faces)
        n_gt = face_normals(gV, np.asarray(gF)[face])
        deviation = np.degrees(np.arccos(np.clip(dot_rows(n_patch, n_gt), -1.0, 1.0)))
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
