import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from meshlab_holefill.geometry.bilateral import bilateral_filter
from meshlab_holefill.geometry.fairing import fair_positions
from meshlab_holefill.geometry.flips import circumcenters, min_angle_scores, relax_edges
from meshlab_holefill.geometry.laplacian import cotangent_laplacian, tangential_umbrella_smoothing, uniform_laplacian
from meshlab_holefill.geometry.pca import fit_plane, project_to_plane
from meshlab_holefill.geometry.quality import corner_angles, face_areas, triangle_quality, vertex_normals
from meshlab_holefill.geometry.refine import refine_patch, split_condition
from meshlab_holefill.geometry.topology import interior_edges
from meshlab_holefill.geometry.triangulate import triangulate_polygon
from meshlab_holefill.patch import HoleFillError

from conftest import grid

EQUILATERAL = np.array([[0, 0, 0], [1, 0, 0], [0.5, np.sqrt(3) / 2, 0]])


def test_quality_of_equilateral_is_one_and_of_degenerate_is_zero():
    V = np.concatenate([EQUILATERAL, [[2, 0, 0]]])
    q = triangle_quality(V, np.array([[0, 1, 2], [0, 1, 3]]))
    assert q[0] == pytest.approx(1.0)
    assert q[1] == 0.0


def test_quality_of_right_isoceles_triangle():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    # r = (2 - sqrt 2)/2, R = sqrt(2)/2  =>  2r/R = 2(2 - sqrt 2)/sqrt 2
    assert triangle_quality(V, np.array([[0, 1, 2]]))[0] == pytest.approx(2 * (2 - np.sqrt(2)) / np.sqrt(2))


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(-5, 5), min_size=9, max_size=9), st.floats(0.1, 10))
def test_quality_is_scale_invariant_and_in_unit_interval(coords, s):
    V = np.array(coords).reshape(3, 3)
    F = np.array([[0, 1, 2]])
    q = triangle_quality(V, F)[0]
    assert 0.0 <= q <= 1.0
    if face_areas(V, F)[0] > 1e-6:
        assert triangle_quality(V * s, F)[0] == pytest.approx(q, rel=1e-6, abs=1e-9)
    assert corner_angles(V, F).sum() == pytest.approx(np.pi) or face_areas(V, F)[0] < 1e-9


def test_laplacians_annihilate_constants_and_cotangent_has_linear_precision():
    V, F = grid(8, 8)
    interior = np.flatnonzero((V[:, 0] > 0.01) & (V[:, 0] < 0.99) & (V[:, 1] > 0.01) & (V[:, 1] < 0.99))
    rng = np.random.default_rng(1)
    V[:, :2] += rng.uniform(-0.02, 0.02, size=(len(V), 2))
    for L in (uniform_laplacian(F, len(V)), cotangent_laplacian(V, F)):
        assert np.allclose(L @ np.ones(len(V)), 0)
        assert abs(L - L.T).max() < 1e-12
    Lc = cotangent_laplacian(V, F)
    linear = 2 * V[:, 0] - 3 * V[:, 1]
    assert np.abs((Lc @ linear)[interior]).max() < 1e-10


def test_tangential_umbrella_smoothing_evens_a_plane_within_it():
    """On a tilted plane the vertices stay in the plane and return to the regular grid."""
    V, F = grid(9, 9, z=lambda x, y: 0.3 * x + 0.2 * y)
    boundary = (V[:, 0] < 1e-9) | (V[:, 0] > 1 - 1e-9) | (V[:, 1] < 1e-9) | (V[:, 1] > 1 - 1e-9)
    rng = np.random.default_rng(4)
    shaken = V.copy()
    shaken[~boundary, :2] += rng.uniform(-0.04, 0.04, size=(int((~boundary).sum()), 2))
    shaken[:, 2] = 0.3 * shaken[:, 0] + 0.2 * shaken[:, 1]
    out = tangential_umbrella_smoothing(shaken, F, boundary, 200)
    assert np.array_equal(out[boundary], shaken[boundary])
    assert np.abs(out[:, 2] - 0.3 * out[:, 0] - 0.2 * out[:, 1]).max() < 1e-12
    # the umbrella's fixed point on this grid is the grid itself (each vertex the mean of its neighbours)
    L = uniform_laplacian(F, len(V))
    assert np.abs((L @ out)[~boundary]).max() < 1e-6
    assert np.abs(out - V).max() < 0.05 * np.abs(shaken - V).max()
    assert np.array_equal(tangential_umbrella_smoothing(shaken, F, boundary, 0), shaken)


def test_tangential_umbrella_smoothing_keeps_a_sphere_round_to_first_order():
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    fixed = V[:, 2] < 0
    out = tangential_umbrella_smoothing(V, F, fixed, 10, step=0.5)
    radius = np.linalg.norm(out, axis=1)
    moved = np.linalg.norm(out - V, axis=1)
    assert moved[~fixed].max() > 1e-3  # the sphere's triangulation is not the umbrella's fixed point
    assert np.abs(radius - 1).max() < 0.05 * moved.max()  # radial drift is second order


