"""Xu et al. 2013: boundary pre-treatment, advancing front, training set, LS-SVM, Poisson, and the filter."""
import math

import numpy as np
import pymeshlab
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.algorithms.xu2013 import lssvm_poisson as xu
from meshlab_holefill.algorithms.xu2013 import laplacian_regression as lr
from meshlab_holefill.algorithms.xu2013 import poisson_patch as pp
from meshlab_holefill.algorithms.xu2013 import poisson_reconstruction as pr
from meshlab_holefill.algorithms.xu2013.lssvm import kkt_matrix, lssvm_fit, rbf_kernel
from meshlab_holefill.algorithms.xu2013.poisson_patch import normalized_cotangent_laplacian
from meshlab_holefill.algorithms.xu2013.advancing_front import advancing_front_triangulation
from meshlab_holefill.algorithms.xu2013._front_predicates import front_angle
from meshlab_holefill.algorithms.xu2013.border_split import split_long_boundary_edges
from meshlab_holefill.geometry.intersections import faces_intersecting
from meshlab_holefill.geometry.quality import face_areas, triangle_quality
from meshlab_holefill.core.holes import boundary_loops, hole_context, nonmanifold_edges
from meshlab_holefill.core.patch import HoleFillError, Patch, validate_patch

from conftest import assert_filled_cleanly, cut_disks, grid, mesh_arrays, meshset_from_arrays, sample

NAME = "meshing_close_holes_lssvm_poisson"
UP = (0.0, 0.0, 1.0)


def circle(k, radius=1.0, z=0.0):
    t = np.linspace(0.0, 2.0 * np.pi, k, endpoint=False)
    return np.stack([radius * np.cos(t), radius * np.sin(t), np.full(k, z)], axis=1)


def sphere_hole(center=(0.0, 0.0, 1.0), radius=0.45, subdiv=4):
    """Unit sphere (pymeshlab) with the faces near ``center`` removed: (V, F, removed faces)."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=subdiv)
    V, F = mesh_arrays(ms)
    return cut_disks(V, F, np.asarray([center], float), radius)


def context_of(V, F, inside=None, rings=xu.RINGS):
    """HoleContext of the mesh's only hole, or of the loop whose vertices all satisfy ``inside``."""
    loops = boundary_loops(F)
    if inside is not None:
        loops = [lp for lp in loops if inside(V[lp.vertices]).all()]
    assert len(loops) == 1
    return hole_context(V, F, loops[0], rings=rings)


def surface_area(V, F):
    return float(face_areas(V, F).sum())


# ------------------------------------------------------------------ Sec. 3.1 boundary pre-treatment

def annulus_with_long_hole_edge():
    """Flat mesh of a square with a square hole whose right side is one edge (4x the others)."""
    import triangle

    inner = [[0.3 + 0.1 * i, 0.3] for i in range(4)] + [[0.7, 0.7]] + [[0.7 - 0.1 * i, 0.7] for i in range(1, 5)] \
        + [[0.3, 0.7 - 0.1 * i] for i in range(1, 4)]
    outer = [[0, 0], [1, 0], [1, 1], [0, 1]]
    pts = np.array(outer + inner, float)
    segs = [[i, (i + 1) % 4] for i in range(4)] + [[4 + i, 4 + (i + 1) % len(inner)] for i in range(len(inner))]
    out = triangle.triangulate({"vertices": pts, "segments": segs, "holes": [[0.5, 0.5]]}, "pqa0.01Y")
    V2, F = out["vertices"], out["triangles"].astype(np.int64)
    A = V2[F]
    ccw = (A[:, 1, 0] - A[:, 0, 0]) * (A[:, 2, 1] - A[:, 0, 1]) - (A[:, 2, 0] - A[:, 0, 0]) * (A[:, 1, 1] - A[:, 0, 1])
    F[ccw < 0] = F[ccw < 0][:, [0, 2, 1]]
    return np.column_stack([V2, np.zeros(len(V2))]), F


def test_boundary_split_halves_long_edges_and_keeps_the_surface():
    V, F = annulus_with_long_hole_edge()
    loops = boundary_loops(F)
    hole = next(lp for lp in loops if np.allclose(V[lp.vertices].min(axis=0)[:2], 0.3))
    assert len(loops) == 2
    P = V[hole.vertices]
    lengths = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)
    ref = split_long_boundary_edges(V, F, [hole], factor=1.5)
    # An edge of length l is halved until its parts are <= k L_ave: 2^d - 1 new vertices.
    limit = 1.5 * lengths.mean()
    depth = np.ceil(np.log2(np.maximum(lengths / limit, 1.0))).astype(int)
    assert ref.split_edges == int(np.sum(2 ** depth - 1)) >= 1
    # Original vertices bit-exact and first; new vertices are the midpoints of original edges.
    assert np.array_equal(ref.V[:len(V)], V)
    a, b = ref.edge_vertices.T
    assert np.allclose(ref.V[len(V):], (1 - ref.edge_weights[:, None]) * V[a] + ref.edge_weights[:, None] * V[b])
    steps = ref.edge_weights * 2 ** depth.max()
    assert np.allclose(steps, np.round(steps)) and len(np.unique(steps)) == ref.split_edges
    # Each original face is exactly covered by its children.
    areas = face_areas(ref.V, ref.F)
    assert np.allclose(np.bincount(ref.face_parents, weights=areas, minlength=len(F)), face_areas(V, F))
    assert surface_area(ref.V, ref.F) == pytest.approx(surface_area(V, F))
    # The refined loop is a boundary loop of the refined mesh, with no edge above k * L_ave left.
    new_loop = ref.loops[0]
    Q = ref.V[new_loop.vertices]
    assert np.linalg.norm(np.roll(Q, -1, axis=0) - Q, axis=1).max() <= 1.5 * lengths.mean() + 1e-12
    assert sorted(new_loop.vertices.tolist()) in [sorted(lp.vertices.tolist()) for lp in boundary_loops(ref.F)]
    assert len(nonmanifold_edges(ref.F)) == 0
    # Border faces of the refined loop hold its edges (patch orientation reversed).
    for i, f in enumerate(new_loop.border_faces):
        u, v = new_loop.vertices[i], new_loop.vertices[(i + 1) % len(new_loop)]
        face = ref.F[f].tolist()
        j = face.index(v)
        assert face[(j + 1) % 3] == u


