"""A hole patch (new vertices and faces in loop-local indices), its validation and merging."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from ..errors import HoleFillError
from ..geometry._flip_kernels import _contains
from ..geometry.quality import face_areas


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
    fe = np.ascontiguousarray(np.asarray(forbidden_edges, np.int64).reshape(-1, 2))
    failure = _edge_failure(np.ascontiguousarray(Fp), k, n, fe)
    if failure:
        raise HoleFillError(_EDGE_FAILURES[failure])


_EDGE_FAILURES = {
    1: "patch uses a directed edge twice (non-manifold edge or inconsistent orientation)",
    2: "patch is oriented against the surrounding mesh",
    3: "patch boundary does not match the hole boundary (not watertight)",
    4: "patch duplicates an existing mesh edge between boundary vertices",
    5: "patch has unused vertices",
}


@njit(cache=True)
def _edge_failure(Fp, k, n, fe):
    """The edge checks of :func:`validate_patch`, in its order: 0 when they pass, else the
    ``_EDGE_FAILURES`` code of the first that fails (faces Fp of valid indices below n, loop
    0..k-1, forbidden loop pairs fe). Directed edge (a, b) is the key a * n + b."""
    m = Fp.shape[0]
    keys = np.empty(3 * m, np.int64)
    for c in range(3):
        for f in range(m):
            keys[c * m + f] = Fp[f, c] * n + Fp[f, (c + 1) % 3]
    ordered = np.sort(keys)
    for e in range(1, 3 * m):
        if ordered[e] == ordered[e - 1]:
            return 1
    # The edges without a twin must be the loop edges (i, i + 1), each once (no duplicates now).
    open_count = 0
    for e in range(3 * m):
        a, b = keys[e] // n, keys[e] % n
        if not _contains(ordered, b * n + a):
            open_count += 1
            if not (a < k and b == (a + 1) % k):
                open_count = -1
                break
    if open_count != k:
        for i in range(k):
            if _contains(ordered, ((i + 1) % k) * n + i):
                return 2
        return 3
    for r in range(fe.shape[0]):
        a, b = min(fe[r, 0], fe[r, 1]), max(fe[r, 0], fe[r, 1])
        if _contains(ordered, a * n + b) or _contains(ordered, b * n + a):
            return 4
    used = np.zeros(n, np.bool_)
    for f in range(m):
        for c in range(3):
            used[Fp[f, c]] = True
    for v in range(k, n):
        if not used[v]:
            return 5
    return 0


def load_validation_kernel():
    """Load the compiled checks of :func:`validate_patch` (its edge checks and face areas) in this process.

    The pipeline calls it before holes are filled, so that forked workers inherit the loaded
    kernels instead of each loading them within its first hole's time (about 0.015 s each).
    """
    _edge_failure(np.array([[0, 1, 2]], np.int64), 3, 3, np.zeros((0, 2), np.int64))
    face_areas(np.eye(3), np.array([[0, 1, 2]], np.int64))


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
