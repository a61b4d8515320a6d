import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from meshlab_holefill.algorithms.hu2012.bilateral_filter import bilateral_filter
from meshlab_holefill.algorithms.hu2012.fairing import fair_positions
from meshlab_holefill.geometry.flips import circumcenters, min_angle_scores, relax_edges
from meshlab_holefill.geometry.laplacian import cotangent_laplacian, tangential_umbrella_smoothing, uniform_laplacian
from meshlab_holefill.geometry.pca import fit_plane, project_to_plane
from meshlab_holefill.geometry.quality import corner_angles, face_areas, triangle_quality, vertex_normals
from meshlab_holefill.geometry.refine import refine_patch, split_condition
from meshlab_holefill.geometry.topology import interior_edges
from meshlab_holefill.geometry.triangulate import triangulate_polygon
from meshlab_holefill.core.patch import HoleFillError

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
    # The points lie in the plane, so the projection is rigid: every pairwise distance is kept.
    assert np.allclose(np.linalg.norm(Q[:, None] - Q[None], axis=2), np.linalg.norm(P[:, None] - P[None], axis=2),
                       atol=1e-12)


def _unit(v):
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(lambda n: np.linalg.norm(n) > 0.1),
       st.lists(st.floats(-3, 3), min_size=3, max_size=3),
       st.lists(st.floats(-2, 2), min_size=12, max_size=12))
def test_project_to_plane_is_rigid_and_counter_clockwise_seen_from_the_normal(normal, centroid, coords):
    """The contract of pca.project_to_plane: orthonormal 2D coordinates, CCW seen from ``normal``."""
    n = _unit(normal)
    c = np.array(centroid)
    # An orthonormal basis (e1, e2) of the plane with e1 x e2 = n, built independently of pca.
    e1 = _unit(np.cross(n, [1.0, 0, 0] if abs(n[0]) < 0.9 else [0, 1.0, 0]))
    e2 = np.cross(n, e1)
    uv = np.array(coords[:8]).reshape(4, 2)
    heights = np.array(coords[8:])
    P = c + uv[:, :1] * e1 + uv[:, 1:] * e2
    Q = project_to_plane(P, c, n)
    # In-plane points: Q is a rotation of uv, so the Gram matrix (all lengths and angles) is kept.
    assert np.allclose(Q @ Q.T, uv @ uv.T, atol=1e-9)
    # A triangle counter-clockwise about n (e1 -> e2 is a positive turn) keeps twice its signed
    # area, +1, in 2D: the 2D frame is a rotation of (e1, e2), not a reflection.
    tri = np.array([c, c + e1, c + e2])
    a, b, d = project_to_plane(tri, c, n)
    assert (b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]) == pytest.approx(1.0)
    # Viewed from -n the same triangle is clockwise.
    a, b, d = project_to_plane(tri, c, -n)
    assert (b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]) == pytest.approx(-1.0)
    # Off-plane offsets along n are dropped: the projection is orthogonal.
    assert np.allclose(project_to_plane(P + heights[:, None] * n, c, n), Q, atol=1e-12)


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


def _assert_oriented_manifold(F, closed=False):
    """No directed edge twice (consistent orientation, no duplicate face), no undirected edge in
    more than two faces (exactly two when ``closed``), no face with a repeated vertex."""
    F = np.asarray(F)
    assert np.all((F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0]))
    directed = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed), "a directed edge is used twice"
    _, count = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    assert count.max() <= 2, "an edge is shared by more than two faces"
    if closed:
        assert np.all(count == 2)


def _bipyramid(k, h):
    """Closed bipyramid: equator 0..k-1 on the unit circle, apexes k = (0, 0, h), k+1 = (0, 0, -h).

    For k = 3, flat enough, every equator edge fails the swap tests (its opposite angles at the
    apexes are obtuse), and every one of them would be swapped to the same edge (k, k+1).
    """
    t = 2 * np.pi * np.arange(k) / k
    V = np.r_[np.c_[np.cos(t), np.sin(t), np.zeros(k)], [[0, 0, h], [0, 0, -h]]]
    i = np.arange(k)
    F = np.r_[np.c_[i, (i + 1) % k, np.full(k, k)], np.c_[(i + 1) % k, i, np.full(k, k + 1)]]
    return V, F


