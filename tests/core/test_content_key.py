"""core.content_key: equal for equal arrays, different when a dtype, a shape or a byte differs."""
import numpy as np

from meshlab_holefill.core.content_key import content_key


def test_equal_arrays_share_a_key_and_any_difference_changes_it():
    a = np.arange(6, dtype=np.float64).reshape(2, 3)
    assert content_key(a, np.arange(3)) == content_key(a.copy(), np.arange(3))
    assert content_key(np.asfortranarray(a)) == content_key(a)  # the layout is not the content
    different = [a.astype(np.float32), a.reshape(3, 2), a.ravel(), a + 1e-300 * (a == 0)]
    assert len({content_key(a)} | {content_key(b) for b in different}) == 1 + len(different)
    assert content_key(a, a) != content_key(a)  # how many arrays counts too
