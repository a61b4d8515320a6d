import collections

import numpy as np
import pymeshlab
import pytest
from hypothesis import given, settings, strategies as st

from meshlab_holefill.algorithms.hu2012.hole_guards import inside_hole_sector
from meshlab_holefill.errors import HoleFillError
from meshlab_holefill.core.holes import boundary_halfedges, boundary_loops, edge_face_counts, edge_summary, hole_context, nonmanifold_edges, vertex_face_incidence

from conftest import cut_disks, grid, mesh_arrays, sample, sphere_with_holes


def test_single_triangle_loop_runs_against_the_face():
    loops = boundary_loops(np.array([[0, 1, 2]]))
    assert len(loops) == 1
    # Patch orientation is the reverse of the face's own order.
    v = loops[0].vertices.tolist()
    assert v in ([0, 2, 1], [2, 1, 0], [1, 0, 2])


def test_grid_with_hole_has_outer_and_inner_loop_with_border_faces():
    V, F = grid(10, 10)
    _, F, removed = cut_disks(V, F, [(0.5, 0.5, 0)], 0.2)
    loops = boundary_loops(F)
    assert len(loops) == 2
    outer, inner = loops
    assert len(outer) == 36
    for lp in loops:
        assert len(np.unique(lp.vertices)) == len(lp.vertices)
        for i, f in enumerate(lp.border_faces):
            a, b = lp.vertices[i], lp.vertices[(i + 1) % len(lp)]
            face = F[f].tolist()
            j = face.index(b)
            assert face[(j + 1) % 3] == a  # the border face holds (b, a)


def test_inner_loop_is_counter_clockwise_seen_from_the_normal():
    V, F = grid(10, 10)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0)], 0.2)
    inner = boundary_loops(F)[1]
    P = V[inner.vertices][:, :2]
    signed = 0.5 * np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])
    assert signed > 0  # faces are counter-clockwise (normal +z), so the patch loop is too


def test_pinched_vertex_is_split_into_simple_loops():
    # Two triangles touching at vertex 0 (a bow tie).
    F = np.array([[0, 1, 2], [0, 3, 4]])
    loops = boundary_loops(F)
    assert [len(lp) for lp in loops] == [3, 3]
    assert all(lp.pinched for lp in loops)
    assert all(len(set(lp.vertices.tolist())) == 3 for lp in loops)


def test_bunny_scan_has_its_five_natural_holes():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("bunny10k_textured.obj"))
    _, F = mesh_arrays(ms)
    assert [len(lp) for lp in boundary_loops(F)] == [38, 22, 22, 19, 8]


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 100_000), n=st.integers(3, 40), m=st.integers(1, 60))
def test_compiled_walk_gives_the_python_walks_loops(seed, n, m):
    # Random faces over few vertices: pinched vertices, non-manifold edges and faces of either
    # orientation (open chains), as the Python walk splits them.
    from meshlab_holefill.core._boundary_loops import boundary_loops_python

    F = np.random.default_rng(seed).integers(0, n, (m, 3))
    F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])]
    compiled, python = boundary_loops(F), boundary_loops_python(F)
    assert len(compiled) == len(python)
    for a, b in zip(compiled, python):
        assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.border_faces, b.border_faces)
        assert a.vertices.dtype == b.vertices.dtype == a.border_faces.dtype == np.int64
        assert (a.pinched, a.closed) == (b.pinched, b.closed)


def test_face_range_scan_loops_are_simple_and_cover_every_boundary_edge():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("rangemaps/face000.ply"))
    _, F = mesh_arrays(ms)
    loops = boundary_loops(F)
    assert len(loops[0]) == 2468
    assert sum(len(lp) for lp in loops) == len(boundary_halfedges(F)[0])
    assert all(len(set(lp.vertices.tolist())) == len(lp) for lp in loops)
    assert all(lp.closed for lp in loops)
    assert any(lp.pinched for lp in loops)


def test_nonmanifold_edge_detected():
    F = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    assert nonmanifold_edges(F).tolist() == [[0, 1]]


@settings(max_examples=15, deadline=None)
@given(st.lists(st.tuples(st.floats(0.25, 0.75), st.floats(0.25, 0.75)), min_size=1, max_size=1),
       st.floats(0.08, 0.2))
def test_one_hole_in_a_grid_gives_two_loops(centers, radius):
    V, F = grid(16, 16)
    _, F2, removed = cut_disks(V, F, [(x, y, 0) for x, y in centers], radius)
    if len(removed) == 0:
        return
    loops = boundary_loops(F2)
    assert len(loops) == 2
    assert sum(len(lp) for lp in loops) == len(boundary_halfedges(F2)[0])


