"""Xu et al. 2013 Sec. 2.2: the LS-SVM regression (Eq. 14) and its RBF kernel."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.algorithms.xu2013.lssvm import kkt_matrix, lssvm_fit, rbf_kernel


def test_lssvm_closed_form_one_and_two_samples():
    one = lssvm_fit([0.3], [2.5], gamma=7.0, width=1.0)
    assert one.bias == pytest.approx(2.5) and one.alpha == pytest.approx([0.0])
    gamma, width, x, y = 4.0, 0.7, np.array([0.0, 1.0]), np.array([1.0, 3.0])
    kappa = math.exp(-1.0 / (2 * width * width))
    model = lssvm_fit(x, y, gamma=gamma, width=width)
    a = (y[0] - y[1]) / (2 * (1 + 1 / gamma - kappa))
    assert model.bias == pytest.approx(2.0) and model.alpha == pytest.approx([a, -a])


def test_lssvm_solves_the_kkt_system_of_eq_14():
    rng = np.random.default_rng(1)
    x, y = rng.uniform(-1, 1, 30), rng.normal(size=30)
    model = lssvm_fit(x, y, gamma=50.0, width=0.3)
    sol = np.linalg.solve(kkt_matrix(x, 50.0, 0.3), np.concatenate([[0.0], y]))
    assert model.bias == pytest.approx(sol[0]) and np.allclose(model.alpha, sol[1:])
    assert abs(model.alpha.sum()) < 1e-9  # sum a_i = 0 (Eq. 13)
    assert np.allclose(rbf_kernel(x, x, 0.3).diagonal(), 1.0)


@settings(max_examples=25, deadline=None)
@given(st.floats(-1e7, 1e7, allow_nan=False), st.floats(0.05, 2.0))
def test_rbf_kernel_depends_on_differences_only(offset, width):
    # Far from the origin (georeferenced scans) the kernel must still see the distances.
    x = np.random.default_rng(3).uniform(-1.0, 1.0, (40, 2))
    K = rbf_kernel(x, x, width)
    assert np.allclose(rbf_kernel(x + offset, x + offset, width), K, rtol=0.0, atol=1e-6)
    lssvm_fit(x[:, 0] + offset, np.sin(x[:, 0]), gamma=10.0, width=width)  # H stays positive definite


@settings(max_examples=40, deadline=None)
@given(st.integers(1, 60), st.integers(1, 60), st.floats(-6.0, 6.0), st.floats(-1e6, 1e6), st.floats(0.05, 3.0))
def test_rbf_kernel_has_the_bits_of_the_kernel_as_written(l, r, log_scale, offset, width):
    # Scalar inputs skip the (l, r, d) array and the scaling is done in place: the same numbers as
    # exp(-|x - z|^2 / (2 width^2)) written out, bit for bit, so the filter's regressions do not change.
    rng = np.random.default_rng(l * 61 + r)
    x, z = offset + 10.0 ** log_scale * rng.normal(size=l), offset + 10.0 ** log_scale * rng.normal(size=r)
    diff = x[:, None, None] - z[None, :, None]  # (l, r, 1)
    general = np.exp(-np.einsum("lrd,lrd->lr", diff, diff) / (2.0 * width * width))
    assert np.array_equal(rbf_kernel(x, z, width), general)
    assert np.array_equal(rbf_kernel(x[:, None], z[:, None], width), general)
    X, Z = np.c_[x, x[::-1]], np.c_[z, z[::-1]]  # vector inputs: the sum over d as written
    diff = X[:, None, :] - Z[None, :, :]
    general = np.exp(-np.einsum("lrd,lrd->lr", diff, diff) / (2.0 * width * width))
    assert np.array_equal(rbf_kernel(X, Z, width), general)


def test_lssvm_learns_a_known_function():
    x = np.linspace(-2, 2, 80)
    model = lssvm_fit(x, np.sin(2 * x), gamma=1e4, width=0.3)
    z = np.linspace(-1.9, 1.9, 57)
    assert np.abs(model(z) - np.sin(2 * z)).max() < 0.02
