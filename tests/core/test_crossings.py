"""core.crossings: the candidate faces near patches, found in one pass."""
import numpy as np
from hypothesis import given, settings, strategies as st

from meshlab_holefill.core.crossings import face_boxes_near


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), n_boxes=st.integers(1, 4))
def test_face_boxes_near_matches_brute_force(seed, n_boxes):
    rng = np.random.default_rng(seed)
    V = rng.uniform(-1, 1, (60, 3))
    F = rng.integers(0, 60, (120, 3))
    centre = rng.uniform(-1, 1, (n_boxes, 3))
    half = rng.uniform(0.01, 0.5, (n_boxes, 3))
    boxes = np.stack([centre - half, centre + half], axis=1)
    near, lo, hi = face_boxes_near(V, F, boxes)
    corners = V[F]
    flo, fhi = corners.min(axis=1), corners.max(axis=1)
    union_lo, union_hi = boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)
    expected = np.flatnonzero(np.all(fhi >= union_lo, axis=1) & np.all(flo <= union_hi, axis=1))
    np.testing.assert_array_equal(near, expected)
    np.testing.assert_array_equal(lo, flo[near])
    np.testing.assert_array_equal(hi, fhi[near])
    # every face overlapping any single box is among the candidates
    for b in boxes:
        each = np.flatnonzero(np.all(fhi >= b[0], axis=1) & np.all(flo <= b[1], axis=1))
        assert np.isin(each, near).all()
