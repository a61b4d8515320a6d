import numpy as np
import pytest

from meshlab_holefill.patch import HoleFillError, Patch, merge_patches, validate_patch

SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)


def test_valid_two_triangle_patch_passes():
    validate_patch(Patch(np.zeros((0, 3)), np.array([[0, 1, 2], [0, 2, 3]])), SQUARE)


def test_patch_with_a_centre_vertex_passes():
    validate_patch(Patch(np.array([[0.5, 0.5, 0.0]]), np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])), SQUARE)


@pytest.mark.parametrize("faces, vertices, message", [
    ([[0, 2, 1], [0, 3, 2]], [], "oriented against"),
    ([[0, 1, 2]], [], "not watertight"),
    ([[0, 1, 2], [0, 2, 3], [0, 2, 3]], [], "directed edge twice"),
    ([[0, 1, 1], [0, 2, 3]], [], "repeating a vertex"),
    ([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]], [[0.5, 0.0, 0.0]], "degenerate"),
    ([[0, 1, 2], [0, 2, 3]], [[0.5, 0.5, 0.0]], "unused"),
    ([[0, 1, 9], [0, 2, 3]], [], "out of range"),
    ([], [], "no faces"),
    ([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]], [[np.nan, 0.5, 0.0]], "non-finite"),
])
def test_invalid_patches_are_rejected_with_a_reason(faces, vertices, message):
    patch = Patch(np.array(vertices, float).reshape(-1, 3), np.array(faces, int).reshape(-1, 3))
    with pytest.raises(HoleFillError, match=message):
        validate_patch(patch, SQUARE)


def test_forbidden_edge_is_rejected():
    patch = Patch(np.zeros((0, 3)), np.array([[0, 1, 2], [0, 2, 3]]))
    with pytest.raises(HoleFillError, match="existing mesh edge"):
        validate_patch(patch, SQUARE, forbidden_edges=[[2, 0]])
    validate_patch(patch, SQUARE, forbidden_edges=[[1, 3]])


def test_merge_keeps_originals_and_maps_loop_indices():
    V = np.random.default_rng(0).normal(size=(10, 3))
    F = np.array([[0, 1, 2], [2, 3, 4]])
    loop = np.array([5, 6, 7, 8])
    patch = Patch(np.array([[9.0, 9, 9]]), np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]))
    V2, F2 = merge_patches(V, F, [loop], [patch])
    assert np.array_equal(V2[:10], V) and np.array_equal(F2[:2], F)
    assert F2[2:].tolist() == [[5, 6, 10], [6, 7, 10], [7, 8, 10], [8, 5, 10]]
    assert V2[10].tolist() == [9, 9, 9]