def test_refined_mesh_attributes_interpolate_vertices_and_copy_faces():
    from meshlab_holefill.core.attributes import MeshArrays, refine_mesh_arrays

    V, F = annulus_with_long_hole_edge()
    hole = next(lp for lp in boundary_loops(F) if np.allclose(V[lp.vertices].min(axis=0)[:2], 0.3))
    rng = np.random.default_rng(0)
    arrays = MeshArrays(V=V, F=F, vertex_attrs={"color": rng.random((len(V), 4)), "quality": rng.random((len(V), 1))},
                        face_attrs={"color": rng.random((len(F), 4)), "selected": np.ones((len(F), 1))})
    ref = split_long_boundary_edges(V, F, [hole], factor=1.5)
    out = refine_mesh_arrays(arrays, ref)
    a, b = ref.edge_vertices.T
    t = ref.edge_weights[:, None]
    for name in ("color", "quality"):
        A = arrays.vertex_attrs[name]
        assert np.array_equal(out.vertex_attrs[name][:len(V)], A)
        expected = (1 - t) * A[a] + t * A[b]
        if name == "color":  # stored as bytes by MeshLab: rounded to the nearest k / 255
            expected = np.round(expected * 255) / 255
        assert np.allclose(out.vertex_attrs[name][len(V):], expected)
    assert np.array_equal(out.face_attrs["color"], arrays.face_attrs["color"][ref.face_parents])
    assert out.face_attrs["selected"].all() and np.array_equal(out.V, ref.V)


def test_boundary_split_repeats_until_no_edge_changes():
    # One edge 8 times the others': split into 8 (three rounds of halving) with limit k * L_ave.
    P = np.array([[0, 0, 0], [8, 0, 0], [8, 1, 0], [0, 1, 0]] + [[x, 1, 0] for x in ()], float)
    V = np.concatenate([P, [[4, -1, 0]]])
    F = np.array([[1, 0, 4]])  # one border triangle below the long edge (0, 1)
    loops = boundary_loops(F)
    ref = split_long_boundary_edges(V, F, loops, factor=1.0)
    Q = ref.V[ref.loops[0].vertices]
    lengths = np.linalg.norm(np.roll(Q, -1, axis=0) - Q, axis=1)
    assert lengths.max() <= np.linalg.norm(V[[0, 1, 4]] - V[[1, 4, 0]], axis=1).mean() + 1e-12
    assert surface_area(ref.V, ref.F) == pytest.approx(surface_area(V, F))


def test_split_run_keeps_original_vertices_and_covers_the_original_surface(bunny_scan):
    V0, F0 = mesh_arrays(bunny_scan)
    m0 = bunny_scan.current_mesh()
    color0, wedge0 = m0.face_color_matrix(), m0.wedge_tex_coord_matrix().reshape(-1, 3, 2)
    res = getattr(bunny_scan, NAME)(newfaceselected=False)
    assert res["split_boundary_edges"] > 0 and res["closed_holes"] == 5
    assert sum(h.get("split_boundary_edges", 0) for h in res["holes"]) == res["split_boundary_edges"]
    V1, F1 = mesh_arrays(bunny_scan)
    m1 = bunny_scan.current_mesh()
    assert np.array_equal(V1[:len(V0)], V0)  # bit-exact, same order
    s = res["split_boundary_edges"]
    originals = np.concatenate([F1[:len(F0)], F1[len(F0):len(F0) + s]])
    assert surface_area(V1, originals) == pytest.approx(surface_area(V0, F0), rel=1e-12)
    changed = np.flatnonzero(np.any(F1[:len(F0)] != F0, axis=1))
    assert 0 < len(changed) <= s
    untouched = np.setdiff1d(np.arange(len(F0)), changed)
    assert np.array_equal(m1.face_color_matrix()[untouched], color0[untouched])
    # Split faces keep their parent's colour; their texture coordinates are the parent's interpolated.
    assert np.allclose(m1.face_color_matrix()[changed], color0[changed])
    wedge1 = m1.wedge_tex_coord_matrix().reshape(-1, 3, 2)
    midpoints = 0
    for f in changed:
        parent = F0[f].tolist()
        for corner in range(3):
            v = F1[f, corner]
            if v < len(V0):
                assert np.allclose(wedge1[f, corner], wedge0[f, parent.index(v)])
            else:  # a new boundary vertex on an edge of the parent: interpolated coordinate
                edge = [c for c in range(3) if np.allclose(
                    np.linalg.norm(V1[v] - V0[parent[c]]) + np.linalg.norm(V1[v] - V0[parent[(c + 1) % 3]]),
                    np.linalg.norm(V0[parent[c]] - V0[parent[(c + 1) % 3]]))]
                c = edge[0]
                t = np.linalg.norm(V1[v] - V0[parent[c]]) / np.linalg.norm(V0[parent[(c + 1) % 3]] - V0[parent[c]])
                assert np.allclose(wedge1[f, corner], (1 - t) * wedge0[f, c] + t * wedge0[f, (c + 1) % 3])
                midpoints += 1
    assert midpoints > 0
    assert res["new_faces"] == len(F1) - len(F0) - s


def test_split_off_keeps_original_faces_bit_exact(bunny_scan):
    V0, F0 = mesh_arrays(bunny_scan)
    res = getattr(bunny_scan, NAME)(split_boundary=False)
    V1, F1 = mesh_arrays(bunny_scan)
    assert res["split_boundary_edges"] == 0 and res["closed_holes"] == 5
    assert np.array_equal(V1[:len(V0)], V0) and np.array_equal(F1[:len(F0)], F0)


# ------------------------------------------------------------------ Sec. 3.2 advancing front

def test_front_angle_convex_reflex_and_collinear():
    # Front p -> v -> q, the uncovered side on the left (seen from the normal side).
    assert math.degrees(front_angle((0, 0, 0), (-1, 0, 0), (0, 1, 0), UP)[0]) == pytest.approx(90)
    assert math.degrees(front_angle((0, 0, 0), (0, 1, 0), (-1, 0, 0), UP)[0]) == pytest.approx(270)
    assert math.degrees(front_angle((0, 0, 0), (0, 1, 0), (-1, 0, 0), (0, 0, -1))[0]) == pytest.approx(90)
    theta, m = front_angle((0, 0, 0), (-1, 0, 0), (1, 0, 0), UP)
    assert math.degrees(theta) == pytest.approx(180) and np.allclose(m, UP)


