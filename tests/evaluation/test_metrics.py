"""evaluation.metrics: distances, quality, normals, creases, mesh checks and the corner quality bound, on cases with known answers."""
from __future__ import annotations

import warnings

import numpy as np
import pymeshlab
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.core.holes import boundary_loops
from meshlab_holefill.evaluation.comparison import MeshCase, prepare_case
from meshlab_holefill.evaluation.metrics import (assign_patches, border_dihedrals, closest_faces, closest_point_on_triangles,
                                                 corner_quality_bound, fan_triangle_quality, hausdorff_one_way,
                                                 hole_metrics, mesh_checks, sample_surface)
from meshlab_holefill.geometry.quality import triangle_quality

from conftest import cut_disks, grid as unit_grid, sample
from evaluation_meshes import grid, sphere


def _hole_setup(V, F, removed):
    """Mesh with the removed faces taken out, the hole's loop/border and its ground truth."""
    case = prepare_case(MeshCase("t", V, F, removed=removed))
    assert len(case.holes) == 1
    return case, case.holes[0]


def test_flat_hole_filled_flat_has_zero_distance_and_no_crease():
    V, F = grid()
    removed = np.linalg.norm(V[F].mean(axis=1)[:, :2] - 12.0, axis=1) < 5.0
    case, hole = _hole_setup(V, F, removed)
    # A different flat triangulation of the same hole: a fan from a new centre vertex.
    centre = case.V0[hole.loop].mean(axis=0)
    V1 = np.vstack([case.V0, centre])
    k = len(hole.loop)
    # loop is in patch orientation: a patch face holds (loop[i], loop[i+1])
    patch = np.stack([np.full(k, len(case.V0)), hole.loop, hole.loop[np.r_[1:k, 0]]], axis=1)
    metrics, arrays = hole_metrics(case.V0, case.F0, V1, patch, hole.loop, hole.border, hole.ground_truth,
                                       case.diag)
    # MeshLab's sampler works in single precision
    assert metrics["dist_patch_to_gt_max"] < 1e-6 * case.diag and metrics["dist_gt_to_patch_max"] < 1e-6 * case.diag
    assert metrics["normal_dev_max_deg"] < 1e-6
    assert metrics["border_dihedral_max_deg"] < 1e-6 and metrics["border_dihedral_excess_deg"] < 1e-6
    assert np.all(arrays["face_distance"] < 1e-9)
    assert metrics["new_vertices"] == 1 and metrics["faces"] == k