@pytest.mark.parametrize("criterion", ["sphere", "angles"])
def test_relax_edges_refuses_a_swap_that_recreates_an_existing_edge(criterion):
    """Next to valence-3 vertices: edges (1, 2) and (2, 0) fail the test, but their swap would
    create the pole-to-pole edge (3, 4), which already exists. Doing it would put (3, 4) in four
    faces (non-manifold), so nothing may change."""
    V, _ = _bipyramid(3, 0.3)
    # The triangular bipyramid after swapping its equator edge (0, 1) into (3, 4): vertices 0
    # and 1 now have valence 3 (each with neighbours 2, 3, 4: a tetrahedron-like corner).
    F = np.array([[0, 4, 3], [1, 3, 4], [1, 2, 3], [2, 1, 4], [2, 0, 3], [0, 2, 4]])
    _assert_oriented_manifold(F, closed=True)
    for max_rounds in (1, 200):
        F2, swaps = relax_edges(V, F, criterion=criterion, max_rounds=max_rounds)
        _assert_oriented_manifold(F2, closed=True)
        assert swaps == 0 and np.array_equal(F2, F)


@pytest.mark.parametrize("criterion", ["sphere", "angles"])
@pytest.mark.parametrize("h", [0.1, 0.3, 0.5])
def test_relax_edges_makes_only_one_of_two_swaps_that_create_the_same_edge(criterion, h):
    """The three equator edges of a flat triangular bipyramid share no face (their opposite angles
    at the apexes are ~120 degrees) and all would become the edge between the apexes: in one
    round only one of them may be swapped."""
    k = 3
    V, F = _bipyramid(k, h)
    F2, swaps = relax_edges(V, F, criterion=criterion, max_rounds=1)
    assert swaps == 1
    _assert_oriented_manifold(F2, closed=True)
    assert {k, k + 1} in [set(e) for e in np.concatenate([F2[:, [0, 1]], F2[:, [1, 2]]]).tolist()]
    F3, _ = relax_edges(V, F, criterion=criterion)
    _assert_oriented_manifold(F3, closed=True)


@settings(max_examples=60, deadline=None)
@given(st.integers(3, 6), st.floats(0.05, 1.0), st.sampled_from(["sphere", "angles", "min_angle"]),
       st.integers(0, 2 ** 32 - 1))
def test_relax_edges_keeps_a_closed_surface_an_oriented_manifold(k, h, criterion, seed):
    """Swapping edges of a closed surface keeps it closed, consistently oriented and manifold
    (a sphere: V - E + F = 2), whatever the criterion, on jittered bipyramids."""
    V, F = _bipyramid(k, h)
    V = V + np.random.default_rng(seed).uniform(-0.05, 0.05, V.shape)
    F2, _ = relax_edges(V, F, criterion=criterion)
    assert len(F2) == len(F)
    _assert_oriented_manifold(F2, closed=True)
    edges = np.unique(np.sort(np.concatenate([F2[:, [0, 1]], F2[:, [1, 2]], F2[:, [2, 0]]]), axis=1), axis=0)
    assert len(V) - len(edges) + len(F2) == 2


def _edge_set(F):
    return {tuple(sorted(e)) for e in np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]).tolist()}


@pytest.mark.parametrize("criterion", ["sphere", "angles", "min_angle"])
def test_relax_edges_never_creates_or_removes_a_fixed_edge(criterion):
    """A fixed edge is kept when it fails the test, and a fixed edge not in the mesh is never made."""
    # A planar quad whose diagonal (0, 1) is very long: every criterion swaps it to (2, 3).
    V = np.array([[0, 0, 0], [2, 0, 0], [1, 0.3, 0], [1, -0.3, 0]], float)
    F = np.array([[0, 1, 2], [1, 0, 3]])
    F_free, swaps = relax_edges(V, F, criterion=criterion)
    assert swaps == 1 and (2, 3) in _edge_set(F_free)
    for fixed in ([[0, 1]], [[3, 2]]):  # the current edge, or the one the swap would create
        F2, swaps = relax_edges(V, F, fixed_edges=np.array(fixed), criterion=criterion)
        assert swaps == 0 and np.array_equal(F2, F)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2 ** 32 - 1), st.sampled_from(["sphere", "angles", "min_angle"]))
def test_relax_edges_respects_fixed_edges_of_a_convex_fan(seed, criterion):
    """On a fan over a convex polygon, fix the loop, one fan diagonal, and some of the edges the
    free relaxation creates: the fixed diagonal stays and none of the forbidden edges appears."""
    rng = np.random.default_rng(seed)
    k = 12
    t = np.sort(rng.uniform(0, 2 * np.pi, k))
    P = np.stack([3 * np.cos(t), np.sin(t), np.zeros(k)], 1)
    F = np.array([[0, i, i + 1] for i in range(1, k - 1)])
    loop = np.stack([np.arange(k), (np.arange(k) + 1) % k], 1)
    free, _ = relax_edges(P, F, fixed_edges=loop, criterion=criterion)
    created = sorted(_edge_set(free) - _edge_set(F))
    forbidden = created[::2]
    kept = (0, int(rng.integers(2, k - 1)))
    F2, _ = relax_edges(P, F, fixed_edges=np.array([*loop.tolist(), kept, *forbidden]).reshape(-1, 2),
                        criterion=criterion)
    edges = _edge_set(F2)
    assert kept in edges
    assert not edges & set(forbidden)
    _assert_oriented_manifold(F2)
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


