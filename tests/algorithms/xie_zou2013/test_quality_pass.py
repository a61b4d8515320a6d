"""HPDE's final quality pass: an operation that folds the patch is undone, not the round's others."""
import numpy as np

from meshlab_holefill.algorithms.xie_zou2013.quality_pass import raise_min_quality
from meshlab_holefill.geometry.quality import triangle_quality


def two_ear_square():
    """A 2 x 2 square, its loop 0..7 counter-clockwise; ears (0, 1, 2) and (4, 5, 6) at almost straight corners.

    The middle vertex 8 is the only free one; swapping each ear's chord onto it lifts that ear.
    """
    V = np.array([[0, 0, 0], [1, -0.02, 0], [2, 0, 0], [2, 1, 0], [2, 2, 0], [1, 2.02, 0], [0, 2, 0], [0, 1, 0],
                  [1, 1, 0]], float)
    F = np.array([[0, 1, 2], [0, 2, 8], [2, 3, 8], [3, 4, 8], [4, 5, 6], [4, 6, 8], [6, 7, 8], [7, 0, 8]])
    return V, F


def has_edge(F, a, b):
    return bool(np.any(np.isin(F, [a, b]).sum(axis=1) == 2))


def test_both_ears_are_lifted_by_swaps():
    V, F = two_ear_square()
    assert triangle_quality(V, F).min() < 0.05
    V2, F2, keep, stats = raise_min_quality(V, F, 8)
    assert has_edge(F2, 1, 8) and has_edge(F2, 5, 8)
    assert stats["swaps"] == 2 and triangle_quality(V2, F2).min() > 0.3
    assert np.array_equal(V2[:8], V[:8])


def test_an_operation_that_folds_is_undone_and_the_round_s_other_operations_kept():
    V, F = two_ear_square()

    def fold_test(V_, F_):  # stands for a fold-over that the first ear's swap would make
        return int(has_edge(F_, 1, 8))

    V2, F2, keep, stats = raise_min_quality(V, F, 8, fold_test=fold_test)
    assert not has_edge(F2, 1, 8)  # undone: the ear (0, 1, 2) stays
    assert any(sorted(f) == [0, 1, 2] for f in F2.tolist())
    assert has_edge(F2, 5, 8)  # kept: the other ear is lifted
    assert stats["swaps"] == 1
    assert fold_test(V2, F2) == 0
