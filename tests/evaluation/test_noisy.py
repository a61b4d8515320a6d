"""evaluation.noisy: scan-like noise along the normals, scaled by the sampling."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.evaluation.analytic import analytic_mesh
from meshlab_holefill.evaluation.noisy import normal_noise
from meshlab_holefill.geometry.quality import edge_lengths, vertex_normals


@settings(max_examples=10, deadline=None)
@given(sigma=st.floats(0.01, 1.0), scale=st.floats(1e-3, 1e3), seed=st.integers(0, 2**31))
def test_the_noise_moves_each_vertex_along_its_normal_by_sigma_mean_edges_at_any_scale(sigma, scale, seed):
    V, F = analytic_mesh("torus")
    V = V * scale
    W = normal_noise(V, F, sigma, seed)
    D, N = W - V, vertex_normals(V, F)
    along = (D * N).sum(axis=1)
    np.testing.assert_allclose(D, along[:, None] * N, atol=1e-12 * scale)  # no tangential part
    relative_rms = np.sqrt((along ** 2).mean()) / edge_lengths(V, F).mean()
    assert abs(relative_rms - sigma) < 0.1 * sigma  # thousands of vertices: within 10 % of sigma


def test_the_noise_is_reproducible_and_leaves_the_input_alone():
    V, F = analytic_mesh("sphere")
    before = V.copy()
    assert np.array_equal(normal_noise(V, F, 0.3, seed=4), normal_noise(V, F, 0.3, seed=4))
    assert not np.array_equal(normal_noise(V, F, 0.3, seed=4), normal_noise(V, F, 0.3, seed=5))
    assert np.array_equal(V, before)


def test_a_vertex_without_faces_stays_where_it_is():
    V, F = analytic_mesh("sphere")
    V = np.vstack([V, [[5.0, 5.0, 5.0]]])
    assert np.array_equal(normal_noise(V, F, 0.5)[-1], [5.0, 5.0, 5.0])