def first_step(P):
    """Apply the advancing front's first step; returns (rule, faces added, vertices added)."""
    from xu2013_front_oracle import PythonFront

    front = PythonFront(np.asarray(P, float), UP, (), 0.75, 10_000)
    node = front._pop()
    before = dict(front.stats)
    assert front._advance(node)
    rule = next(r for r in (1, 2, 3) if front.stats[f"rule{r}"] > before[f"rule{r}"])
    return rule, len(front.faces), len(front.P) - len(P)


@pytest.mark.parametrize("k, rule, faces, new_vertices", [
    (3, 1, 1, 0),    # 60 degrees <= 75: one triangle joining the neighbours
    (6, 2, 2, 1),    # 120 degrees: one vertex on the bisector (the centre), two triangles
    (30, 3, 3, 2),   # 168 degrees > 135: two vertices trisecting the angle, three triangles
])
def test_angle_rules_of_fig_3(k, rule, faces, new_vertices):
    assert first_step(circle(k)) == (rule, faces, new_vertices)


def test_rule_two_merges_with_the_opposite_corner_of_a_square():
    nv, F, stats = advancing_front_triangulation(circle(4))
    assert len(F) == 2 and len(nv) == 0 and stats["merges"] == 1


def test_merge_may_not_close_a_wide_neighbour_angle_by_an_ear():
    # Rule 2 at v (100 degrees) puts its vertex on u, the vertex beyond p: the triangle (p, v, u)
    # would keep p's whole 122-degree front angle (quality < 0.5). The merge is refused (Step 4),
    # so v falls back to the next rule; without the limit the merge goes through.
    import math

    from meshlab_holefill.algorithms.xu2013.advancing_front import MERGE_EAR_MAX
    from xu2013_front_oracle import PythonFront

    p = 0.1 * np.array([math.cos(math.radians(100)), math.sin(math.radians(100)), 0.0])
    u = 0.65 * np.array([math.cos(math.radians(50)), math.sin(math.radians(50)), 0.0])
    P = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], u, p])
    front = PythonFront(P, UP, (), 0.75, 1000)
    assert front.node_theta[3] > MERGE_EAR_MAX and front.node_theta[0] < math.radians(135)
    assert front._build(0, 2) is None
    free = PythonFront(P, UP, (), 0.75, 1000, None, 4 * math.pi)
    faces, new_pos, sequence = free._build(0, 2)
    assert new_pos == {} and sequence == [2] and (3, 0, 2) in faces


def test_swaps_do_not_cut_off_a_worse_ear():
    # Boundary p, v, q with a 146-degree corner at v, inner vertex c: swapping (v, c) to (p, q)
    # would leave the ear (p, v, q), worse than the two triangles it replaces.
    from meshlab_holefill.algorithms.xu2013.poisson_patch import _ear_guard

    V = np.array([[-1.0, 0.0, 0.0], [0.0, 0.3, 0.0], [1.0, 0.0, 0.0], [0.0, -0.6, 0.0]])
    F = np.array([[0, 3, 1], [1, 3, 2]])
    A, B, replaced = np.array([[0, 3, 2]]), np.array([[1, 0, 2]]), np.array([[0, 1]])
    assert triangle_quality(V, B).min() < triangle_quality(V, F).min()
    assert not _ear_guard(3)(V, F, A, B, replaced)[0]   # p, v, q on the hole boundary: refused
    assert _ear_guard(0)(V, F, A, B, replaced)[0]       # inner vertices: left to the Delaunay test
    V2 = np.array([[-1.0, 0.0, 0.0], [0.0, 1.5, 0.0], [1.0, 0.0, 0.0], [0.0, -1.5, 0.0]])
    # A 67-degree corner: the ear is better than the thin pair it replaces, the swap may go.
    assert triangle_quality(V2, B).min() > triangle_quality(V2, F).min()
    assert _ear_guard(3)(V2, F, A, B, replaced)[0]


def test_new_vertices_lie_in_the_plane_of_the_two_front_edges():
    # A non-planar boundary: the first (rule 3) step puts its vertices in the plane of p, v, q.
    from xu2013_front_oracle import PythonFront

    P = circle(30)
    P[:, 2] = 0.2 * P[:, 0] ** 2
    front = PythonFront(P, UP, (), 0.75, 10_000)
    node = front._pop()
    v, p, q = (front.node_vertex[node], front.node_vertex[front.node_prev[node]],
               front.node_vertex[front.node_next[node]])
    assert front._advance(node) and len(front.P) > len(P)
    n = np.cross(P[q] - P[v], P[p] - P[v])
    for w in front.P[len(P):]:
        assert abs(np.dot(np.asarray(w) - P[v], n)) < 1e-12 * np.linalg.norm(n)


@pytest.mark.parametrize("k", [8, 30, 80])
def test_planar_circle_is_covered_with_good_triangles(k):
    P = circle(k)
    nv, F, stats = advancing_front_triangulation(P)
    X = np.concatenate([P, nv])
    validate_patch(Patch(nv, F), P)
    assert np.all(np.abs(nv[:, 2]) < 1e-12)  # in the plane of the edges
    q = triangle_quality(X, F)
    assert q.mean() > 0.85 and q.min() > 0.2
    assert len(faces_intersecting(X, F, np.arange(len(F)), np.arange(len(F)))) == 0
    # Density like the boundary's: about as many triangles as an equilateral mesh of that edge.
    h = 2 * np.pi / k
    assert len(F) < 1.5 * np.pi / (np.sqrt(3) / 4 * h * h) + k


@settings(max_examples=40, deadline=None)
@given(k=st.integers(5, 60), lobes=st.integers(2, 6), amplitude=st.floats(0.0, 0.35),
       phase=st.floats(0.0, 6.28), tilt=st.floats(-0.3, 0.3))
def test_star_shaped_holes_close_without_overlap(k, lobes, amplitude, phase, tilt):
    t = np.linspace(0, 2 * np.pi, k, endpoint=False)
    r = 1 + amplitude * np.sin(lobes * t + phase)
    P = np.stack([r * np.cos(t), r * np.sin(t), tilt * r * np.cos(t) ** 2], axis=1)
    nv, F, _ = advancing_front_triangulation(P)
    X = np.concatenate([P, nv])
    validate_patch(Patch(nv, F), P)
    assert len(faces_intersecting(X, F, np.arange(len(F)), np.arange(len(F)))) == 0