def test_equilateral_triangle_has_quality_one_and_density_ratio_one():
    V, F = grid(8, equilateral=True)
    tri = V[F]
    lengths = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=2)
    assert np.allclose(lengths, 1.0)
    removed = np.zeros(len(F), bool)
    removed[len(F) // 2 + 3] = True  # one interior triangle: a 3-edge hole
    case, hole = _hole_setup(V, F, removed)
    patch = hole.ground_truth[1]  # filled exactly with the removed triangle
    metrics, _ = hole_metrics(case.V0, case.F0, case.V0, patch, hole.loop, hole.border, hole.ground_truth,
                                  case.diag)
    assert metrics["quality_mean"] == pytest.approx(1.0) and metrics["quality_min"] == pytest.approx(1.0)
    assert metrics["quality_share07"] == 1.0 and metrics["quality_hist"][-1] == 1
    assert metrics["edge_ratio"] == pytest.approx(1.0)
    assert metrics["dist_patch_to_gt_max"] < 1e-12


def test_lifted_patch_distance_and_normal_deviation_known():
    """A flat patch lifted by h over a flat hole: distance h, then a flipped patch deviates 180 degrees."""
    V, F = grid()
    removed = np.linalg.norm(V[F].mean(axis=1)[:, :2] - 12.0, axis=1) < 5.0
    case, hole = _hole_setup(V, F, removed)
    gV, gF = hole.ground_truth
    n0 = len(case.V0)
    h = 0.25
    centre = case.V0[hole.loop].mean(axis=0) + [0, 0, h]
    V1 = np.vstack([case.V0, centre])
    k = len(hole.loop)
    fan = np.stack([np.full(k, n0), hole.loop, hole.loop[np.r_[1:k, 0]]], axis=1)
    d, _, _ = closest_faces(V1[[n0]], gV, gF)
    assert d[0] == pytest.approx(h)
    flipped = fan[:, ::-1]
    metrics, _ = hole_metrics(case.V0, case.F0, V1, flipped, hole.loop, hole.border, hole.ground_truth,
                                  case.diag)
    assert metrics["normal_dev_mean_deg"] > 170.0


def test_border_dihedral_of_a_right_angle_fold():
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, -1, 0], [0.5, 0, 1.0]])
    F_mesh = np.array([[0, 2, 1]])  # traverses edge (1, 0)
    he = np.array([[1, 0]])
    patch = np.array([[0, 1, 3]])  # traverses (0, 1): the opposite direction, as a patch must
    angle = border_dihedrals(V, F_mesh, he, np.array([0]), patch)
    assert angle[0] == pytest.approx(90.0)
    assert np.isnan(border_dihedrals(V, F_mesh, he, np.array([0]), patch[:, ::-1])[0])


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10_000))
def test_closest_point_on_triangle_beats_dense_sampling(seed):
    rng = np.random.default_rng(seed)
    T = rng.normal(size=(3, 3))
    X = rng.normal(size=(1, 3)) * 2
    P = closest_point_on_triangles(X, T[[0]], T[[1]], T[[2]])[0]
    s, t = np.meshgrid(np.linspace(0, 1, 120), np.linspace(0, 1, 120))
    ok = s + t <= 1
    samples = T[0] + s[ok, None] * (T[1] - T[0]) + t[ok, None] * (T[2] - T[0])
    sampled = np.linalg.norm(samples - X, axis=1).min()
    exact = np.linalg.norm(P - X[0])
    assert exact <= sampled + 1e-12
    assert exact >= sampled - 0.03 * np.linalg.norm(T - T.mean(axis=0), axis=1).max()


def test_patch_distance_does_not_depend_on_its_triangulation():
    """The same flat cap, as 2 triangles or split 4-fold, is the same distance from a curved truth."""
    coarse_V = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    coarse_F = np.array([[0, 1, 2], [0, 2, 3]])
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(coarse_V, coarse_F))
    ms.meshing_surface_subdivision_midpoint(iterations=2, threshold=pymeshlab.PercentageValue(0))
    fine_V, fine_F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    assert len(fine_F) == 32
    gt_V, gt_F = grid(20)[0] / 20.0, grid(20)[1]
    gt_V[:, 2] = 0.2 * np.sin(np.pi * gt_V[:, 0]) * np.sin(np.pi * gt_V[:, 1])  # a bump sharing the border
    coarse = hausdorff_one_way(coarse_V, coarse_F, gt_V, gt_F)["mean"]
    fine = hausdorff_one_way(fine_V, fine_F, gt_V, gt_F)["mean"]
    assert coarse == pytest.approx(fine, rel=0.03)
    # the surface mean of 0.2 sin(pi x) sin(pi y) over the unit square is 0.8 / pi^2 (distance ~ height here)
    assert 0.6 * 0.8 / np.pi ** 2 < coarse < 1.05 * 0.8 / np.pi ** 2