def test_hole_context_rings_scale_and_normals():
    V, F, _ = sphere_with_holes(subdiv=4, centers=[(0, 0, 1)], radius=0.3)
    loop = boundary_loops(F)[0]
    ctx = hole_context(V, F, loop, vertex_face_incidence(F, len(V)), rings=2)
    k = ctx.size
    assert np.array_equal(ctx.global_index[:k], loop.vertices)
    assert np.array_equal(ctx.vertices[:k], V[loop.vertices])
    assert set(np.unique(ctx.depth)) == {0, 1, 2}
    # On a unit sphere, vertex normals point along the position.
    cos = np.einsum("ij,ij->i", ctx.normals[ctx.depth < 2], ctx.vertices[ctx.depth < 2])
    assert cos.min() > 0.99
    assert np.allclose(ctx.edge_scale, ctx.mean_edge_length, rtol=0.3)
    # border faces hold the loop edges
    for i in range(k):
        face = ctx.faces[ctx.border_faces[i]].tolist()
        assert i in face and (i + 1) % k in face


def test_obstacle_faces_beyond_the_rings_share_the_rings_vertices_and_only_the_crossing_checks_see_them():
    V, F, _ = sphere_with_holes(subdiv=4, centers=[(0, 0, 1)], radius=0.3)
    loop = boundary_loops(F)[0]
    incidence = vertex_face_incidence(F, len(V))
    plain = hole_context(V, F, loop, incidence, rings=2)
    near = np.flatnonzero(V[F, 2].max(axis=1) > 0.6)  # the rings and faces beyond them
    ctx = hole_context(V, F, loop, incidence, rings=2, obstacles=near)
    for name in ("vertices", "faces", "normals", "depth", "edge_scale", "forbidden_edges"):
        assert np.array_equal(getattr(ctx, name), getattr(plain, name))
    assert plain.surroundings()[1] is plain.faces and len(plain.obstacle_faces) == 0
    ring_faces = set(plain.extra["global_faces"].tolist())
    assert len(ctx.obstacle_faces) == len(set(near.tolist()) - ring_faces) > 0
    X, S = ctx.surroundings()
    # every obstacle face is a mesh face, in the local numbering of the rings' vertices then the new ones
    local_to_global = np.concatenate([ctx.global_index, np.flatnonzero(np.isin(np.arange(len(V)), F[near]) &
                                                                       ~np.isin(np.arange(len(V)), ctx.global_index))])
    assert np.array_equal(X, V[local_to_global])
    beyond = set(map(tuple, np.sort(F[np.setdiff1d(near, plain.extra["global_faces"])], axis=1).tolist()))
    assert set(map(tuple, np.sort(local_to_global[S[len(ctx.faces):]], axis=1).tolist())) == beyond
    # faces touching the rings use the rings' vertices, not copies of them
    assert np.any(S[len(ctx.faces):] < len(ctx.vertices))


def test_hole_sector_on_a_square_corner():
    # Counter-clockwise square seen from +z: at (1, 0) the hole sector points up-left.
    z = np.array([0, 0, 1.0])
    apex, prev, nxt = np.array([1.0, 0, 0]), np.array([0.0, 0, 0]), np.array([1.0, 1, 0])
    inside = inside_hole_sector(apex, z, prev, nxt, np.array([[0.5, 0.5, 0], [1.5, -0.5, 0], [2, 0.1, 0]]))
    assert inside.tolist() == [True, False, False]


def _grid_hole_with_flipped_border_face(which=0, nx=6, radius=0.25):
    """A grid with one hole whose border face of loop edge ``which`` is flipped (inconsistent orientation)."""
    V, F = grid(nx, nx)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0)], radius)
    outer, inner = boundary_loops(F)
    F_flipped = F.copy()
    f = inner.border_faces[which]
    F_flipped[f] = F_flipped[f][::-1]
    return V, F, F_flipped, outer, inner


def _chain_edges(lp):
    """Directed edges (patch orientation) a loop or chain walks: k for a closed loop, k - 1 for an open chain."""
    v = lp.vertices.tolist()
    pairs = list(zip(v, v[1:] + v[:1]))
    return pairs if lp.closed else pairs[:-1]