@settings(max_examples=30, deadline=None)
@given(k=st.integers(8, 120), lobes=st.integers(2, 6), amplitude=st.floats(0.0, 0.35),
       saddle=st.floats(0.0, 0.3), phase=st.floats(0.0, 6.28))
def test_closing_fronts_stay_well_inside_the_triangle_bound(k, lobes, amplitude, saddle, phase):
    # The default bound stops fronts that left the hole early; one that closes (here star-shaped and
    # saddle-shaped loops, whose surface the vector area underestimates) uses under half of it.
    from meshlab_holefill.algorithms.xu2013.advancing_front import FACE_BOUND

    t = np.linspace(0, 2 * np.pi, k, endpoint=False)
    r = 1 + amplitude * np.sin(lobes * t + phase)
    P = np.stack([r * np.cos(t), r * np.sin(t), saddle * r * np.cos(2 * t)], axis=1)
    Q = P - P[0]
    area = np.linalg.norm(0.5 * np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0))
    h = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1).mean()
    bound = FACE_BOUND * area / (0.43 * h * h) + 10 * k + 100
    nv, F, _ = advancing_front_triangulation(P)
    assert len(F) < 0.5 * bound


def test_self_crossing_boundary_fails_clearly():
    # A figure-eight: no valid disk patch exists; the front runs out of the loop's ball and is stopped.
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    P = np.stack([np.sin(t), np.sin(t) * np.cos(t), np.zeros_like(t)], axis=1)
    P[:, 2] = 1e-3 * np.cos(t)
    with pytest.raises(HoleFillError, match="advancing front left the hole: a new vertex lies more than .* loop's radius"):
        advancing_front_triangulation(P)


def test_steps_that_cross_the_surrounding_mesh_are_rejected():
    from xu2013_front_oracle import PythonFront

    P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    wall = np.array([[0.5, 0.5, -1], [0.9, 0.1, -1], [0.7, 0.3, 1.0]], float)  # pierces triangle (0, 1, 2)
    front = PythonFront(P, UP, (), 0.75, 100, (np.concatenate([P, wall]), np.array([[4, 5, 6]])))
    corners = lambda f: [[tuple(P[x]) for x in f]]  # noqa: E731
    assert front.obstacles.crossed([(0, 1, 2)], corners((0, 1, 2)))
    assert not front.obstacles.crossed([(0, 2, 3)], corners((0, 2, 3)))
    assert front.obstacles.tests == 2
    # A new vertex hovering right over a mesh face is refused too.
    assert front.obstacles.distance((0.7, 0.3, 0.0), 0.1) < 0.01
    assert front.obstacles.distance((0.2, 0.8, 0.0), 0.1) == 0.1  # nothing within reach


def test_refused_nodes_far_from_a_step_stay_refused_without_changing_the_patch(monkeypatch):
    # After a step only the refused nodes within the reach of its checks are retried
    # (_release_blocked_near); retrying every refused node must give the same patches. On
    # bunny10k_textured one hole's front refuses 35 steps, 2 of them kept back after far steps.
    # The retry-all run is the Python reference front (xu2013_front_oracle) with that change.
    import xu2013_front_oracle as oracle
    from meshlab_holefill.algorithms.xu2013 import poisson_patch

    def run():
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(sample("bunny10k_textured.obj"))
        res = ms.meshing_close_holes_lssvm_poisson(workers=1)
        return mesh_arrays(ms), res["holes"]

    (V1, F1), holes = run()
    kept = sum(h.get("afm_kept_blocked") or 0 for h in holes)
    assert kept > 0
    monkeypatch.setattr(oracle.PythonFront, "_release_blocked_near", lambda self, new_faces: self._release_blocked())
    monkeypatch.setattr(poisson_patch, "advancing_front_triangulation", oracle.oracle_triangulation)
    (V2, F2), holes_full = run()
    assert np.array_equal(V1, V2) and np.array_equal(F1, F2)
    assert sum(h.get("afm_kept_blocked") or 0 for h in holes_full) == 0


def test_front_that_runs_out_of_the_hole_stops():
    # The outer border of a flat grid, read as a hole, is the plane outside the square: with
    # the surface normals the front grows outward without end; it must stop with a reason.
    from meshlab_holefill.algorithms.xu2013.poisson_patch import reference_normals

    V, F = grid(10, 10)
    ctx = hole_context(V, F, boundary_loops(F)[0], rings=2)
    with pytest.raises(HoleFillError, match="left the hole|did not close|stuck"):
        advancing_front_triangulation(ctx.points, reference_normal=reference_normals(ctx),
                                      obstacles=(ctx.vertices, ctx.faces))


# ------------------------------------------------------------------ Sec. 2.1, 3.3 Laplacian and training set

def test_normalised_cotangent_laplacian_rows():
    V, F = grid(6, 6, z=lambda x, y: 0.3 * x * y)
    L = normalized_cotangent_laplacian(V, F)
    assert np.allclose(np.asarray(L.sum(axis=1)).ravel(), 0.0)  # Eq. 6: w_ij sum to 1, L_ii = -1
    assert np.allclose(L.diagonal(), -1.0)
    flat, _ = grid(6, 6)
    inner = np.flatnonzero((flat[:, 0] > 0) & (flat[:, 0] < 1) & (flat[:, 1] > 0) & (flat[:, 1] < 1))
    assert np.allclose((normalized_cotangent_laplacian(flat, F) @ flat)[inner], 0.0)  # planar: delta = 0


def test_training_set_is_k_layers_with_laplacians_toward_the_centre():
    V, F, _ = sphere_hole()
    ctx = context_of(V, F)
    for layers in (1, 2, 3):
        X, delta = lr.training_set(ctx, layers)
        assert len(X) == np.count_nonzero((ctx.depth >= 1) & (ctx.depth <= layers))
        # On the unit sphere the cotangent Laplacian points to the centre (mean curvature normal).
        assert np.all(np.einsum("ij,ij->i", delta, X) < 0)
        cosines = -np.einsum("ij,ij->i", delta, X) / np.linalg.norm(delta, axis=1)
        assert cosines.min() > 0.95
    assert len(lr.training_set(ctx, 2)[0]) > len(lr.training_set(ctx, 1)[0])


