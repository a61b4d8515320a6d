"""core.attributes: the interpolation weights of new vertices' attributes."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.core.attributes import _idw_weights


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10**6), sources=st.integers(1, 300), targets=st.integers(0, 400),
       scale=st.sampled_from([1e-3, 1.0, 1e4]), offset=st.sampled_from([0.0, 1e6]))
def test_idw_weights_have_the_bits_of_the_three_axis_sum(seed, sources, targets, scale, offset):
    rng = np.random.default_rng(seed)
    S = rng.normal(size=(sources, 3)) * scale + offset
    T = rng.normal(size=(targets, 3)) * scale + offset
    W = _idw_weights(S, T)
    d2 = ((T[:, None, :] - S[None, :, :]) ** 2).sum(axis=2)  # the interpolation as first written
    w = 1.0 / np.maximum(d2, 1e-300)
    assert W.shape == (targets, sources) and W.tobytes() == (w / w.sum(axis=1, keepdims=True)).tobytes()
    np.testing.assert_allclose(W.sum(axis=1), 1.0, rtol=1e-12)


def test_a_target_on_a_source_takes_its_value():
    S = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    W = _idw_weights(S, S[1:2] + [[0.0, 0.0, 1e-12]])
    assert W[0, 1] == 1.0 and W[0, 0] < 1e-20 and W[0, 2] < 1e-20
