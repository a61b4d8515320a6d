"""Holes with known ground truth, and the metrics that compare hole fillers on them.

``cut_holes`` removes face regions from a closed mesh and keeps them as ground truth;
``evaluate_fill`` measures a filled mesh against it (distances via MeshLab's own
Hausdorff sampler, triangle quality, density match, intersections, changed originals).
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import pymeshlab
import scipy.sparse as sp

from .geometry.intersections import faces_intersecting
from .geometry.quality import edge_lengths, face_normals, triangle_quality
from .holes import boundary_loops, nonmanifold_edges

# Target boundary sizes (edges) of the hole classes.
SIZE_CLASSES = {"small": 20, "medium": 60, "large": 150, "irregular": 250}


@dataclass
class CutHole:
    """A hole cut into a mesh, with the removed faces as ground truth.

    Attributes
    ----------
    size_class : str
    removed_faces : (r, 3) int64  faces of the original mesh that were removed (original indices)
    boundary_edges : int
    """

    size_class: str
    removed_faces: np.ndarray
    boundary_edges: int


def face_adjacency(F):
    """Sparse (m, m) face adjacency through shared edges."""
    F = np.asarray(F, np.int64)
    m = len(F)
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    keys = E[:, 0] * (F.max() + 1) + E[:, 1]
    order = np.argsort(keys)
    ks = keys[order]
    same = np.flatnonzero(ks[1:] == ks[:-1])
    a, b = order[same] % m, order[same + 1] % m
    return sp.coo_matrix((np.ones(2 * len(a)), (np.r_[a, b], np.r_[b, a])), shape=(m, m)).tocsr()


def _region_boundary(F, region):
    """Number of boundary edges of a face region and whether it is one simple loop."""
    loops = boundary_loops(F[region])
    return sum(len(lp) for lp in loops), len(loops) == 1 and not loops[0].pinched


def star_region(F, centroids, adjacency, seed_face, normal, radius, amplitude=0.0, lobes=3, phase=0.0,
                stretch=1.0):
    """Face region around a seed face inside a (noisy) star-shaped outline, made a topological disk.

    A face is inside when its centroid, seen in the tangent plane of the seed, lies within
    radius * (1 + amplitude * sin(lobes * theta + phase)) (x stretched by ``stretch``); the
    region is the inside component containing the seed, with enclosed islands filled in.

    Returns
    -------
    (r,) int64 face indices
    """
    from scipy.sparse.csgraph import connected_components

    from .geometry.pca import plane_frame

    u, v = plane_frame(normal)
    D = centroids - centroids[seed_face]
    x, y, z = D @ u / stretch, D @ v, D @ normal
    theta = np.arctan2(y, x)
    limit = radius * (1.0 + amplitude * np.sin(lobes * theta + phase))
    inside = (np.hypot(x, y) < limit) & (np.abs(z) < 2 * radius)
    idx = np.flatnonzero(inside)
    sub = adjacency[idx][:, idx]
    _, label = connected_components(sub, directed=False)
    region = idx[label == label[np.searchsorted(idx, seed_face)]]
    mask = np.zeros(len(F), bool)
    mask[region] = True
    rest = np.flatnonzero(~mask)
    n_comp, lab = connected_components(adjacency[rest][:, rest], directed=False)
    if n_comp > 1:
        biggest = np.argmax(np.bincount(lab))
        mask[rest[lab != biggest]] = True
    return np.flatnonzero(mask)


def cut_holes(V, F, sizes=("small", "medium", "large", "irregular"), seed=0, max_tries=50):
    """Cut one hole per requested size class into a closed mesh, holes kept apart and simple.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int
    sizes : sequence of str (keys of SIZE_CLASSES)
    seed : int

    Returns
    -------
    F_cut : (m - r, 3) int64  remaining faces (original order kept)
    holes : list of CutHole
    """
    F = np.asarray(F, np.int64)
    V = np.asarray(V, np.float64)
    rng = np.random.default_rng(seed)
    adjacency = face_adjacency(F)
    centroids = V[F].mean(axis=1)
    normals = face_normals(V, F)
    mean_edge = float(edge_lengths(V, F).mean())
    blocked = np.zeros(len(F), bool)
    removed = np.zeros(len(F), bool)
    holes = []
    for size in sizes:
        target = SIZE_CLASSES[size]
        for _ in range(max_tries):
            seed_face = int(rng.integers(len(F)))
            if blocked[seed_face]:
                continue
            irregular = size == "irregular"
            shape = dict(amplitude=0.45 if irregular else 0.0, lobes=int(rng.integers(2, 5)),
                         phase=float(rng.uniform(0, 2 * np.pi)), stretch=1.6 if irregular else 1.0)
            # Grow the outline until the boundary reaches the target length.
            radius = mean_edge * target / (2 * np.pi) * 0.25
            region, edges, simple = None, 0, False
            for _ in range(80):
                region = star_region(F, centroids, adjacency, seed_face, normals[seed_face], radius, **shape)
                edges, simple = _region_boundary(F, region)
                if edges >= target or not simple:
                    break
                radius *= 1.05
            if not simple or edges < 0.8 * target or edges > 1.5 * target or blocked[region].any():
                continue
            # The remaining mesh must stay free of pinched vertices around the new hole.
            trial = removed.copy()
            trial[region] = True
            loops = boundary_loops(F[~trial])
            if any(lp.pinched for lp in loops) or len(loops) != len(holes) + 1:
                continue
            removed = trial
            holes.append(CutHole(size, F[region], edges))
            # Keep later holes two face rings away from this one.
            ring = np.zeros(len(F), bool)
            ring[region] = True
            for _ in range(3):
                ring = ring | (adjacency @ ring.astype(np.float64) > 0)
            blocked |= ring
            break
        else:
            raise RuntimeError(f"could not cut a simple '{size}' hole after {max_tries} tries")
    return F[~removed], holes


def hausdorff_one_way(src_V, src_F, dst_V, dst_F, samples=20000):
    """Distances from surface src to surface dst (MeshLab's Hausdorff sampler).

    Returns
    -------
    dict with ``mean``, ``rms``, ``max`` (absolute units).
    """
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(src_V, np.float64), face_matrix=np.asarray(src_F, np.int32)))
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(dst_V, np.float64), face_matrix=np.asarray(dst_F, np.int32)))
    res = ms.get_hausdorff_distance(sampledmesh=0, targetmesh=1, samplevert=True, sampleedge=True,
                                    sampleface=True, samplenum=samples, maxdist=pymeshlab.PercentageValue(100))
    return {"mean": float(res["mean"]), "rms": float(res["RMS"]), "max": float(res["max"])}


def compact_mesh(V, F):
    """Keep only the vertices F uses; returns (V', F') with F' reindexed."""
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
    from scipy.sparse.csgraph import connected_components

    q = len(F_new)
    if q == 0:
        return [np.zeros(0, np.int64) for _ in loop_vertex_sets]
    n_comp, label = connected_components(face_adjacency(F_new), directed=False)
    owner = np.full(n_comp, -1)
    for h, verts in enumerate(loop_vertex_sets):
        touching = np.isin(F_new, verts).any(axis=1)
        owner[np.unique(label[touching])] = h
    return [np.flatnonzero(owner[label] == h) for h in range(len(loop_vertex_sets))]


def mesh_checks(V0, F0, V1, F1):
    """Whole-mesh checks after a fill: originals unchanged, manifoldness, boundary left, intersections.

    Returns
    -------
    dict with ``originals_changed`` (moved original vertices + changed original faces),
    ``nonmanifold_edges``, ``boundary_edges_left``, ``intersecting_new_faces``,
    ``new_faces``, ``new_vertices``.
    """
    n0, m0 = len(V0), len(F0)
    moved = int(np.count_nonzero(np.any(V1[:n0] != V0, axis=1))) if len(V1) >= n0 else n0
    changed = int(np.count_nonzero(np.any(F1[:m0] != F0, axis=1))) if len(F1) >= m0 else m0
    new = np.arange(m0, len(F1))
    hits = faces_intersecting(V1, F1, new, np.arange(len(F1))) if len(new) else []
    return {"originals_changed": moved + changed, "nonmanifold_edges": int(len(nonmanifold_edges(F1))),
            "boundary_edges_left": int(sum(len(lp) for lp in boundary_loops(F1))),
            "intersecting_new_faces": int(len(hits)), "new_faces": int(len(F1) - m0),
            "new_vertices": int(len(V1) - n0)}


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


def run_filter_timed(ms, name, **params):
    """Apply a filter (ours or built-in) and return (result, seconds)."""
    from .registry import apply_filter

    t0 = time.perf_counter()
    res = apply_filter(ms, name, **params)
    return res, time.perf_counter() - t0