# ------------------------------------------------------------------ Sec. 2.2 LS-SVM

def test_lssvm_closed_form_one_and_two_samples():
    one = lssvm_fit([0.3], [2.5], gamma=7.0, width=1.0)
    assert one.bias == pytest.approx(2.5) and one.alpha == pytest.approx([0.0])
    gamma, width, x, y = 4.0, 0.7, np.array([0.0, 1.0]), np.array([1.0, 3.0])
    kappa = math.exp(-1.0 / (2 * width * width))
    model = lssvm_fit(x, y, gamma=gamma, width=width)
    a = (y[0] - y[1]) / (2 * (1 + 1 / gamma - kappa))
    assert model.bias == pytest.approx(2.0) and model.alpha == pytest.approx([a, -a])


def test_lssvm_solves_the_kkt_system_of_eq_14():
    rng = np.random.default_rng(1)
    x, y = rng.uniform(-1, 1, 30), rng.normal(size=30)
    model = lssvm_fit(x, y, gamma=50.0, width=0.3)
    sol = np.linalg.solve(kkt_matrix(x, 50.0, 0.3), np.concatenate([[0.0], y]))
    assert model.bias == pytest.approx(sol[0]) and np.allclose(model.alpha, sol[1:])
    assert abs(model.alpha.sum()) < 1e-9  # sum a_i = 0 (Eq. 13)
    assert np.allclose(rbf_kernel(x, x, 0.3).diagonal(), 1.0)


@settings(max_examples=25, deadline=None)
@given(st.floats(-1e7, 1e7, allow_nan=False), st.floats(0.05, 2.0))
def test_rbf_kernel_depends_on_differences_only(offset, width):
    # Far from the origin (georeferenced scans) the kernel must still see the distances.
    x = np.random.default_rng(3).uniform(-1.0, 1.0, (40, 2))
    K = rbf_kernel(x, x, width)
    assert np.allclose(rbf_kernel(x + offset, x + offset, width), K, rtol=0.0, atol=1e-6)
    lssvm_fit(x[:, 0] + offset, np.sin(x[:, 0]), gamma=10.0, width=width)  # H stays positive definite


def test_mesh_far_from_the_origin_is_filled_as_well_as_at_the_origin():
    from meshlab_holefill import array_api
    from conftest import sphere_with_holes

    V, F, _ = sphere_with_holes()
    offset = np.array([1e8, -2e7, 5e6])  # georeferenced coordinates of a unit-sized model
    errors = []
    for shift in (np.zeros(3), offset):
        V1, F1, result = array_api.fill_holes(V + shift, F, "lssvm_poisson", workers=1)
        assert result["closed_holes"] == 2, [h.get("reason") for h in result["holes"]]
        assert_filled_cleanly(V + shift, F, V1, F1)
        errors.append(np.abs(np.linalg.norm(V1[len(V):] - shift, axis=1) - 1.0).max())
    assert errors[1] <= 1.01 * errors[0] + 1e-9


def test_lssvm_learns_a_known_function():
    x = np.linspace(-2, 2, 80)
    model = lssvm_fit(x, np.sin(2 * x), gamma=1e4, width=0.3)
    z = np.linspace(-1.9, 1.9, 57)
    assert np.abs(model(z) - np.sin(2 * z)).max() < 0.02


# ------------------------------------------------------------------ Sec. 3.4 Poisson, and the whole method

def test_hole_in_a_plane_stays_planar():
    V, F = grid(14, 14, z=lambda x, y: 0.0 * x)
    V, F, _ = cut_disks(V, F, [[0.5, 0.5, 0.0]], 0.3)
    ctx = context_of(V, F, inside=lambda P: np.abs(P[:, :2] - 0.5).max(axis=1) < 0.45)
    patch = xu.fill(ctx)
    validate_patch(patch, ctx.points)
    X = np.concatenate([ctx.points, patch.vertices])
    q = triangle_quality(X, patch.faces)
    assert q.mean() >= 0.85 and q.min() >= 0.3
    # about the grid's density (edge 1/13): the disk of radius ~0.3 holds ~(0.3 * 13)^2 * pi vertices
    assert 25 <= len(patch.vertices) <= 80
    assert np.abs(patch.vertices[:, 2]).max() < 1e-9


def test_hole_in_a_sphere_bulges_toward_the_sphere():
    V, F, _ = sphere_hole()
    ctx = context_of(V, F)
    lssvm = xu.fill(ctx)
    zero = xu.fill(ctx, laplacian_prediction="zero", poisson_boundary="dirichlet")  # the membrane
    flat = np.abs(ctx.points[:, 2]).mean()  # the boundary's plane
    r_lssvm = np.abs(np.linalg.norm(lssvm.vertices, axis=1) - 1)
    r_zero = np.abs(np.linalg.norm(zero.vertices, axis=1) - 1)
    assert lssvm.vertices[:, 2].max() > flat + 0.5 * (1 - flat)  # rises most of the way to the pole
    assert r_lssvm.mean() < 0.25 * r_zero.mean()
    assert r_lssvm.max() < 0.02
    assert lssvm.info["training_samples"] > 0 and lssvm.info["afm_domain"] == "3d"


def test_poisson_solve_with_zero_laplacian_is_the_membrane():
    V, F, _ = sphere_hole()
    ctx = context_of(V, F)
    patch = xu.fill(ctx, laplacian_prediction="zero", relax=False)
    X = patch.all_points(ctx.points)
    L = normalized_cotangent_laplacian(X, patch.faces)
    inner = np.arange(len(X)) >= ctx.size
    # Relaxed weights after the solve differ from the solve's: check the membrane property loosely.
    assert np.abs(L[inner] @ X).max() < 0.05 * ctx.mean_edge_length