def test_fairing_reproduces_a_plane_and_solves_its_system():
    V, F = grid(9, 9, z=lambda x, y: 0.3 * x + 0.2 * y)
    boundary = (V[:, 0] < 1e-9) | (V[:, 0] > 1 - 1e-9) | (V[:, 1] < 1e-9) | (V[:, 1] > 1 - 1e-9)
    for order in (1, 2):
        # The thin-plate solve needs two rings of constrained vertices.
        fixed = boundary if order == 1 else boundary | (np.abs(V[:, 0] - 0.5) > 0.37) | (np.abs(V[:, 1] - 0.5) > 0.37)
        noisy = V.copy()
        noisy[~fixed, 2] += 0.2
        out = fair_positions(noisy, F, fixed, order=order)
        assert np.allclose(out, V, atol=1e-9)
        L = uniform_laplacian(F, len(V))
        residual = (L if order == 1 else L @ L) @ out
        assert np.abs(residual[~fixed]).max() < 1e-9


def test_pca_plane_of_tilted_points():
    rng = np.random.default_rng(0)
    P = rng.uniform(-1, 1, size=(50, 3))
    n = np.array([1.0, 2.0, 2.0]) / 3
    P -= np.outer(P @ n, n)
    c, normal, w, axes = fit_plane(P + 5)
    assert abs(abs(normal @ n) - 1) < 1e-12 and w[0] < 1e-14
    Q = project_to_plane(P + 5, c, normal)
    assert Q.shape == (50, 2)


@settings(max_examples=60, deadline=None)
@given(st.floats(-1.0, 3.0), st.floats(0.05, 1.5), st.floats(-1.0, 3.0), st.floats(0.05, 1.5), st.floats(-0.3, 0.3))
def test_min_angle_criterion_swaps_exactly_when_the_minimum_angle_rises(cx, cy, dx, dy, dz):
    """Xie and Zou Sec. 4.7: edge (a, b) becomes (c, d) iff that raises the pair's smallest angle."""
    V = np.array([[0, 0, 0], [2, 0, 0], [cx, cy, 0], [dx, -dy, dz]])
    F = np.array([[0, 1, 2], [1, 0, 3]])
    new = np.array([[0, 3, 2], [1, 2, 3]])
    before = corner_angles(V, F).min()
    after = corner_angles(V, new).min()
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]).sum(axis=0)
    M = np.cross(V[new[:, 1]] - V[new[:, 0]], V[new[:, 2]] - V[new[:, 0]])
    folds = np.any(M @ N <= 0)  # the quad is not convex: the other diagonal folds the pair
    F2, swaps = relax_edges(V, F, criterion="min_angle")
    if folds:
        assert swaps == 0
    else:
        assert swaps == (1 if after > before + 1e-9 else 0)
        assert corner_angles(V, F2).min() == pytest.approx(max(before, after) if swaps else before)
    o, n = min_angle_scores(V, F[:1], F[1:], new[:1], new[1:])
    assert o[0] == pytest.approx(before) and n[0] == pytest.approx(after)


def test_min_angle_criterion_never_lowers_the_smallest_angle_and_converges():
    rng = np.random.default_rng(5)
    P = rng.uniform(-1, 1, (80, 2))
    P[:, 0] *= 4  # stretched: the Delaunay triangulation of the stretched points is poor here
    from scipy.spatial import Delaunay
    F = Delaunay(P * [0.25, 1]).simplices
    V = np.c_[P, 0.05 * np.sin(P[:, 0])]
    up = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])[:, 2] < 0
    F[up] = F[up][:, [0, 2, 1]]
    F2, swaps = relax_edges(V, F, criterion="min_angle")
    assert swaps > 0
    assert corner_angles(V, F2).min() >= corner_angles(V, F).min() - 1e-12
    assert np.sort(corner_angles(V, F2).min(axis=1))[:10].sum() > np.sort(corner_angles(V, F).min(axis=1))[:10].sum()
    assert relax_edges(V, F2, criterion="min_angle")[1] == 0  # no swap left that raises an angle
    # A callable scorer with the same scores gives the same faces; one that rules all out none.
    F3, swaps3 = relax_edges(V, F, criterion=min_angle_scores)
    assert np.array_equal(F3, F2) and swaps3 == swaps
    veto = lambda V, o1, o2, n1, n2: (np.zeros(len(o1)), np.full(len(o1), -np.inf))  # noqa: E731
    assert relax_edges(V, F, criterion=veto)[1] == 0