def _symmetric_fan(r0, z0, r1, z1):
    """Vertex 0 at the origin with the 1-ring (r0, 0, z0), (0, r1, z1), (-r0, 0, z0), (0, -r1, z1).

    The ring is symmetric under (x, y) -> (-x, -y), so the area-weighted normal at vertex 0 is
    exactly +z, and each neighbour's h = <n, v - q> is minus its height.
    """
    V = np.array([[0, 0, 0], [r0, 0, z0], [0, r1, z1], [-r0, 0, z0], [0, -r1, z1]], float)
    F = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]])
    movable = np.array([True, False, False, False, False])
    return V, F, movable


def _fleishman_height(ts, hs, sigma_c, sigma_s, range_term=True):
    """Height of v = 0 after one step: v - n sum(w h) / sum(w) with h = -z, i.e. sum(w z) / sum(w)."""
    ts, zs = np.asarray(ts, float), -np.asarray(hs, float)
    w = np.exp(-ts ** 2 / (2 * sigma_c ** 2) - (zs ** 2 / (2 * sigma_s ** 2) if range_term else 0))
    return float((w * zs).sum() / w.sum())


def test_bilateral_step_is_the_fleishman_weighted_average_of_the_one_ring():
    """One step moves v along n by sum(w_i h_i) / sum(w_i), w_i = exp(-t^2/2sc^2) exp(-h^2/2ss^2).

    The near neighbours (distance 1, height 0.1) and the far ones (distance 2, height 0.4) make
    the closeness and the range kernels weigh differently, so exchanging sigma_c and sigma_s (or
    dropping either kernel) changes the result.
    """
    V, F, movable = _symmetric_fan(1.0, 0.1, 2.0, 0.4)
    sigma_c, sigma_s = 1.0, 0.25
    # By hand: t^2 = 1.01 and 4.16, h = -0.1 and -0.4;
    # log w = -1.01/2 - 0.01/0.125 = -0.585 and -4.16/2 - 0.16/0.125 = -3.36.
    w_near, w_far = np.exp(-0.585), np.exp(-3.36)
    expected = (0.1 * w_near + 0.4 * w_far) / (w_near + w_far)
    assert expected == pytest.approx(0.117607, abs=1e-6)
    assert expected == pytest.approx(_fleishman_height([1.01 ** 0.5, 4.16 ** 0.5], [-0.1, -0.4], sigma_c, sigma_s))
    out = bilateral_filter(V, F, movable, sigma_c, sigma_s, iterations=1)
    assert out[0] == pytest.approx([0, 0, expected], abs=1e-12)
    assert np.array_equal(out[1:], V[1:])
    # Per-vertex widths: the moving vertex's own sigma_c, sigma_s are used, not its neighbours'.
    sc = np.array([sigma_c, 50.0, 0.01, 7.0, 3.0])
    ss = np.array([sigma_s, 0.01, 50.0, 3.0, 7.0])
    assert bilateral_filter(V, F, movable, sc, ss, iterations=1)[0] == pytest.approx([0, 0, expected], abs=1e-12)
    # Exchanging the two widths gives a clearly different point (the near neighbours dominate).
    swapped = _fleishman_height([1.01 ** 0.5, 4.16 ** 0.5], [-0.1, -0.4], sigma_s, sigma_c)
    assert abs(swapped - expected) > 0.01


def test_bilateral_range_term_downweights_a_neighbour_across_a_crease():
    """The feature-preserving kernel exp(-h^2 / 2 sigma_s^2) weighs a neighbour 0.5 along the
    normal (across a crease) less than the closeness kernel alone, so v moves less toward it,
    the less the narrower sigma_s is."""
    V, F, movable = _symmetric_fan(1.0, 0.0, 1.0, 0.5)  # two neighbours in v's plane, two 0.5 up
    sigma_c = 1.0
    t = np.sqrt([1.0, 1.25])
    closeness_only = _fleishman_height(t, [0.0, -0.5], sigma_c, 1.0, range_term=False)
    heights = []
    for sigma_s in (0.1, 0.2, 0.4, 1.0):
        # By hand: near pair w = exp(-1/2), far pair w = exp(-1.25/2 - 0.25/(2 sigma_s^2)).
        w_near, w_far = np.exp(-0.5), np.exp(-0.625 - 0.125 / sigma_s ** 2)
        expected = 0.5 * w_far / (w_near + w_far)
        out = bilateral_filter(V, F, movable, sigma_c, sigma_s, iterations=1)
        assert out[0] == pytest.approx([0, 0, expected], abs=1e-12)
        heights.append(out[0, 2])
    assert np.all(np.diff(heights) > 0) and heights[-1] < closeness_only
    assert heights[0] < 1e-3 * closeness_only  # sigma_s = 0.1: the crease is kept


