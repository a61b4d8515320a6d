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


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), int32=st.booleans())
def test_faces_near_boxes_are_those_not_wholly_beyond_one_side_of_their_union(seed, int32):
    from meshlab_holefill.core.crossings import face_boxes_near

    rng = np.random.default_rng(seed)
    V = rng.random((60, 3))
    F = rng.integers(0, 60, (80, 3)).astype(np.int32 if int32 else np.int64)
    lo = rng.random((2, 3)) * 0.6
    boxes = np.stack([lo, lo + rng.random((2, 3)) * 0.4], axis=1)
    near, face_lo, face_hi = face_boxes_near(V, F, boxes)
    corners = V[F]
    union_lo, union_hi = boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)
    beyond = (corners < union_lo).all(axis=1).any(axis=1) | (corners > union_hi).all(axis=1).any(axis=1)
    assert near.tolist() == np.flatnonzero(~beyond).tolist()
    np.testing.assert_array_equal(face_lo, corners[near].min(axis=1))
    np.testing.assert_array_equal(face_hi, corners[near].max(axis=1))
