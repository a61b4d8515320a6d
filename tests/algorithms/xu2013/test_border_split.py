"""Xu et al. 2013 Sec. 3.1: the boundary pre-treatment splitting long boundary edges."""
import numpy as np
import pytest

from meshlab_holefill.algorithms.xu2013.border_split import split_long_boundary_edges
from meshlab_holefill.core.holes import boundary_loops, nonmanifold_edges
from meshlab_holefill.geometry.quality import face_areas

from xu2013_cases import surface_area


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