def test_bilateral_guard_refuses_a_move_that_flips_a_face_of_good_quality():
    """min_quality also undoes moves that turn a face over, even when its 2r/R stays good.

    v = (0, 0, 1) is a roof over a thin rectangle (two steep faces along it) with two neighbours
    far below (z = -3) at the ends; its normal is +z by symmetry and the mean height of its ring
    is -1, so with (nearly) equal weights v moves to z = -1: the steep faces are mirrored through
    z = 0, same quality but reversed normals, and the other faces become better shaped.
    """
    V = np.array([[0, 0, 1.0], [2, 0, -3], [1, 0.2, 0], [-1, 0.2, 0], [-2, 0, -3], [-1, -0.2, 0], [1, -0.2, 0]])
    F = np.array([[0, i, i % 6 + 1] for i in range(1, 7)])
    movable = np.arange(7) == 0

    def cross(X):
        return np.cross(X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]])

    free = bilateral_filter(V, F, movable, 1e3, 1e3, iterations=1)
    assert free[0] == pytest.approx([0, 0, -1], abs=1e-4)
    flipped = np.einsum("ij,ij->i", cross(V), cross(free)) <= 0
    assert flipped.tolist() == [False, True, False, False, True, False]
    # The quality test alone would accept the move: no face drops below min(0.5, its old quality).
    assert np.all(triangle_quality(free, F) >= np.minimum(triangle_quality(V, F), 0.5))
    guarded = bilateral_filter(V, F, movable, 1e3, 1e3, iterations=1, min_quality=0.5)
    assert np.all(np.einsum("ij,ij->i", cross(V), cross(guarded)) > 0)
    assert np.array_equal(guarded, V)  # the only move was the flipping one


def test_vertex_normals_of_a_grid_point_up():
    V, F = grid(4, 4)
    assert np.allclose(vertex_normals(V, F), [0, 0, 1])


def test_vertex_normals_weigh_faces_by_area():
    """Sum of face cross products: a face of area 2 counts twice as much as one of area 1.

    Both faces have a right angle at vertex 0 and at vertex 1 the angles differ, so neither the
    unweighted mean of unit normals, (0, 1, 1)/sqrt 2, nor angle weighting gives the answer.
    """
    V = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [0, 0, 1], [5, 5, 5]], float)
    F = np.array([[0, 1, 2],   # area 2, normal +z
                  [0, 3, 1]])  # area 1, normal +y, shares edge (0, 1) with consistent orientation
    N = vertex_normals(V, F)
    both = np.array([0, 2, 4]) / np.sqrt(20)  # (0, 2, 0) + (0, 0, 4), normalised
    assert np.allclose(N[0], both) and np.allclose(N[1], both)
    assert np.allclose(N[2], [0, 0, 1]) and np.allclose(N[3], [0, 1, 0])
    assert np.array_equal(N[4], [0, 0, 0])  # a vertex without faces gets a zero normal


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
    with pytest.raises(HoleFillError, match="polygon is not simple"):
        triangulate_polygon(bowtie)


def test_constrained_triangulation_rejects_coincident_vertices_before_triangle_crashes():
    # A polygon through the same point twice (an unwelded border vertex); Triangle segfaults on it.
    pinched = np.array([[0, 0], [2, 0], [1, 1], [2, 2], [0, 2], [1, 1]], float)
    with pytest.raises(HoleFillError, match="two vertices at the same position"):
        triangulate_polygon(pinched)
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    with pytest.raises(HoleFillError, match="two vertices at the same position"):
        triangulate_polygon(square, extra_points=np.array([[0.5, 0.5], [0.5, 0.5]]))


@pytest.mark.parametrize("scale", [1e-9, 1e-4, 1.0, 1e4, 1e9])
def test_area_bounded_refinement_does_not_depend_on_the_unit(scale):
    """The area bound reaches Triangle whatever its exponent (it reads digits and '.' only)."""
    t = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    circle = np.stack([np.cos(t), np.sin(t)], axis=1)
    edge = np.linalg.norm(circle[1] - circle[0])
    P, T = triangulate_polygon(circle * scale, max_area=np.sqrt(3) / 4 * (edge * scale) ** 2, min_angle=30)
    # about pi / (sqrt(3)/4 edge^2) = 1170 triangles at unit scale; rounding of the scaled input moves it a little
    assert 1100 < len(T) < 1250
    u, w = P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]]
    area = 0.5 * np.abs(u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0])
    assert area.max() <= np.sqrt(3) / 4 * (edge * scale) ** 2 * (1 + 1e-9)
    assert area.sum() == pytest.approx(0.5 * 64 * np.sin(2 * np.pi / 64) * scale ** 2, rel=1e-9)
