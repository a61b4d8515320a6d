"""The scalar 3-vector helpers of the compiled kernels add as numpy does (geometry._vector_kernels)."""
import numpy as np

from meshlab_holefill.geometry._vector_kernels import dot3, norm3


def test_row_dot_and_norm_sum_as_numpy_does():
    """dot3 adds in np.einsum's order and norm3 in np.linalg.norm's, zeros' signs included."""
    rng = np.random.default_rng(3)
    X = rng.normal(size=(3000, 3)) * np.exp(3 * rng.normal(size=(3000, 1)))
    Y = rng.normal(size=(3000, 3))
    X[:300] *= rng.integers(0, 2, (300, 3))  # zeros ...
    Y[:300] *= rng.choice([-1.0, 1.0], (300, 3)) * rng.integers(0, 2, (300, 3))  # ... and negative zeros
    dots = np.array([dot3(tuple(x), tuple(y)) for x, y in zip(X, Y)])
    assert dots.tobytes() == np.einsum("ij,ij->i", X, Y).tobytes()
    T = np.stack([X[:1000], X[1000:2000], X[2000:]], axis=1)
    n = Y[:1000]
    d3 = np.array([[dot3(tuple(T[k, i]), tuple(n[k])) for i in range(3)] for k in range(1000)])
    assert d3.tobytes() == np.einsum("kij,kj->ki", T, n).tobytes()
    norms = np.array([norm3(tuple(x)) for x in X])
    assert norms.tobytes() == np.linalg.norm(X, axis=1).tobytes()
