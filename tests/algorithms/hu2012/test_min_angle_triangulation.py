"""Hu et al. Sec. III.B: the modified minimum-angle triangulation of the hole."""
import numpy as np
import pytest

from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import boundary_angles, min_angle_triangulation, normal_angle_threshold

UP = np.array([0.0, 0.0, 1.0])
# Counter-clockwise L shape seen from +z: the vertex (1, 1) is the concave one.
L_SHAPE = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]], float)


def test_convex_and_concave_vertices_of_an_l_shape():
    angle, convex = boundary_angles(L_SHAPE, np.tile(UP, (6, 1)))
    assert convex.tolist() == [True, True, True, False, True, True]
    assert np.degrees(angle).round(6).tolist() == [90, 90, 90, 270, 90, 90]


def test_the_concave_reading_flips_with_the_normal():
    # Seen from below the same loop is clockwise: every vertex swaps convexity (Eq. 2's two cases).
    _, convex = boundary_angles(L_SHAPE, np.tile(-UP, (6, 1)))
    assert convex.tolist() == [False, False, False, True, False, False]


def test_normal_angle_threshold_rule():
    tilt = lambda deg: np.array([np.sin(np.radians(deg)), 0, np.cos(np.radians(deg))])
    assert np.degrees(normal_angle_threshold(np.array([tilt(0), tilt(50)]))) == pytest.approx(45)
    assert np.degrees(normal_angle_threshold(np.array([tilt(0), tilt(80)]))) == pytest.approx(0.85 * 80)


def test_min_angle_triangulation_of_the_l_shape_cuts_convex_ears_only():
    F = min_angle_triangulation(L_SHAPE, np.tile(UP, (6, 1)))
    assert len(F) == 4
    # Every face is counter-clockwise (oriented like the loop) and the concave vertex is never an ear tip.
    P = L_SHAPE
    normals = np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])
    assert np.all(normals[:, 2] > 0)
    edges = {tuple(sorted(e)) for f in F.tolist() for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
    assert (2, 4) not in edges  # the diagonal outside the L


def test_min_angle_triangulation_prefers_the_smallest_angle():
    # A thin triangle tip at vertex 1 (the sharpest angle) must be the first ear.
    P = np.array([[0, 0, 0], [10, 0.5, 0], [0, 1, 0], [-1, 0.5, 0]], float)
    F = min_angle_triangulation(P, np.tile(UP, (4, 1)))
    assert F[0].tolist() == [0, 1, 2]


def test_min_angle_triangulation_avoids_forbidden_edges():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    F = min_angle_triangulation(square, np.tile(UP, (4, 1)), forbidden_edges=[[0, 2]])
    edges = {tuple(sorted(e)) for f in F.tolist() for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
    assert (1, 3) in edges and (0, 2) not in edges


def test_scalar_sector_test_agrees_with_the_vectorised_one():
    from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import _in_sector
    from meshlab_holefill.algorithms.hu2012.hole_guards import inside_hole_sector

    rng = np.random.default_rng(3)
    agree = 0
    for _ in range(300):
        apex, normal, prev, nxt, target = rng.normal(size=(5, 3))
        expected = bool(inside_hole_sector(apex, normal, prev, nxt, target[None])[0])
        assert _in_sector(*(x.tolist() for x in (apex, normal, prev, nxt, target))) == expected
        agree += expected
    assert 0 < agree < 300  # both outcomes occurred


# A hole's border at the corner of a subdivided box (pymeshlab's cube, midpoint-subdivided 4 times):
# it runs straight along two creases into the corner (0), whose two border neighbours already
# share a face of the mesh (the forbidden edge (1, 14)).
BOX_CORNER = np.array([[-0.5, -0.5, -0.5], [-0.4375, -0.5, -0.5], [-0.375, -0.5, -0.5], [-0.375, -0.5, -0.4375],
                       [-0.375, -0.5, -0.375], [-0.375, -0.5, -0.3125], [-0.4375, -0.5, -0.25],
                       [-0.5, -0.5, -0.1875], [-0.5, -0.4375, -0.25], [-0.5, -0.375, -0.3125],
                       [-0.5, -0.3125, -0.375], [-0.5, -0.3125, -0.4375], [-0.5, -0.3125, -0.5],
                       [-0.5, -0.375, -0.5], [-0.5, -0.4375, -0.5]])
_S, _C, _H = 0.31622776601683794, 0.9486832980505138, 0.7071067811865475
BOX_CORNER_NORMALS = np.array([[0, 0, -1], [0, 0, -1], [0, -_S, -_C], [0, -1, 0], [0, -1, 0], [0, -1, 0], [0, -1, 0],
                               [-_H, -_H, 0], [-1, 0, 0], [-1, 0, 0], [-1, 0, 0], [-1, 0, 0], [-_S, 0, -_C],
                               [0, 0, -1], [0, 0, -1]], float)


def test_a_loop_the_greedy_ear_order_cannot_close_is_closed_by_the_search():
    import importlib

    from meshlab_holefill.errors import HoleFillError

    module = importlib.import_module("meshlab_holefill.algorithms.hu2012.min_angle_triangulation")
    with pytest.raises(HoleFillError, match="no valid ear left"):  # the paper's greedy order alone
        module.greedy_ear_faces(BOX_CORNER, BOX_CORNER_NORMALS, [[1, 14]])
    for faces in (min_angle_triangulation(BOX_CORNER, BOX_CORNER_NORMALS, [[1, 14]]),
                  module.min_angle_triangulation_python(BOX_CORNER, BOX_CORNER_NORMALS, [[1, 14]])):
        assert faces.shape == (len(BOX_CORNER) - 2, 3)
        P = BOX_CORNER
        assert np.linalg.norm(np.cross(P[faces[:, 1]] - P[faces[:, 0]], P[faces[:, 2]] - P[faces[:, 0]]), axis=1).min() > 1e-3
        directed = {(int(a), int(b)) for f in faces for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}
        assert len(directed) == 3 * len(faces)  # no edge used twice in one direction: oriented
        k = len(P)
        assert all((i, (i + 1) % k) in directed for i in range(k))  # every border edge, with the loop's orientation
        assert (1, 14) not in directed and (14, 1) not in directed


def test_a_loop_that_cannot_be_closed_still_raises():
    from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import min_angle_triangulation_python
    from meshlab_holefill.errors import HoleFillError

    collinear = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], float)
    with pytest.raises(HoleFillError, match="no valid ear left"):
        min_angle_triangulation_python(collinear, np.tile(UP, (4, 1)))


def test_a_loop_without_area_has_no_plane():
    from meshlab_holefill.algorithms.hu2012.min_angle_triangulation import hole_plane_triangulation
    from meshlab_holefill.errors import HoleFillError

    there_and_back = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 0, 0.0]])
    with pytest.raises(HoleFillError, match="encloses no area"):
        hole_plane_triangulation(there_and_back)
