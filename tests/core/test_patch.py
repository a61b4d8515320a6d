import numpy as np
import pytest

from meshlab_holefill.core.holes import boundary_loops, nonmanifold_edges
from meshlab_holefill.core.patch import HoleFillError, Patch, merge_patches, validate_patch

SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)


def _square_hole_mesh():
    """A 3 x 3-cell grid over [-1, 2]^2 (counter-clockwise faces, normal +z) without its middle cell.

    The middle cell is SQUARE; returns V, F and the hole's loop in patch orientation (SQUARE's order).
    """
    xs = np.arange(-1.0, 3.0)
    V = np.array([[x, y, 0.0] for y in xs for x in xs])
    idx = np.arange(16).reshape(4, 4)
    F = [[idx[r, c], idx[r, c + 1], idx[r + 1, c + 1]] for r in range(3) for c in range(3) if (r, c) != (1, 1)]
    F += [[idx[r, c], idx[r + 1, c + 1], idx[r + 1, c]] for r in range(3) for c in range(3) if (r, c) != (1, 1)]
    loop = np.array([idx[1, 1], idx[1, 2], idx[2, 2], idx[2, 1]])
    assert np.array_equal(V[loop], SQUARE)
    return V, np.array(F), loop


@pytest.mark.parametrize("vertices, faces", [
    ([], [[0, 1, 2], [0, 2, 3]]),
    ([[0.5, 0.5, 0.0]], [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]),
], ids=["two triangles", "centre vertex"])
def test_valid_patch_passes_and_closes_its_hole_watertight(vertices, faces):
    patch = Patch(np.array(vertices, float).reshape(-1, 3), np.array(faces))
    before = (patch.vertices.copy(), patch.faces.copy())
    assert validate_patch(patch, SQUARE) is None  # it only raises; a valid patch is left as it is
    assert np.array_equal(patch.vertices, before[0]) and np.array_equal(patch.faces, before[1])
    # What validation promises, checked on the merged mesh: the hole is gone (only the outer
    # border is left), every edge has at most two faces, and every directed edge is used once
    # (the patch is oriented like the surrounding faces).
    V, F, loop = _square_hole_mesh()
    assert sorted(len(lp) for lp in boundary_loops(F)) == [4, 12]
    V2, F2 = merge_patches(V, F, [loop], [patch])
    assert [len(lp) for lp in boundary_loops(F2)] == [12]
    assert len(nonmanifold_edges(F2)) == 0
    directed = np.concatenate([F2[:, [0, 1]], F2[:, [1, 2]], F2[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed)
    # the patch faces up like the mesh, and covers the unit square exactly once
    T = V2[F2[len(F):]]
    normals = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    assert np.all(normals[:, 2] > 0) and normals[:, 2].sum() / 2 == pytest.approx(1.0)


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
    assert validate_patch(patch, SQUARE, forbidden_edges=[[1, 3]]) is None  # the unused diagonal is allowed


def test_merge_keeps_originals_and_maps_loop_indices():
    V = np.random.default_rng(0).normal(size=(10, 3))
    F = np.array([[0, 1, 2], [2, 3, 4]])
    loop = np.array([5, 6, 7, 8])
    patch = Patch(np.array([[9.0, 9, 9]]), np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]))
    V2, F2 = merge_patches(V, F, [loop], [patch])
    assert np.array_equal(V2[:10], V) and np.array_equal(F2[:2], F)
    assert F2[2:].tolist() == [[5, 6, 10], [6, 7, 10], [7, 8, 10], [8, 5, 10]]
    assert V2[10].tolist() == [9, 9, 9]


def _edge_failure_numpy(Fp, k, n, fe):
    """The edge checks of validate_patch in numpy (the compiled checks' reference): 0 or the failure code."""
    directed = np.concatenate([Fp[:, [0, 1]], Fp[:, [1, 2]], Fp[:, [2, 0]]])
    dkeys = directed[:, 0] * n + directed[:, 1]
    if len(np.unique(dkeys)) != len(dkeys):
        return 1
    open_edges = directed[~np.isin(dkeys, directed[:, 1] * n + directed[:, 0])]
    loop_edges = np.stack([np.arange(k), (np.arange(k) + 1) % k], axis=1)
    open_keys = np.sort(open_edges[:, 0] * n + open_edges[:, 1])
    loop_keys = np.sort(loop_edges[:, 0] * n + loop_edges[:, 1])
    if len(open_keys) != len(loop_keys) or np.any(open_keys != loop_keys):
        return 2 if np.isin(loop_edges[:, 1] * n + loop_edges[:, 0], dkeys).any() else 3
    und = np.sort(directed, axis=1)
    fe = np.sort(fe, axis=1)
    if len(fe) and np.isin(fe[:, 0] * n + fe[:, 1], und[:, 0] * n + und[:, 1]).any():
        return 4
    return 5 if n > k and len(np.unique(Fp[Fp >= k])) != n - k else 0


def test_compiled_edge_checks_answer_as_the_numpy_checks():
    from meshlab_holefill.core.patch import _edge_failure

    rng = np.random.default_rng(5)
    k = 8
    fan = np.array([[i, (i + 1) % k, k] for i in range(k)])  # a valid patch: a fan around vertex k
    codes = set()
    for trial in range(300):
        F = fan.copy()
        n = k + 1 + int(rng.integers(0, 2))  # sometimes an unused vertex
        change = trial % 5
        if change == 1:
            F[rng.integers(0, len(F))] = F[rng.integers(0, len(F)), ::-1]  # a face turned over
        elif change == 2:
            F = F[rng.random(len(F)) < 0.8]  # faces dropped
        elif change == 3:
            F = np.concatenate([F, F[rng.integers(0, len(F), 1)]])  # a face twice
        elif change == 4:
            F = rng.integers(0, n, (int(rng.integers(1, 12)), 3))  # anything
        if len(F) == 0:
            continue
        fe = rng.integers(0, k, (int(rng.integers(0, 3)), 2))
        want = _edge_failure_numpy(F, k, n, fe)
        assert _edge_failure(np.ascontiguousarray(F, np.int64), k, n, np.ascontiguousarray(fe, np.int64)) == want
        codes.add(want)
    assert codes == {0, 1, 2, 3, 4, 5}
