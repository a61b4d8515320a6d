"""Pfeifle-Seidel density refinement of geometry.refine."""
import numpy as np

from meshlab_holefill.geometry.quality import triangle_quality
from meshlab_holefill.geometry.refine import refine_patch, split_condition


def test_refinement_matches_the_boundary_density():
    k = 48
    t = np.linspace(0, 2 * np.pi, k, endpoint=False)
    P = np.stack([np.cos(t), np.sin(t), np.zeros(k)], 1)
    F = np.array([[0, i, i + 1] for i in range(1, k - 1)])
    h = 2 * np.sin(np.pi / k)
    loop = np.stack([np.arange(k), (np.arange(k) + 1) % k], 1)
    V, F2, scale, info = refine_patch(P, F, np.full(k, h), fixed_edges=loop)
    assert len(V) > k + 100  # interior filled with vertices
    assert not split_condition(V, F2, scale, np.sqrt(2))[0].any()  # converged
    E = np.concatenate([F2[:, [0, 1]], F2[:, [1, 2]], F2[:, [2, 0]]])
    lengths = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    assert 0.7 < lengths.mean() / h < 1.4
    # Splits and swaps alone do not move vertices: fair quality, not the best.
    assert triangle_quality(V, F2).mean() > 0.7
