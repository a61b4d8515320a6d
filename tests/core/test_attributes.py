"""core.attributes: new vertices' attributes interpolated from their hole's border."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.core._attribute_kernels import idw_interpolated


def _weighted_means(S, T, A):
    """The interpolation in numpy: the (t, s) inverse-squared-distance weights, normalised, times the values."""
    d2 = ((T[:, None, :] - S[None, :, :]) ** 2).sum(axis=2)
    w = 1.0 / np.maximum(d2, 1e-300)
    return (w / w.sum(axis=1, keepdims=True)) @ A


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10**6), sources=st.integers(1, 300), targets=st.integers(0, 400),
       columns=st.integers(1, 6), scale=st.sampled_from([1e-3, 1.0, 1e4]), offset=st.sampled_from([0.0, 1e6]))
def test_idw_interpolation_is_the_numpy_weighted_mean_to_rounding(seed, sources, targets, columns, scale, offset):
    rng = np.random.default_rng(seed)
    S = rng.normal(size=(sources, 3)) * scale + offset
    T = rng.normal(size=(targets, 3)) * scale + offset
    A = rng.uniform(-1.0, 1.0, (sources, columns))
    got = idw_interpolated(S, T, A)
    assert got.shape == (targets, columns)
    # the sums are taken in another order than numpy's pairwise sum and BLAS's product: last bits only
    np.testing.assert_allclose(got, _weighted_means(S, T, A), rtol=0, atol=1e-13)
    # a weighted mean: within the values' range, and a constant stays that constant (to rounding)
    assert np.all(got >= A.min(axis=0) - 1e-13) and np.all(got <= A.max(axis=0) + 1e-13)
    np.testing.assert_allclose(idw_interpolated(S, T, np.full((sources, 1), 0.25)), 0.25, rtol=1e-14)


def test_a_target_on_a_source_takes_its_value():
    S = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    A = np.array([[0.1, 7.0], [0.5, 8.0], [0.9, 9.0]])
    assert idw_interpolated(S, S[1:2] + [[0.0, 0.0, 1e-12]], A).tolist() == [[0.5, 8.0]]
    assert idw_interpolated(S, S[2:3].copy(), A).tolist() == [[0.9, 9.0]]  # at distance 0: weight 1e300
