"""LS-SVM readings: the normal-frame Laplacian regression and the leave-one-out model selection."""
import numpy as np
import pymeshlab
import pytest
from hypothesis import given, settings, strategies as st

from meshlab_holefill.algorithms.xu2013.lssvm import lssvm_fit
from meshlab_holefill.algorithms.xu2013.laplacian_regression import loo_error, select_model, LOO_GAMMAS, LOO_WIDTHS
from meshlab_holefill.array_api import fill_holes
from meshlab_holefill.evaluation.cut_holes import cut_holes


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 10_000), gamma=st.sampled_from([1.0, 10.0, 100.0]), width=st.sampled_from([0.3, 1.0]))
def test_closed_form_leave_one_out_matches_refits(seed, gamma, width):
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1, 1, (15, 3))
    y = np.sin(2 * x[:, 0]) + 0.1 * rng.normal(size=15)
    brute = []
    for i in range(len(x)):
        keep = np.arange(len(x)) != i
        f = lssvm_fit(x[keep], y[keep], gamma=gamma, width=width)
        brute.append(y[i] - f(x[i:i + 1])[0])
    assert loo_error(x, y, gamma, width) == pytest.approx(np.mean(np.square(brute)), rel=1e-6)


def test_model_selection_picks_from_the_grid_and_fixed_keeps_the_parameters():
    rng = np.random.default_rng(0)
    x = rng.uniform(-1, 1, (40, 2))
    y = x[:, 0] ** 2
    assert select_model(x, y, 2.0, 10.0, 0.5, "fixed") == (10.0, 1.0)
    g, w = select_model(x, y, 2.0, 10.0, 0.5, "loo")
    assert g in LOO_GAMMAS and w / 2.0 in LOO_WIDTHS


@pytest.fixture(scope="module")
def sphere_holes():
    ms = pymeshlab.MeshSet()
    ms.create_sphere(radius=1.0, subdiv=5)
    V = np.asarray(ms.current_mesh().vertex_matrix(), np.float64)
    F = np.asarray(ms.current_mesh().face_matrix(), np.int64)
    F_cut, holes = cut_holes(V, F, sizes=["medium", "large"], seed=0)
    return V, F_cut


def _sphere_cap_error(sphere_holes, **params):
    V, F = sphere_holes
    V2, F2, res = fill_holes(V, F, "lssvm_poisson", **params)
    assert res["closed_holes"] == 2
    return float(np.abs(np.linalg.norm(V2[len(V):], axis=1) - 1.0).mean())


def test_normal_frame_keeps_a_sphere_cap_closer_than_the_global_frame(sphere_holes):
    # With the square Dirichlet system: per-axis regression (the paper as printed) is not
    # rotation-invariant; the curvature learnt in the normal frame is the sphere's constant one,
    # so the cap stays on the sphere.
    err = {frame: _sphere_cap_error(sphere_holes, laplacian_frame=frame, poisson_boundary="dirichlet")
           for frame in ("global", "normal")}
    assert err["normal"] < 0.6 * err["global"]
    assert err["normal"] < 0.01  # 2.9 per mille of the bounding-box diagonal 3.46 (measured 1.95; global 3.38)


def test_boundary_laplacian_rows_keep_both_frames_on_the_sphere(sphere_holes):
    # The boundary vertices' Laplacian rows (the default) carry the sphere's slope into the patch:
    # closer than the Dirichlet system in either frame.
    for frame in ("global", "normal"):
        rows = _sphere_cap_error(sphere_holes, laplacian_frame=frame)
        dirichlet = _sphere_cap_error(sphere_holes, laplacian_frame=frame, poisson_boundary="dirichlet")
        assert rows < 0.75 * dirichlet or rows < 0.005, (frame, rows, dirichlet)
        assert rows < 0.006  # measured 0.0039 (global), 0.0050 (normal)