def test_repeated_poisson_solves_converge_to_their_own_weights():
    # Sec. 3.4: L_Vn depends on the positions, so each further solve uses the previous result's
    # weights; the displacement shrinks and the final positions satisfy their own Laplacian system.
    from meshlab_holefill.algorithms.xu2013.poisson_reconstruction import poisson_reposition

    V, F, _ = sphere_hole()
    ctx = context_of(V, F)
    patch = xu.fill(ctx, laplacian_prediction="zero", relax=False)
    X, fixed = patch.all_points(ctx.points), np.arange(ctx.size + len(patch.vertices)) < ctx.size
    X[~fixed] += 0.3 * ctx.mean_edge_length * np.random.default_rng(0).normal(size=((~fixed).sum(), 3))
    residuals, changes = [], []
    for iterations in (1, 2, 4, 8):
        Y, G, info = poisson_reposition(X, patch.faces, fixed, None, iterations=iterations)
        assert info["poisson_solves"] == iterations and not info["poisson_rejected"]
        changes.append(info["poisson_last_change"])
        residuals.append(np.abs(normalized_cotangent_laplacian(Y, G)[~fixed] @ Y).max() / ctx.mean_edge_length)
    assert np.all(np.diff(changes) < 0) and np.all(np.diff(residuals) < 0)
    assert residuals[-1] < 0.05 * residuals[0]


def _fold_case():
    """Planar patch (8 boundary vertices, 3 inner) and a solve target moving inner vertex 10 past edge (3, 8).

    Returns X (initial patch), F (its Delaunay faces), T (the target: triangle (3, 8, 10) turned
    over, a quad whose other diagonal (10, 4) is sound) and a stand-in HoleContext for the swaps.
    """
    from types import SimpleNamespace

    from scipy.spatial import Delaunay

    k = 8
    t = np.linspace(0.0, 2.0 * np.pi, k, endpoint=False)
    X = np.concatenate([np.stack([np.cos(t), np.sin(t), 0.0 * t], axis=1),
                        [[-0.35, -0.2, 0.0], [0.35, -0.2, 0.0], [0.0, 0.4, 0.0]]])
    F = Delaunay(X[:, :2]).simplices.astype(np.int64)
    A = X[F]
    cw = np.cross(A[:, 1] - A[:, 0], A[:, 2] - A[:, 0])[:, 2] < 0
    F[cw] = F[cw][:, [0, 2, 1]]
    T = X.copy()
    T[10] = X[10] + 1.2 * (0.5 * (X[3] + X[8]) - X[10])
    return X, F, T, SimpleNamespace(size=k, forbidden_edges=np.zeros((0, 2), np.int64))


def test_poisson_solve_folded_across_one_edge_is_kept_when_a_swap_unfolds_it():
    # The path of 335d403: a solve that turns one quad over is kept with the quad's other diagonal
    # instead of being discarded. The right-hand side is set so that the solve lands exactly on T.
    from meshlab_holefill.geometry.flips import folds

    X, F, T, ctx = _fold_case()
    free = np.arange(len(X)) >= ctx.size
    rhs = np.asarray(normalized_cotangent_laplacian(X, F) @ T)[free]
    regressors = [lambda x, d=d: rhs[:, d] for d in range(3)]
    assert not folds(X, F) and folds(T, F)
    Y, G, info = pr.poisson_reposition(X, F, ~free, regressors, relax_ctx=ctx)
    assert not info["poisson_rejected"] and info["poisson_solves"] == 1
    assert np.allclose(Y, T, atol=1e-9)  # the solve is kept ...
    assert not folds(Y, G) and not np.array_equal(np.sort(G, axis=1), np.sort(F, axis=1))  # ... with swapped faces
    assert sorted(map(sorted, G[(G == 10).any(axis=1)].tolist())).count([3, 8, 10]) == 0
    # Without the swaps (no HoleContext) the folded solve is discarded.
    Y0, G0, info0 = pr.poisson_reposition(X, F, ~free, regressors)
    assert info0["poisson_rejected"] and info0["poisson_solves"] == 0
    assert np.array_equal(Y0, X) and np.array_equal(G0, F)


def test_sliver_repair_leaves_good_patches_alone():
    from meshlab_holefill.algorithms.xu2013.poisson_patch import repair_slivers

    X, F, T, ctx = _fold_case()
    fixed = np.arange(len(X)) < ctx.size
    Y, G, kept = repair_slivers(X, F, fixed, ctx, floor=0.3)
    assert triangle_quality(X, F).min() >= 0.3
    assert kept == 0 and Y is X and G is F


@pytest.fixture(scope="module")
def face_hole_227():
    """face000.ply's largest natural hole (227 edges; the benchmark's face000 hole 1) after Sec. 3.1."""
    from meshlab_holefill.evaluation.metrics import corner_quality_bound

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("rangemaps/face000.ply"))
    V, F = mesh_arrays(ms)
    loop = [lp for lp in boundary_loops(F) if len(lp) == 227][0]
    bound = corner_quality_bound(V, F, loop.vertices)
    ref = xu.prepare_boundary(V, F, [loop], {})
    return hole_context(ref.V, ref.F, ref.loops[0], rings=xu.RINGS), bound


def test_sliver_repair_lifts_the_border_row_the_poisson_solve_squeezes(face_hole_227, monkeypatch):
    # The 3D front leaves this hole, so the filter's patch is the developed boundary's front
    # (fill() takes ~3 s to find that out; this builds that patch directly). The Poisson solve
    # with the square Dirichlet system squeezes the triangles along a stretch of the border;
    # smoothing and swaps alone leave 0.216, while the corner bound is 0.596. The local repair
    # lifts them above 0.3. The boundary rows (the default) do not squeeze that row.
    from meshlab_holefill.algorithms.xu2013.poisson_patch import harmonic_lift, planar_boundaries

    ctx, bound = face_hole_227
    assert bound > 0.5
    D = dict(planar_boundaries(ctx))["developed"]
    new_vertices, F0, _ = advancing_front_triangulation(D, ctx.forbidden_edges, 0.75, reference_normal=UP)
    X0 = harmonic_lift(np.concatenate([D, new_vertices]), F0, ctx.points)
    regressors = lr.fit_laplacian_regressors(*lr.training_set(ctx, 2), 10.0, 0.5)
    X, F, info = pr.reposition(ctx, X0, F0, regressors, 1, True, "dirichlet")
    q = triangle_quality(X, F)
    assert info["sliver_repairs"] >= 1 and info["poisson_damping"] == 1.0
    assert q.min() >= 0.3 and q.mean() >= 0.85
    assert len(pp.context_hits(X, F, ctx)) == 0
    monkeypatch.setattr(pr, "SLIVER_QUALITY", 0.0)  # without the repair
    X1, F1, _ = pr.reposition(ctx, X0, F0, regressors, 1, True, "dirichlet")
    assert triangle_quality(X1, F1).min() < 0.3
    X2, F2, info2 = pr.reposition(ctx, X0, F0, regressors, 1, True)
    assert triangle_quality(X2, F2).min() >= 0.3 and info2["sliver_repairs"] == 0