def test_patch_distance_depends_only_on_the_two_surfaces():
    """Same figures whatever was sampled before (MeshLab's sampler has one unseedable generator)."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=2)
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    ms.create_sphere(subdiv=4)
    W, G = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    first = hausdorff_one_way(V, F, W, G)
    ms.get_hausdorff_distance(sampledmesh=0, targetmesh=1)  # advances MeshLab's generator
    hausdorff_one_way(W, G, V, F, samples=777)
    assert hausdorff_one_way(V, F, W, G) == first
    assert hausdorff_one_way(V, F, W, G, seed=1) != first
    # exact distances of the seeded samples (numpy closest points, nearest-centroid candidates)
    d, _, _ = closest_faces(sample_surface(V, F, 20000), W, G)
    assert first["mean"] == pytest.approx(d.mean(), rel=1e-5)
    assert first["max"] == pytest.approx(d.max(), rel=1e-5)


def test_surface_samples_are_spread_by_area():
    V = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [3, 0, 0], [3, 1, 0]])
    F = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])  # unit square, then a 2x1 rectangle
    X = sample_surface(V, F, 30000, seed=3)
    assert np.all((X[:, 0] >= 0) & (X[:, 0] <= 3) & (X[:, 1] >= 0) & (X[:, 1] <= 1) & (X[:, 2] == 0))
    assert np.mean(X[:, 0] < 1) == pytest.approx(1 / 3, abs=0.01)
    assert np.mean(X[:, 1] < 0.5) == pytest.approx(0.5, abs=0.01)  # uniform inside each triangle too
    assert sample_surface(V, F[:0], 10).shape == (0, 3)


def _grid_with_two_cell_holes():
    """7 x 7 vertices in the unit square (spacing 1/6) with two one-cell holes: loops of 24, 4 and 4 edges."""
    V, F = unit_grid(7, 7)
    _, F, _ = cut_disks(V, F, [(0.25, 0.25, 0), (0.75, 0.75, 0)], 0.05)
    assert [lp.vertices.tolist() for lp in boundary_loops(F)][1:] == [[8, 9, 16, 15], [32, 33, 40, 39]]
    return V, F


def test_mesh_checks_of_a_clean_fill():
    V0, F0 = _grid_with_two_cell_holes()
    F1 = np.concatenate([F0, [[8, 9, 16], [8, 16, 15], [32, 33, 40], [32, 40, 39]]])
    assert mesh_checks(V0, F0, V0, F0) == {
        "originals_changed": 0, "nonmanifold_edges": 0, "boundary_edges_left": 32,
        "intersecting_new_faces": 0, "new_faces": 0, "new_vertices": 0}
    checks, hits = mesh_checks(V0, F0, V0.copy(), F1, return_hits=True)
    assert checks == {"originals_changed": 0, "nonmanifold_edges": 0, "boundary_edges_left": 24,
                      "intersecting_new_faces": 0, "new_faces": 4, "new_vertices": 0}
    assert hits.dtype == np.int64 and len(hits) == 0


def test_mesh_checks_counts_each_defect_exactly():
    V0, F0 = _grid_with_two_cell_holes()
    n, m = len(V0), len(F0)
    V1, F1 = V0.copy(), F0.copy()
    V1[46, 2] += 0.01  # one original vertex moved (on the outer border, away from the new faces)
    corner = int(np.flatnonzero((F0 == 42).any(axis=1))[0])
    F1[corner] = np.roll(F1[corner], 1)  # one original face rewritten: the same triangle, but a changed row
    fill = [[8, 9, 16], [8, 16, 15]]  # the first hole closed, the second (4 edges) left open
    # A closed tetrahedron on the interior edge 11-12 (x 4/6..5/6, y 1/6), new vertices n, n + 1
    # up in the air: that edge gets 4 faces, every other tetrahedron edge 2, no new border.
    tetra_V = [[0.75, 1 / 6 + 0.05, 0.15], [0.75, 1 / 6 - 0.05, 0.15]]
    tetra = [[11, 12, n], [12, 11, n + 1], [11, n, n + 1], [12, n + 1, n]]
    # A lone upright triangle through the middle of one face (cell x 4/6..5/6, y 2/6..3/6): 3 border edges.
    pierce_V = [[0.77, 0.36, -0.05], [0.79, 0.36, -0.05], [0.78, 0.36, 0.05]]
    pierce = [[n + 2, n + 3, n + 4]]
    V1 = np.concatenate([V1, tetra_V, pierce_V])
    F1 = np.concatenate([F1, fill, tetra, pierce])
    checks, hits = mesh_checks(V0, F0, V1, F1, return_hits=True)
    assert checks == {"originals_changed": 2,  # 1 moved vertex + 1 changed face
                      "nonmanifold_edges": 1,  # 11-12
                      "boundary_edges_left": 24 + 4 + 3,  # outer border, open hole, lone triangle
                      "intersecting_new_faces": 1,  # only the upright triangle
                      "new_faces": 2 + 4 + 1, "new_vertices": 2 + 3}
    assert hits.tolist() == [m + 2 + 4]


@settings(max_examples=30, deadline=None)
@given(st.sets(st.integers(0, 48), max_size=10), st.sets(st.integers(0, 67), max_size=10),
       st.floats(1e-9, 0.5))
def test_mesh_checks_counts_every_moved_vertex_and_changed_face(moved, rotated, shift):
    V0, F0 = _grid_with_two_cell_holes()
    assert (len(V0), len(F0)) == (49, 68)
    V1, F1 = V0.copy(), F0.copy()
    V1[sorted(moved), 2] += shift  # any move counts, however small
    F1[sorted(rotated)] = np.roll(F1[sorted(rotated)], 1, axis=1)  # same triangles, rewritten rows
    checks = mesh_checks(V0, F0, V1, F1)
    assert checks["originals_changed"] == len(moved) + len(rotated)
    assert checks["new_faces"] == checks["new_vertices"] == checks["nonmanifold_edges"] == 0


def _iso_quality(theta):
    return 8 * np.sin(theta / 2) * np.sin((np.pi - theta) / 4) ** 2


def test_iso_formula_is_the_quality_of_the_isosceles_triangle():
    for theta in np.radians([5.0, 9.6, 30.0, 60.0, 90.0, 150.0]):
        V = np.array([[0.0, 0, 0], [np.cos(-theta / 2), np.sin(-theta / 2), 0], [np.cos(theta / 2), np.sin(theta / 2), 0]])
        assert triangle_quality(V, np.array([[0, 1, 2]]))[0] == pytest.approx(_iso_quality(theta), abs=1e-12)
    assert _iso_quality(np.radians(9.3)) < 0.3 < _iso_quality(np.radians(9.4))


def test_square_hole_in_a_grid_is_bounded_by_a_fan_of_two_triangles():
    V, F = grid(10)
    centre = V[F].mean(axis=1)
    inside = np.all(np.abs(centre[:, :2] - 5.0) < 2.0, axis=1)  # a 4 x 4 square of cells
    F = F[~inside]
    hole = [lp for lp in boundary_loops(F) if len(lp) == 16][0]
    # equal edges at 90 degrees: a fan of two 45-degree isosceles triangles beats the single right triangle
    assert corner_quality_bound(V, F, hole.vertices) == pytest.approx(_iso_quality(np.pi / 4))
    assert _iso_quality(np.pi / 4) > _iso_quality(np.pi / 2)


@settings(max_examples=25, deadline=None)
@given(face=st.integers(0, 1279), stretch=st.floats(1.0, 12.0))
def test_removed_face_never_beats_the_bound(face, stretch):
    """A one-face hole: the removed face itself is a non-folding patch, so its quality <= bound."""
    V, F = sphere(3)
    V = V * np.array([stretch, 1.0, 1.0])
    keep = np.ones(len(F), bool)
    keep[face] = False
    bound = corner_quality_bound(V, F[keep], F[face])
    q = triangle_quality(V, F[[face]])[0]
    assert q <= bound + 1e-9
    # a sharp face (stretched sphere) gives a bound below the equilateral's
    if q < 0.5:
        assert bound < 1.0


def test_fan_formula_matches_triangle_quality():
    rng = np.random.default_rng(3)
    for angle, rho in zip(rng.uniform(0.05, 3.0, 20), rng.uniform(0.2, 5.0, 20)):
        V = np.array([[0.0, 0, 0], [1.0, 0, 0], [rho * np.cos(angle), rho * np.sin(angle), 0]])
        assert fan_triangle_quality(angle, rho) == pytest.approx(triangle_quality(V, np.array([[0, 1, 2]]))[0])


def test_short_edge_beside_a_long_one_at_a_sharp_corner_lowers_the_bound():
    """bunny10k_textured.obj's 8-edge hole: 29.8 degree corner between edges of ratio 4.15."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("bunny10k_textured.obj"))
    V, F = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    (hole,) = [lp for lp in boundary_loops(F) if len(lp) == 8]
    bound = corner_quality_bound(V, F, hole.vertices)
    assert bound == pytest.approx(0.146, abs=0.002)
    assert bound < _iso_quality(np.radians(29.8))