def test_flipped_border_face_turns_the_hole_into_open_chains():
    # Flipping the face that holds loop edge (l0, l1) reverses that boundary half-edge, so the
    # walk l1 -> l2 -> ... -> l0 dead-ends at l0 and the reversed edge is a chain of its own.
    V, F, F_flipped, outer, inner = _grid_hole_with_flipped_border_face(0)
    l, bf = inner.vertices.tolist(), inner.border_faces.tolist()
    assert len(l) == 10 and len(set(bf)) == 10  # each border face holds one loop edge
    loops = boundary_loops(F_flipped)
    closed = [lp for lp in loops if lp.closed]
    chains = sorted((lp for lp in loops if not lp.closed), key=len, reverse=True)
    # the outer border is untouched: still one closed, unpinched loop
    assert len(closed) == 1 and closed[0].vertices.tolist() == outer.vertices.tolist() and not closed[0].pinched
    assert [c.vertices.tolist() for c in chains] == [l[1:] + l[:1], [l[1], l[0]]]
    assert [c.border_faces.tolist() for c in chains] == [bf[1:], bf[:1]]
    assert all(c.pinched for c in chains)  # open chains are flagged pinched too (never a simple hole)


@settings(max_examples=12, deadline=None)
@given(st.integers(0, 11))
def test_any_flipped_border_face_leaves_only_open_chains_that_cover_the_hole(which):
    V, F, F_flipped, outer, inner = _grid_hole_with_flipped_border_face(which, nx=10, radius=0.2)
    assert len(inner) == 12
    loops = boundary_loops(F_flipped)
    hole = set(inner.vertices.tolist())
    for lp in loops:
        if set(lp.vertices.tolist()) <= hole:
            # no closed loop can run through a reversed half-edge
            assert not lp.closed and lp.pinched
            assert len(lp.border_faces) == len(lp.vertices) - 1
        else:
            assert lp.closed and lp.vertices.tolist() == outer.vertices.tolist()
    # the chains together walk every border edge of the hole exactly once, each against its border face
    edges = [e for lp in loops if not lp.closed for e in _chain_edges(lp)]
    assert len(edges) == len(inner)
    assert sorted(map(sorted, edges)) == sorted(map(sorted, _chain_edges(inner)))
    for lp in loops:
        for (a, b), f in zip(_chain_edges(lp), lp.border_faces):
            face = F_flipped[f].tolist()
            assert face[(face.index(b) + 1) % 3] == a  # the border face holds (b, a)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_vertices=st.integers(3, 12), n_faces=st.integers(1, 40),
       degenerate=st.booleans(), int32=st.booleans(), high_valence=st.booleans())
def test_edge_tables_match_counting_every_half_edge(seed, n_vertices, n_faces, degenerate, int32, high_valence):
    # Random triangle soups: repeated faces, both orientations, edges with 1 to many faces; optionally faces
    # repeating a vertex, pymeshlab's int32 indices, and a vertex on more than 32 half-edges (the compiled
    # kernel sorts such a group differently).
    rng = np.random.default_rng(seed)
    rows = [rng.choice(n_vertices, 3, replace=not degenerate) for _ in range(n_faces)]
    if high_valence:
        rows += [[0, 1 + j % (n_vertices - 1), 1 + (j + 1) % (n_vertices - 1)] for j in range(40)]
    F = np.array(rows, np.int32 if int32 else np.int64)
    halfedges = collections.defaultdict(list)
    for f, face in enumerate(F):
        for corner in range(3):
            a, b = int(face[corner]), int(face[(corner + 1) % 3])
            halfedges[(min(a, b), max(a, b))].append((a, b, f))
    edges = sorted(halfedges)
    got_edges, got_counts = edge_face_counts(F)
    assert got_edges.tolist() == [list(e) for e in edges]
    assert got_counts.tolist() == [len(halfedges[e]) for e in edges]
    border = [halfedges[e][0] for e in edges if len(halfedges[e]) == 1]
    he, faces = boundary_halfedges(F)
    assert np.column_stack([he, faces]).tolist() == [list(x) for x in border]
    he2, faces2, bad = edge_summary(F)
    assert np.array_equal(he2, he) and np.array_equal(faces2, faces)
    assert bad.tolist() == [list(e) for e in edges if len(halfedges[e]) > 2]
    assert nonmanifold_edges(F).tolist() == bad.tolist()


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_vertices=st.integers(3, 15), n_faces=st.integers(1, 50),
       int32=st.booleans())