def test_normal_cos_refuses_swaps_that_turn_a_triangle_too_far():
    # A pair bent by 108 degrees along (a, b), d above b: the swap to (c, d) raises the smallest
    # angle (0.337 -> 0.449 rad) but the new triangle (b, c, d) turns by about 73 degrees from
    # the mean normal of the old pair (cosine 0.298).
    th = np.radians(108.0)
    V = np.array([[0, 0, 0], [2, 0, 0], [0.8, 1.0, 0], [2.0, -0.7 * np.cos(th), 0.7 * np.sin(th)]])
    F = np.array([[0, 1, 2], [1, 0, 3]])
    o, n = min_angle_scores(V, F[:1], F[1:], np.array([[0, 3, 2]]), np.array([[1, 2, 3]]))
    assert n[0] > o[0] + 0.1
    assert relax_edges(V, F, criterion="min_angle", normal_cos=0.0)[1] == 1
    assert relax_edges(V, F, criterion="min_angle", normal_cos=0.5)[1] == 0
    assert relax_edges(V, F, criterion="min_angle", normal_cos=None)[1] == 1


def test_relax_edges_makes_a_planar_triangulation_delaunay():
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(0, 2 * np.pi, 30))
    P = np.stack([3 * np.cos(t), np.sin(t), np.zeros(30)], 1)  # convex, not cocircular
    F = np.array([[0, i, i + 1] for i in range(1, 29)])  # a fan: far from Delaunay
    k = 30
    loop = np.stack([np.arange(k), (np.arange(k) + 1) % k], 1)
    F2, swaps = relax_edges(P, F, fixed_edges=loop)
    assert swaps > 0 and len(F2) == len(F)
    E, f1, c1, f2, c2 = interior_edges(F2, k)
    d = F2[f2, (c2 + 2) % 3]
    cc, r = circumcenters(P, F2[f1])
    assert np.all(np.linalg.norm(P[d] - cc, axis=1) >= r * (1 - 1e-6))
    # orientation kept: all normals still +z
    assert np.all(np.cross(P[F2[:, 1]] - P[F2[:, 0]], P[F2[:, 2]] - P[F2[:, 0]])[:, 2] > 0)


def test_refinement_matches_the_boundary_density():
    k = 48
    t = np.linspace(0, 2 * np.pi, k, endpoint=False)
    P = np.stack([np.cos(t), np.sin(t), np.zeros(k)], 1)
    F = np.array([[0, i, i + 1] for i in range(1, k - 1)])
    h = 2 * np.sin(np.pi / k)
    loop = np.stack([np.arange(k), (np.arange(k) + 1) % k], 1)
    V, F2, scale, info = refine_patch(P, F, np.full(k, h), fixed_edges=loop)
    assert len(V) > k + 100  # interior filled with vertices
    assert not split_condition(V, F2, scale, np.sqrt(2))[0].any()  # converged
    E = np.concatenate([F2[:, [0, 1]], F2[:, [1, 2]], F2[:, [2, 0]]])
    lengths = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    assert 0.7 < lengths.mean() / h < 1.4
    # Splits and swaps alone do not move vertices: fair quality, not the best.
    assert triangle_quality(V, F2).mean() > 0.7


def test_bilateral_filter_pulls_a_bump_back_and_keeps_a_plane():
    V, F = grid(7, 7)
    movable = np.zeros(len(V), bool)
    centre = 24
    movable[centre] = True
    flat = bilateral_filter(V, F, movable, 0.1, 0.5, iterations=3)
    assert np.allclose(flat, V)
    bumped = V.copy()
    bumped[centre, 2] = 0.05
    out = bilateral_filter(bumped, F, movable, sigma_c=1 / 6, sigma_s=0.5 / 6, iterations=3)
    assert abs(out[centre, 2]) < 0.05 * 0.5
    assert np.array_equal(out[~movable], bumped[~movable])


def test_vertex_normals_of_a_grid_point_up():
    V, F = grid(4, 4)
    assert np.allclose(vertex_normals(V, F), [0, 0, 1])


def test_constrained_triangulation_keeps_the_polygon_and_adds_no_point():
    # An L-shaped (non-convex) polygon.
    Q = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float)
    P, T = triangulate_polygon(Q)
    assert len(P) == 6 and len(T) == 4
    edges = {tuple(sorted(e)) for t in T for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    assert all(tuple(sorted((i, (i + 1) % 6))) in edges for i in range(6))
    A = P[T]
    signed = (A[:, 1, 0] - A[:, 0, 0]) * (A[:, 2, 1] - A[:, 0, 1]) - (A[:, 2, 0] - A[:, 0, 0]) * (A[:, 1, 1] - A[:, 0, 1])
    assert np.all(signed > 0)
    P2, T2 = triangulate_polygon(Q[::-1])
    A = P2[T2]
    signed = (A[:, 1, 0] - A[:, 0, 0]) * (A[:, 2, 1] - A[:, 0, 1]) - (A[:, 2, 0] - A[:, 0, 0]) * (A[:, 1, 1] - A[:, 0, 1])
    assert np.all(signed < 0)


def test_constrained_triangulation_rejects_a_self_intersecting_polygon():
    bowtie = np.array([[0, 0], [2, 2], [2, 0], [0, 2]], float)  # edges (0,1) and (2,3) cross at (1,1)
    with pytest.raises(HoleFillError):
        triangulate_polygon(bowtie)