def test_filter_on_a_sphere_hole(tmp_path):
    V, F, removed = sphere_hole(center=(0.6, 0.0, 0.8), radius=0.5)
    ms = meshset_from_arrays(V, F)
    res = getattr(ms, NAME)()
    assert res["closed_holes"] == 1 and res["failed_holes"] == 0
    V1, F1 = mesh_arrays(ms)
    assert np.array_equal(V1[:len(V)], V) and np.array_equal(F1[:len(F)], F)  # nothing to split here
    assert boundary_loops(F1) == [] and len(nonmanifold_edges(F1)) == 0
    new = F1[len(F):]
    q = triangle_quality(V1, new)
    assert q.mean() >= 0.85 and q.min() >= 0.3
    assert len(faces_intersecting(V1, F1, np.arange(len(F), len(F1)), np.arange(len(F1)))) == 0
    assert np.abs(np.linalg.norm(V1[len(V):], axis=1) - 1).max() < 0.01


def test_bunny_scan_natural_holes_all_close_with_good_triangles(bunny_scan):
    V0, F0 = mesh_arrays(bunny_scan)
    res = getattr(bunny_scan, NAME)()
    assert res["closed_holes"] == 5, [h.get("reason") for h in res["holes"]]
    V1, F1 = mesh_arrays(bunny_scan)
    assert_filled_cleanly(V0, F0, V1, F1, faces_kept=False)  # long border edges are split (Sec. 3.1)
    # Patch faces: every vertex new or on a hole border (the halves of split border faces keep
    # an original inner vertex and the shape of the face they split).
    loops = boundary_loops(F0)
    allowed = np.ones(len(V1), bool)
    allowed[:len(V0)] = np.isin(np.arange(len(V0)), np.concatenate([lp.vertices for lp in loops]))
    patch = F1[allowed[F1].all(axis=1)]
    q = triangle_quality(V1, patch)
    assert q.mean() >= 0.9
    # Only the 8-edge hole has a triangle below 0.3: a border corner there allows no better
    # than 0.147 (metrics.corner_quality_bound).
    small = next(lp.vertices for lp in loops if len(lp) == 8)
    assert np.isin(patch[q < 0.3], small).any(axis=1).all() and q.min() >= 0.1


def test_lssvm_beats_the_membrane_on_a_torus_hole():
    ms = pymeshlab.MeshSet()
    ms.create_torus(hradius=1.0, vradius=0.4, hsubdiv=64, vsubdiv=32)
    V, F = mesh_arrays(ms)
    V, F, _ = cut_disks(V, F, [[1.4, 0.0, 0.0]], 0.3)
    ctx = context_of(V, F)

    def torus_error(X):
        return np.abs(np.hypot(np.hypot(X[:, 0], X[:, 1]) - 1.0, X[:, 2]) - 0.4).mean()

    membrane = xu.fill(ctx, laplacian_prediction="zero", poisson_boundary="dirichlet")
    assert torus_error(xu.fill(ctx).vertices) < 0.5 * torus_error(membrane.vertices)


def test_parameters_are_exposed_and_validated(bunny_scan):
    from meshlab_holefill import FilterParameterError

    for name in ("split_boundary", "split_factor", "layers", "gamma", "kernel_width", "poisson_iterations",
                 "laplacian_prediction", "merge_factor"):
        assert name in [p.name for p in xu.PARAMS]
    with pytest.raises(FilterParameterError, match=r"'laplacian_prediction': expected one of \['lssvm', 'zero'\]"):
        getattr(bunny_scan, NAME)(laplacian_prediction="cubic")
    with pytest.raises(FilterParameterError, match="'layers': 9 is above the maximum 5"):
        getattr(bunny_scan, NAME)(layers=9)


# ------------------------------------------------------------------ direct tests of building blocks

def tilted_plane_hole(n=13, radius=0.3):
    """HoleContext of a disk cut from a grid on the plane z = 0.3 x + 0.2 y (a staircase loop)."""
    V, F = grid(n, n, z=lambda x, y: 0.3 * x + 0.2 * y)
    V, F, _ = cut_disks(V, F, [(0.5, 0.5, 0.25)], radius)
    return context_of(V, F, inside=lambda P: np.linalg.norm(P[:, :2] - 0.5, axis=1) < 0.45)  # not the outer border


def tilted_polar_hole(m=24, rings=10, hole=0.42):
    """HoleContext of a polar disc mesh on the plane z = 0.3 x + 0.2 y, the rings inside r = 0.4 cut:
    the loop is a regular m-gon (no collinear edges)."""
    t = 2 * np.pi * np.arange(m) / m
    r = np.linspace(0, 1, rings + 1)[1:]
    P = np.concatenate([[[0.0, 0.0]], (r[:, None, None] * np.stack([np.cos(t), np.sin(t)], 1)).reshape(-1, 2)])
    V = np.column_stack([P, 0.3 * P[:, 0] + 0.2 * P[:, 1]])
    ring = 1 + np.arange(rings * m).reshape(rings, m)
    nxt = np.roll(ring, -1, axis=1)
    F = np.concatenate([np.stack([np.zeros(m, np.int64), ring[0], nxt[0]], 1),
                        np.stack([ring[:-1], ring[1:], nxt[1:]], 2).reshape(-1, 3),
                        np.stack([ring[:-1], nxt[1:], nxt[:-1]], 2).reshape(-1, 3)])
    V, F, _ = cut_disks(V, F, [(0.0, 0.0, 0.0)], hole)
    return context_of(V, F, inside=lambda Q: np.linalg.norm(Q[:, :2], axis=1) < 0.5)


def off_plane(X):
    return np.abs(X[:, 2] - 0.3 * X[:, 0] - 0.2 * X[:, 1]).max()


