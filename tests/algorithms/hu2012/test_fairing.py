"""Membrane and thin-plate fairing, the fairing option of Hu et al.'s filter."""
import numpy as np

from meshlab_holefill.algorithms.hu2012.fairing import fair_positions
from meshlab_holefill.geometry.laplacian import uniform_laplacian
from conftest import grid


def test_fairing_reproduces_a_plane_and_solves_its_system():
    V, F = grid(9, 9, z=lambda x, y: 0.3 * x + 0.2 * y)
    boundary = (V[:, 0] < 1e-9) | (V[:, 0] > 1 - 1e-9) | (V[:, 1] < 1e-9) | (V[:, 1] > 1 - 1e-9)
    for order in (1, 2):
        # The thin-plate solve needs two rings of constrained vertices.
        fixed = boundary if order == 1 else boundary | (np.abs(V[:, 0] - 0.5) > 0.37) | (np.abs(V[:, 1] - 0.5) > 0.37)
        noisy = V.copy()
        noisy[~fixed, 2] += 0.2
        out = fair_positions(noisy, F, fixed, order=order)
        assert np.allclose(out, V, atol=1e-9)
        L = uniform_laplacian(F, len(V))
        residual = (L if order == 1 else L @ L) @ out
        assert np.abs(residual[~fixed]).max() < 1e-9
