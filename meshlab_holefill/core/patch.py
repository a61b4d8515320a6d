"""A hole patch (new vertices and faces in loop-local indices), its validation and merging."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import HoleFillError
from ..geometry.quality import face_areas
from .sets import isin_ints, unique_ints


@dataclass
class Patch:
    """New geometry closing one hole.

    Attributes
    ----------
    vertices : (p, 3) float64
        New vertices only.
    faces : (q, 3) int64
        Indices into ``concatenate([hole.points, vertices])``: index i < k is loop vertex i,
        index k + j is new vertex j.
    info : dict
        Algorithm-specific statistics reported in the per-hole result (times, restarts...).
    """

    vertices: np.ndarray
    faces: np.ndarray
    info: dict = field(default_factory=dict)

    def all_points(self, loop_points):
        """(k + p, 3) loop points followed by the new vertices."""
        return np.concatenate([np.asarray(loop_points, np.float64).reshape(-1, 3),
                               np.asarray(self.vertices, np.float64).reshape(-1, 3)])


def validate_patch(patch, loop_points, forbidden_edges=(), area_tol=None):
    """Check that a patch closes its hole exactly once, as a consistently oriented 2-manifold.

    Checks: finite coordinates; face indices in range; no face repeating a vertex and no
    face of (near) zero area; every directed edge used at most once (orientation
    consistent, no non-manifold edge); the patch's boundary is exactly the loop, each loop
    edge (i, i+1) used once in that direction (so the patch is oriented like the border
    faces and the hole ends up watertight); no interior edge duplicating a mesh edge
    between loop vertices (``forbidden_edges``); every new vertex used.

    Parameters
    ----------
    patch : Patch
    loop_points : (k, 3) float64
    forbidden_edges : (p, 2) int, loop-local pairs already joined by a mesh edge
    area_tol : float, optional
        Faces with area <= area_tol are degenerate. Default: 1e-12 * (loop bbox diagonal)^2.

    Raises
    ------
    HoleFillError
        Naming the first violated property.
    """
    P = np.asarray(loop_points, np.float64)
    k = len(P)
    Fp = np.asarray(patch.faces, np.int64).reshape(-1, 3)
    Vp = np.asarray(patch.vertices, np.float64).reshape(-1, 3)
    n = k + len(Vp)
    if len(Fp) == 0:
        raise HoleFillError("patch has no faces")
    if not np.all(np.isfinite(Vp)):
        raise HoleFillError("patch has non-finite vertex coordinates")
    if Fp.min() < 0 or Fp.max() >= n:
        raise HoleFillError("patch face index out of range")
    if np.any((Fp[:, 0] == Fp[:, 1]) | (Fp[:, 1] == Fp[:, 2]) | (Fp[:, 0] == Fp[:, 2])):
        raise HoleFillError("patch has a face repeating a vertex")
    X = np.concatenate([P, Vp])
    if area_tol is None:
        diag = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0))) if k else 1.0
        area_tol = 1e-12 * diag * diag
    if np.any(face_areas(X, Fp) <= area_tol):
        raise HoleFillError("patch has a degenerate (zero-area) face")
    directed = np.concatenate([Fp[:, [0, 1]], Fp[:, [1, 2]], Fp[:, [2, 0]]])
    dkeys = directed[:, 0] * n + directed[:, 1]
    if len(unique_ints(dkeys)) != len(dkeys):
        raise HoleFillError("patch uses a directed edge twice (non-manifold edge or inconsistent orientation)")
    reverse = directed[:, 1] * n + directed[:, 0]
    has_twin = isin_ints(dkeys, reverse)
    open_edges = directed[~has_twin]
    loop_edges = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    open_keys = np.sort(open_edges[:, 0] * n + open_edges[:, 1])
    loop_keys = np.sort(loop_edges[:, 0] * n + loop_edges[:, 1])
    if len(open_keys) != len(loop_keys) or np.any(open_keys != loop_keys):
        if isin_ints(loop_edges[:, 1] * n + loop_edges[:, 0], dkeys).any():
            raise HoleFillError("patch is oriented against the surrounding mesh")
        raise HoleFillError("patch boundary does not match the hole boundary (not watertight)")
    fe = np.asarray(forbidden_edges, np.int64).reshape(-1, 2)
    if len(fe):
        und = np.sort(directed, axis=1)
        und_keys = und[:, 0] * n + und[:, 1]
        fe = np.sort(fe, axis=1)
        if isin_ints(fe[:, 0] * n + fe[:, 1], und_keys).any():
            raise HoleFillError("patch duplicates an existing mesh edge between boundary vertices")
    if len(Vp) and len(unique_ints(Fp[Fp >= k])) != len(Vp):
        raise HoleFillError("patch has unused vertices")


def merge_patches(V, F, loops, patches):
    """Append patches to a mesh; original vertices and faces keep their order and values.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int
    loops : list of (k_i,) int64 global loop vertex indices, one per patch
    patches : list of Patch

    Returns
    -------
    V2 : (n + sum p_i, 3) float64
    F2 : (m + sum q_i, 3)
        F's integer type (int32 stays int32, as pymeshlab reads and writes it; other types give int64).
    """
    F = np.asarray(F)
    index = F.dtype if F.dtype in (np.int32, np.int64) else np.dtype(np.int64)
    Vs, Fs = [np.asarray(V, np.float64)], [F.astype(index, copy=False)]
    offset = len(V)
    for loop, patch in zip(loops, patches):
        loop = np.asarray(loop, np.int64)
        local_to_global = np.concatenate([loop, offset + np.arange(len(patch.vertices), dtype=np.int64)])
        Fs.append(local_to_global[np.asarray(patch.faces, np.int64)].astype(index, copy=False))
        Vs.append(np.asarray(patch.vertices, np.float64).reshape(-1, 3))
        offset += len(patch.vertices)
    return np.concatenate(Vs), np.concatenate(Fs)