def test_vertex_face_incidence_lists_each_face_once_per_vertex_in_order(seed, n_vertices, n_faces, int32):
    rng = np.random.default_rng(seed)
    F = rng.integers(0, n_vertices, (n_faces, 3)).astype(np.int32 if int32 else np.int64)  # repeats included
    incidence = vertex_face_incidence(F, n_vertices + 2)  # two vertices without faces
    assert incidence.shape == (n_vertices + 2, n_faces)
    for v in range(n_vertices + 2):
        row = incidence.indices[incidence.indptr[v]:incidence.indptr[v + 1]]
        assert row.tolist() == [f for f in range(n_faces) if v in F[f].tolist()]
    assert set(incidence.data.tolist()) <= {1}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_incident_faces_are_the_union_of_the_incidence_rows(seed):
    from meshlab_holefill.core.holes import incident_faces

    rng = np.random.default_rng(seed)
    F = rng.integers(0, 40, (120, 3))
    incidence = vertex_face_incidence(F, 42)  # vertices 40 and 41 hold no face
    for vertices in (rng.choice(42, 7, replace=False), np.array([40, 41]), np.array([3]), np.arange(42)):
        expected = np.unique(incidence[vertices].indices)
        got = incident_faces(incidence, vertices)
        assert got.dtype == expected.dtype and got.tolist() == expected.tolist()


def _with_duplicate_border_vertex(V, F, loop):
    """The mesh with loop vertex v split in two coincident vertices v, v' joined by a zero-area face,
    so that the loop runs ... -> v -> v' -> w: a duplicate vertex as remeshed booleans leave them."""
    v, w = int(loop.vertices[0]), int(loop.vertices[1])
    g = next(f for f in range(len(F)) if v in F[f] and w in F[f])
    x = int(next(c for c in F[g] if c not in (v, w)))
    V2 = np.vstack([V, V[v]])
    dup = len(V)
    F2 = F.copy()
    F2[g] = np.where(F2[g] == v, dup, F2[g])
    # Opposite to the face's own (now v' -> x or x -> v') edge, so the degenerate face is oriented with the mesh.
    row = list(F2[g])
    i = row.index(dup)
    new = [v, x, dup] if row[(i + 1) % 3] == x else [v, dup, x]
    return V2, np.vstack([F2, new])


@pytest.mark.parametrize("algorithm", ["min_angle_bilateral", "curve_unfolding", "lssvm_poisson", "differential_evolution"])
def test_a_border_edge_between_coincident_vertices_is_refused_by_name_and_the_mesh_kept(algorithm):
    from meshlab_holefill import fill_holes
    from meshlab_holefill.core import examples

    V, F, loop = examples.bowl_with_hole()
    V2, F2 = _with_duplicate_border_vertex(V, F, loop)
    hole = min(boundary_loops(F2), key=len)
    assert len(hole) == len(loop) + 1  # the zero-length edge joined the loop
    V3, F3, result = fill_holes(V2, F2, algorithm, workers=1)
    entry = next(h for h in result["holes"] if h["boundary_edges"] == len(hole))
    assert entry["status"] == "failed"
    assert "duplicate vertices" in entry["reason"] and "merge close vertices" in entry["reason"]
    assert np.array_equal(V3, V2) and np.array_equal(F3, F2)
    with pytest.raises(Exception, match="duplicate vertices"):
        hole_context(V2, F2, hole)


def _with_face_cut_loose_at_a_corner():
    """A sphere whose face 100 uses a copy v' of its first vertex v: the border runs v -> a -> v' -> b -> v.

    Returns V, F and the pair (v, v').
    """
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    V, F = mesh_arrays(ms)
    v = int(F[100, 0])
    V = np.vstack([V, V[v]])
    F = F.copy()
    F[100, 0] = len(V) - 1
    return V, F, (v, len(V) - 1)


@pytest.mark.parametrize("algorithm", ["min_angle_bilateral", "curve_unfolding", "lssvm_poisson", "differential_evolution"])
def test_a_border_through_one_position_twice_is_refused_by_name_and_the_mesh_kept(algorithm):
    from meshlab_holefill import fill_holes

    V, F, (v, copy) = _with_face_cut_loose_at_a_corner()
    (hole,) = boundary_loops(F)
    assert len(hole) == 4 and len(set(hole.vertices.tolist())) == 4  # no vertex twice: not a pinched loop
    V2, F2, result = fill_holes(V, F, algorithm, workers=1)
    (entry,) = result["holes"]
    assert entry["status"] == "failed"
    assert "passes twice through one position" in entry["reason"] and "meshing_merge_close_vertices" in entry["reason"]
    assert np.array_equal(V2, V) and np.array_equal(F2, F)
    with pytest.raises(HoleFillError, match=f"vertices {v} and {copy} coincide"):
        hole_context(V, F, hole)


def test_merging_close_vertices_leaves_no_hole_where_a_face_was_cut_loose():
    V, F, _ = _with_face_cut_loose_at_a_corner()
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F))
    ms.meshing_merge_close_vertices()
    assert boundary_loops(mesh_arrays(ms)[1]) == []
