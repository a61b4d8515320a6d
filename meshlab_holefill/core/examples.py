"""Small holed meshes for the algorithms' runnable examples (numpy only)."""
from __future__ import annotations

import numpy as np

from .holes import boundary_loops
from .patch import validate_patch

__all__ = ["bowl_with_hole", "is_disc_patch"]


def bowl_with_hole(n=11, radius=0.45):
    """A bowl-shaped grid over [-1, 1]^2 (z = 0.2 (x^2 + y^2)) with a round hole in the middle.

    Returns
    -------
    V : (n * n, 3) float64
    F : (m, 3) int64
    loop : BoundaryLoop
        The hole (not the grid's outer border).
    """
    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    V = np.c_[x.ravel(), y.ravel(), 0.2 * (x ** 2 + y ** 2).ravel()]
    i = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)).ravel()
    F = np.concatenate([np.c_[i, i + 1, i + n + 1], np.c_[i, i + n + 1, i + n]])
    F = F[np.linalg.norm(V[F].mean(axis=1)[:, :2], axis=1) > radius]
    return V, F, min(boundary_loops(F), key=len)


def is_disc_patch(patch, ctx):
    """Whether ``patch`` closes its hole exactly once as a disc (validated; Euler: F = 2 V_new + k - 2)."""
    validate_patch(patch, ctx.points, ctx.forbidden_edges)
    return len(patch.faces) == 2 * len(patch.vertices) + ctx.size - 2
