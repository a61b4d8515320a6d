"""Holes with known ground truth cut into closed meshes: star-shaped face regions of a chosen boundary size.

:func:`cut_holes` removes one face region per requested size class (``SIZE_CLASSES``: target
boundary edges) and returns the removed faces as ground truth; :func:`hole_plan` says which
size and shape each of a comparison's holes gets. The comparison (:mod:`.comparison`) measures
every filler's patch against these removed faces.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.sparse.csgraph import connected_components

from ..core.holes import boundary_loops
from ..geometry.pca import plane_frame
from ..geometry.quality import edge_lengths, face_normals
from ..geometry.topology import face_adjacency

__all__ = ["IRREGULAR_SHAPE", "SIZE_CLASSES", "CutHole", "cut_holes", "hole_plan", "star_region"]

# Target boundary sizes (edges) of the hole classes; an "irregular" hole is by default also
# irregular in shape (IRREGULAR_SHAPE).
SIZE_CLASSES = {"small": 20, "medium": 60, "large": 150, "irregular": 250}
# Star outline of an irregular hole: radius modulated by 45 %, stretched 1.6 x along one axis.
IRREGULAR_SHAPE = {"amplitude": 0.45, "stretch": 1.6}


@dataclass
class CutHole:
    """A hole cut into a mesh, with the removed faces as ground truth.

    Attributes
    ----------
    size_class : str
    removed_faces : (r, 3) int64  faces of the original mesh that were removed (original indices)
    boundary_edges : int
    shape : str  "compact" (round outline) or "irregular" (lobed, stretched outline)
    center : (3,) float64  centroid of the seed face
    face_indices : (r,) int64  positions of the removed faces in the original F
    """

    size_class: str
    removed_faces: np.ndarray
    boundary_edges: int
    shape: str = "compact"
    center: np.ndarray = field(default_factory=lambda: np.zeros(3))
    face_indices: np.ndarray | None = None


def _region_boundary(F, region):
    """Number of boundary edges of a face region and whether it is one simple loop."""
    loops = boundary_loops(F[region])
    return sum(len(lp) for lp in loops), len(loops) == 1 and not loops[0].pinched


def star_region(F, centroids, adjacency, seed_face, normal, radius, amplitude=0.0, lobes=3, phase=0.0,
                stretch=1.0, border=None):
    """Face region around a seed face inside a (noisy) star-shaped outline, made a topological disk.

    A face is inside when its centroid, seen in the tangent plane of the seed, lies within
    radius * (1 + amplitude * sin(lobes * theta + phase)) (x stretched by ``stretch``); the
    region is the inside component containing the seed, with enclosed islands filled in.

    Parameters
    ----------
    F : (m, 3) int  (only its length is used)
    centroids : (m, 3) float64
    adjacency : (m, m) sparse face adjacency (:func:`geometry.topology.face_adjacency`)
    seed_face : int
    normal : (3,) float64  unit normal of the seed face (the outline lies in its tangent plane)
    radius : float  mean radius of the outline
    amplitude, lobes, phase : float, int, float  radius modulation amplitude * sin(lobes * theta + phase)
    stretch : float  stretch of the outline along the tangent plane's first axis
    border : (m,) bool, optional
        For a local window of a larger mesh: faces with a neighbour outside the window. The
        complement components touching it are "outside"; the others are enclosed islands.
        Without it the biggest complement component is the outside.

    Returns
    -------
    (r,) int64 face indices
    """
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
        touching = np.unique(lab[border[rest]]) if border is not None else np.zeros(0, np.int64)
        outside = np.isin(lab, touching) if len(touching) else lab == np.argmax(np.bincount(lab))
        mask[rest[~outside]] = True
    return np.flatnonzero(mask)


def hole_plan(count, sizes=("small", "medium", "large")):
    """Size class and shape of each of ``count`` holes: sizes cycle, shapes alternate.

    Returns
    -------
    list of (size_class, shape) with shape "compact" or "irregular".
    """
    sizes = list(sizes)
    return [(sizes[i % len(sizes)], "compact" if i % 2 == 0 else "irregular") for i in range(count)]


def _seed_order(centroids, center, rng, tries):
    """Seed faces to try: random, or the faces nearest a requested centre."""
    if center is None:
        return rng.integers(len(centroids), size=tries)
    d = np.linalg.norm(centroids - np.asarray(center, np.float64), axis=1)
    near = np.argpartition(d, min(tries, len(d) - 1))[:tries]
    return near[np.argsort(d[near])]


def cut_holes(V, F, sizes=("small", "medium", "large", "irregular"), seed=0, max_tries=50, shapes=None,
              centers=None, strict=True):
    """Cut one hole per requested size class into a closed mesh, holes kept apart and simple.

    Each hole is a star-shaped face region grown until its boundary reaches the class's
    target edge count (0.8 to 1.5 times the target is accepted); the remaining mesh keeps
    simple, unpinched boundary loops, and later holes stay three face rings away.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int
    sizes : sequence of str (keys of SIZE_CLASSES)
    seed : int
    max_tries : int  seed faces tried per hole
    shapes : sequence of str, optional
        "compact" or "irregular" per hole; by default a hole is irregular iff its class is.
    centers : (h, 3) float64, optional
        Grow hole i from the faces nearest centers[i] (the same holes on remeshed copies).
    strict : bool
        Raise when a hole cannot be cut; otherwise leave it out.

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
    for h, size in enumerate(sizes):
        shape_name = shapes[h] if shapes is not None else ("irregular" if size == "irregular" else "compact")
        irregular = shape_name == "irregular"
        target = SIZE_CLASSES[size]
        center = None if centers is None else centers[h]
        # Only a window around the seed is examined, so the cost per hole does not grow with the mesh.
        window_radius = mean_edge * target * (0.9 if irregular else 0.5)
        for seed_face in _seed_order(centroids, center, rng, max_tries):
            seed_face = int(seed_face)
            if blocked[seed_face]:
                continue
            local = np.flatnonzero(np.linalg.norm(centroids - centroids[seed_face], axis=1) < window_radius)
            local_adj = adjacency[local][:, local]
            outside_links = np.asarray(adjacency[local].sum(axis=1)).ravel() - np.asarray(local_adj.sum(axis=1)).ravel()
            border = outside_links > 0
            seed_local = int(np.searchsorted(local, seed_face))
            shape = dict(amplitude=IRREGULAR_SHAPE["amplitude"] if irregular else 0.0,
                         lobes=int(rng.integers(2, 5)), phase=float(rng.uniform(0, 2 * np.pi)),
                         stretch=IRREGULAR_SHAPE["stretch"] if irregular else 1.0)
            # Grow the outline until the boundary reaches the target length.
            radius = mean_edge * target / (2 * np.pi) * 0.25
            region, edges, simple = None, 0, False
            for _ in range(80):
                region_local = star_region(local, centroids[local], local_adj, seed_local, normals[seed_face],
                                           radius, border=border, **shape)
                region = local[region_local]
                edges, simple = _region_boundary(F, region)
                if edges >= target or not simple or border[region_local].any():
                    break
                radius *= 1.05
            if (not simple or border[region_local].any() or edges < 0.8 * target or edges > 1.5 * target
                    or blocked[region].any()):
                continue
            # The remaining mesh must stay free of pinched vertices around the new hole.
            trial = removed.copy()
            trial[region] = True
            loops = boundary_loops(F[~trial])
            if any(lp.pinched for lp in loops) or len(loops) != len(holes) + 1:
                continue
            removed = trial
            holes.append(CutHole(size, F[region], edges, shape_name, centroids[seed_face].copy(), np.sort(region)))
            # Keep later holes two face rings away from this one.
            ring = np.zeros(len(F), bool)
            ring[region] = True
            for _ in range(3):
                ring = ring | (adjacency @ ring.astype(np.float64) > 0)
            blocked |= ring
            break
        else:
            if strict:
                raise RuntimeError(f"could not cut a simple '{size}' hole after {max_tries} tries")
    return F[~removed], holes
