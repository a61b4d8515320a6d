"""Meshes the evaluation tests share: flat grids (optionally equilateral) and MeshLab's icosphere."""
import numpy as np

from meshlab_holefill.meshlab.mesh_files import mesh_arrays


def grid(n=24, equilateral=False):
    """Flat triangulated square (z = 0) with n x n cells; equilateral rows when asked."""
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    x = i + (0.5 * (j % 2) if equilateral else 0.0)
    y = j * (np.sqrt(3) / 2 if equilateral else 1.0)
    V = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1).astype(np.float64)
    idx = lambda a, b: a * (n + 1) + b  # noqa: E731
    F = []
    for a in range(n):
        for b in range(n):
            p, q, r, s = idx(a, b), idx(a + 1, b), idx(a + 1, b + 1), idx(a, b + 1)
            if equilateral and b % 2 == 0:
                F += [[p, q, s], [q, r, s]]
            else:
                F += [[p, q, r], [p, r, s]]
    return V, np.asarray(F, np.int64)


def sphere(subdiv=4):
    """MeshLab's icosphere of radius 1: ((n, 3) float64, (m, 3) int64)."""
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=subdiv)
    return mesh_arrays(ms)

