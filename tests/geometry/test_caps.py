"""geometry.caps: caps split open by a vertex inside the quad beside them."""
import numpy as np
from hypothesis import given, strategies as st

from meshlab_holefill.geometry.caps import split_caps
from meshlab_holefill.geometry.quality import face_normals, triangle_quality


def cap_over_diagonal(height, offset=0.0, depth=1.0):
    """A quad (0, 1) diagonal with the cap's apex ``height`` above its midpoint (shifted by ``offset`` along it)
    and the other triangle's apex ``depth`` below: triangles (0, 1, 2), (1, 0, 3)."""
    V = np.array([[0, 0, 0], [2, 0, 0], [1 + offset, height, 0], [1, -depth, 0.1]], float)
    return V, np.array([[0, 1, 2], [1, 0, 3]])


def test_a_flat_cap_gets_a_vertex_inside_the_quad_and_four_better_triangles():
    V, F = cap_over_diagonal(0.01)
    V2, F2 = split_caps(V, F, floor=0.3)
    assert len(V2) == 5 and len(F2) == 4
    np.testing.assert_allclose(V2[4], V.mean(axis=0))
    assert triangle_quality(V2, F2).min() > 10 * triangle_quality(V, F).min()
    # orientation kept: every new face turns the same way as the faces it replaces
    assert np.all(face_normals(V2, F2) @ np.array([0.0, 0.0, 1.0]) > 0)


def test_fixed_edges_candidates_and_good_triangles_are_left_alone():
    V, F = cap_over_diagonal(0.01)
    assert len(split_caps(V, F, floor=0.3, fixed_edges=np.array([[1, 0]]))[0]) == 4
    assert len(split_caps(V, F, floor=0.3, candidates=np.array([False, True]))[0]) == 4
    assert len(split_caps(V, F, floor=1e-4)[0]) == 4  # the cap is better than the floor
    good = cap_over_diagonal(0.9)
    assert split_caps(*good, floor=0.3)[1] is good[1]


def test_a_cap_on_the_border_has_no_edge_to_split():
    V = np.array([[0, 0, 0], [2, 0, 0], [1, 0.01, 0]], float)
    V2, F2 = split_caps(V, np.array([[0, 1, 2]]), floor=0.3)
    assert len(V2) == 3 and len(F2) == 1


@given(height=st.floats(1e-4, 0.2), offset=st.floats(-0.6, 0.6), depth=st.floats(0.3, 2.0))
def test_a_split_cap_is_replaced_by_four_triangles_each_better_than_the_worse_of_the_two(height, offset, depth):
    V, F = cap_over_diagonal(height, offset, depth)
    q = triangle_quality(V, F)
    V2, F2 = split_caps(V, F, floor=0.3)
    if len(V2) == len(V):
        assert np.array_equal(F2, F)
        return
    assert len(F2) == 4 and triangle_quality(V2, F2).min() > q.min()
    assert np.all(face_normals(V2, F2)[:, 2] > 0)
    edges = np.sort(np.concatenate([F2[:, [0, 1]], F2[:, [1, 2]], F2[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert counts.max() == 2 and (counts == 1).sum() == 4  # a disc: the quad's four sides are its border



def test_split_quads_puts_a_vertex_on_each_edge_and_keeps_the_orientation():
    from meshlab_holefill.geometry.caps import split_quads

    V, F = cap_over_diagonal(0.5)
    V2, F2 = split_quads(V, F, np.array([0]), np.array([1]), np.array([0]), np.array([1]), np.array([2]),
                         np.array([3]), np.array([[1.0, 0.0, 0.0]]))
    assert len(V2) == 5 and F2.tolist() == [[0, 4, 2], [1, 4, 3], [4, 1, 2], [4, 0, 3]]
    assert np.all(face_normals(V2, F2)[:, 2] > 0) and np.array_equal(F, [[0, 1, 2], [1, 0, 3]])  # F not changed