def test_a_border_edge_of_no_length_bounds_the_quality_at_zero_without_warnings():
    # Marching cubes leaves coincident vertices: a loop edge between two of them forces a degenerate triangle.
    V, F = grid(10)
    centre = V[F].mean(axis=1)
    F = F[~np.all(np.abs(centre[:, :2] - 5.0) < 2.0, axis=1)]
    hole = [lp for lp in boundary_loops(F) if len(lp) == 16][0].vertices
    V = V.copy()
    V[hole[1]] = V[hole[2]]  # a corner's neighbour moved onto the next loop vertex
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert corner_quality_bound(V, F, hole) == 0.0


@pytest.mark.parametrize("order", [(0, 1), (1, 0)])
def test_patches_of_two_holes_that_share_a_vertex_go_each_to_its_own_hole(order):
    """Two square holes of a grid touching at one corner (a pinched border): the fan of each
    touches the shared vertex, and each goes to the hole whose loop it closes, listed either way."""
    V, F = unit_grid(6, 6)  # 36 vertices, row-major, 50 faces
    at = lambda i, j: 6 * j + i  # noqa: E731
    quads = [(1, 1), (2, 2)]  # cells sharing the vertex at (2, 2)
    cell = lambda i, j: {at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)}  # noqa: E731
    inside = np.array([any(set(f) <= cell(*q) for q in quads) for f in F])
    loops = [np.array(sorted(cell(*q))) for q in quads]
    fans = [np.array([[a, b, c], [a, c, d]]) for a, b, c, d in
            ([at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)] for i, j in quads)]
    assert inside.sum() == 4 and set(loops[0]) & set(loops[1]) == {at(2, 2)}
    F_new = np.concatenate([fans[k] for k in order])
    patches = assign_patches(F_new, loops)
    for k, position in zip(order, (0, 1)):
        np.testing.assert_array_equal(patches[k], 2 * position + np.arange(2))