def test_initial_patches_yield_every_domain_in_order_each_closing_the_hole_on_its_plane():
    from meshlab_holefill.algorithms.xu2013.poisson_patch import initial_patches

    ctx = tilted_polar_hole()
    k = ctx.size
    assert k == 24
    failures = []
    domains = []
    for X, F, stats, layout in initial_patches(ctx, 0.75, failures):
        domains.append(stats["domain"])
        # Loop first and bit-exact: the planar domains are lifted back onto the loop, not left in z = 0.
        assert np.array_equal(X[:k], ctx.points)
        validate_patch(Patch(X[k:], F), ctx.points, ctx.forbidden_edges)
        assert len(X) > k and off_plane(X) < 1e-12  # a planar hole gives a planar patch in every domain
    assert domains == ["3d", "developed", "projected", "ears", "least bend"] and failures == []


def test_initial_patches_fall_back_lazily_and_record_why(monkeypatch):
    from meshlab_holefill.algorithms.xu2013 import poisson_patch as patch_module

    ctx = tilted_polar_hole()
    calls = []
    real = patch_module.advancing_front_triangulation

    def front(P, *args, **kwargs):
        calls.append(kwargs.get("obstacles") is not None)
        if len(calls) == 1:
            raise HoleFillError("front ran out of the hole")
        return real(P, *args, **kwargs)

    monkeypatch.setattr(patch_module, "advancing_front_triangulation", front)
    failures = []
    patches = patch_module.initial_patches(ctx, 0.75, failures)
    assert calls == [] and failures == []  # a generator: nothing runs before it is asked
    X, F, stats, layout = next(patches)
    assert stats["domain"] == "developed" and calls == [True, False]  # only the 3D front and one planar front ran
    assert failures == ["3d advancing front: front ran out of the hole"]
    assert np.array_equal(X[:ctx.size], ctx.points) and off_plane(X) < 1e-12
    validate_patch(Patch(X[ctx.size:], F), ctx.points, ctx.forbidden_edges)


def test_planar_boundaries_offer_the_projection_of_a_planar_hole_with_collinear_edges():
    from meshlab_holefill.algorithms.xu2013.poisson_patch import planar_boundaries
    from meshlab_holefill.geometry.segments import polygon_edges_touch

    # Minimal: a U whose two top edges lie on y = 2, far apart; the polygon is simple.
    U = np.array([[0, 0], [3, 0], [3, 2], [2, 2], [2, 1], [1, 1], [1, 2], [0, 2.0]])
    assert not polygon_edges_touch(U)
    U[6] = [2, 2]  # the right top edge now overlaps the left one's end: they touch
    assert polygon_edges_touch(U)
    # A disk cut from a tilted grid: its loop is a staircase with many collinear edges, and its
    # projection onto its own plane is congruent to it, hence simple.
    ctx = tilted_plane_hole()
    assert [name for name, _ in planar_boundaries(ctx)] == ["developed", "projected"]


def patch_of_removed_faces(V, F_kept, F_removed, rings=2):
    """HoleContext of the cut hole and the removed faces as its patch: (ctx, true new vertices, patch faces)."""
    ctx = hole_context(V, F_kept, min(boundary_loops(F_kept), key=len), rings=rings)
    k = ctx.size
    new = np.setdiff1d(np.unique(F_removed), ctx.loop)
    index = np.full(len(V), -1)
    index[ctx.loop], index[new] = np.arange(k), k + np.arange(len(new))
    return ctx, V[new], index[F_removed]


def test_fair_patch_in_context_restores_a_flat_grid_exactly():
    from meshlab_holefill.algorithms.hu2012.fairing import fair_patch_in_context

    # On a regular flat grid every vertex is the mean of its 1-ring, so L x = 0 and L^2 x = 0 hold
    # at the true positions: fairing any start must give them back, flat.
    V, F, removed = cut_disks(*grid(11, 11), [(0.5, 0.5, 0.0)], 0.3)
    ctx, truth, Fp = patch_of_removed_faces(V, F, removed)
    start = truth + np.random.default_rng(0).normal(scale=0.05, size=truth.shape)
    for order in (1, 2):
        out = fair_patch_in_context(ctx.vertices, ctx.faces, ctx.size, start, Fp, order=order)
        assert out.shape == truth.shape and np.abs(out - truth).max() < 1e-12


def test_fair_patch_in_context_bulges_a_flat_patch_onto_the_sphere():
    from meshlab_holefill.algorithms.hu2012.fairing import fair_patch_in_context

    V, F, removed = sphere_hole(radius=0.5)
    ctx, truth, Fp = patch_of_removed_faces(V, F, removed)
    plane_z = ctx.points[:, 2].mean()
    flat = truth.copy()
    flat[:, 2] = plane_z  # the cap pressed into the loop's plane: up to 0.125 inside the sphere
    assert np.abs(np.linalg.norm(flat, axis=1) - 1).max() > 0.1
    # Thin plate (default order 2): the fixed ring outside the loop carries the sphere's slope in,
    # the patch rises above the loop plane to within 0.01 of the sphere.
    out = fair_patch_in_context(ctx.vertices, ctx.faces, ctx.size, flat, Fp)
    assert np.abs(np.linalg.norm(out, axis=1) - 1).max() < 0.01
    assert out[:, 2].min() > ctx.points[:, 2].max()
    # The membrane (order 1) only spans the loop: it stays near the plane, far from the sphere.
    membrane = fair_patch_in_context(ctx.vertices, ctx.faces, ctx.size, flat, Fp, order=1)
    assert np.abs(np.linalg.norm(membrane, axis=1) - 1).max() > 0.1


@pytest.mark.parametrize("scale", [1e-6, 1e-3, 1e3, 1e9])
def test_the_patch_does_not_depend_on_the_unit(scale):
    """Every tolerance of the front is relative: the same hole in other units gets the same patch."""
    from conftest import sphere_with_holes

    V, F, _ = sphere_with_holes(subdiv=3, centers=[(0, 0, 1)], radius=0.3)
    ref = xu.fill(hole_context(V, F, boundary_loops(F)[0], rings=xu.RINGS))
    patch = xu.fill(hole_context(V * scale, F, boundary_loops(F)[0], rings=xu.RINGS))
    assert np.array_equal(patch.faces, ref.faces) and patch.info["afm_rejected"] == ref.info["afm_rejected"]
    np.testing.assert_allclose(patch.vertices / scale, ref.vertices, rtol=0, atol=1e-9)
