"""The sort-based set operations give numpy's answers, element for element and in numpy's dtype."""
import numpy as np
import pytest

from meshlab_holefill.geometry.sets import isin_ints, positions_ints, setdiff_ints, unique_ints


@pytest.mark.parametrize("dtype", [np.int32, np.int64])
def test_set_operations_answer_as_numpy(dtype):
    rng = np.random.default_rng(3)
    for size in (0, 1, 2, 7, 300, 5000):
        x = rng.integers(-50, 10 * size + 5, size).astype(dtype).reshape(-1, 1)  # any shape is flattened
        y = rng.integers(-60, 10 * size + 60, size // 2 + 1).astype(dtype)  # values below, inside and past x's
        for got, want in ((unique_ints(x), np.unique(x)), (isin_ints(y, x), np.isin(y, x)),
                          (setdiff_ints(x, y), np.setdiff1d(x, y))):
            assert got.dtype == want.dtype and got.shape == want.shape
            np.testing.assert_array_equal(got, want)


def test_membership_keeps_the_shape_of_the_values():
    values = np.array([[1, 5], [9, 2]])
    assert isin_ints(values, [2, 9, 11]).tolist() == [[False, False], [True, True]]
    assert isin_ints(values, np.zeros(0, np.int64)).tolist() == [[False, False], [False, False]]


def test_positions_renumber_values_by_an_unordered_table():
    rng = np.random.default_rng(5)
    table = rng.permutation(np.arange(-20, 400, 3))
    values = rng.choice(table, (50, 3))
    got = positions_ints(table, values)
    assert got.shape == values.shape and got.dtype == np.int64
    np.testing.assert_array_equal(table[got], values)