def test_a_ground_truth_that_meets_no_border_edge_has_no_border_dihedral_and_warns_nothing():
    """The removed surface given apart from the border (lifted off the plane, its own vertices): no
    border dihedral of it exists, so its mean is None rather than numpy's mean of an empty slice."""
    V, F = grid()
    removed = np.linalg.norm(V[F].mean(axis=1)[:, :2] - 12.0, axis=1) < 5.0
    case, hole = _hole_setup(V, F, removed)
    gV, gF = hole.ground_truth
    apart = np.vstack([gV, gV[gF.ravel()] + [0.0, 0.0, 1.0]])
    gF_apart = len(gV) + np.arange(gF.size).reshape(-1, 3)
    centre = case.V0[hole.loop].mean(axis=0)
    k = len(hole.loop)
    patch = np.stack([np.full(k, len(case.V0)), hole.loop, hole.loop[np.r_[1:k, 0]]], axis=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        metrics, _ = hole_metrics(case.V0, case.F0, np.vstack([case.V0, centre]), patch, hole.loop, hole.border,
                                  (apart, gF_apart), case.diag)
    assert metrics["gt_border_dihedral_mean_deg"] is None and metrics["border_dihedral_excess_deg"] is None
    assert metrics["dist_patch_to_gt_mean"] > 0.5  # the lifted copy is one unit above the patch
