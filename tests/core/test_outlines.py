"""core.outlines: island outlines against holes, and a loop's measures."""
import numpy as np
import scipy.sparse as sp
import pymeshlab
import pytest
from hypothesis import given, settings, strategies as st

from meshlab_holefill.core.holes import boundary_loops, vertex_face_incidence
from meshlab_holefill.core.outlines import loop_measures

from conftest import cut_disks, grid


def test_loop_measures_of_a_planar_circle():
    t = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    P = np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], 1)
    m = loop_measures(P)
    assert m["planarity"] == pytest.approx(0, abs=1e-12)
    assert m["diameter"] == pytest.approx(2, rel=1e-3)
    assert m["perimeter"] == pytest.approx(2 * np.pi, rel=1e-2)


def _is_outline_ring_by_ring(V, F, loop, incidence):
    """The outline test grown one ring of faces at a time by sparse row gathers (the reference; no pinch vertex)."""
    from meshlab_holefill.core.outlines import loop_facings, outline_budgets, vector_area
    from meshlab_holefill.geometry.quality import face_areas

    budget = outline_budgets([vector_area(V[np.asarray(loop.vertices)])], loop_facings(V, F, [loop]))[0]
    frontier = np.unique(np.asarray(loop.border_faces, np.int64))
    seen = np.zeros(len(F), bool)
    seen[frontier] = True
    area = face_areas(V, F[frontier]).sum()
    while area <= budget:
        near = incidence[np.unique(F[frontier])].indices
        frontier = np.unique(near[~seen[near]])
        if len(frontier) == 0:
            return True
        seen[frontier] = True
        area += face_areas(V, F[frontier]).sum()
    return False


def _islands_and_holes():
    """A grid with two holes, plus a lone triangle and a small square island beside it."""
    V, F = grid(12, 12)
    _, F, _ = cut_disks(V, F, [(0.3, 0.3, 0), (0.7, 0.6, 0)], 0.12)
    Vi, Fi = grid(3, 3)
    tri_V = np.array([[2.0, 0, 0], [2.2, 0, 0], [2.0, 0.2, 0]])
    V2 = np.concatenate([V, Vi * 0.3 + [1.5, 0, 0.1], tri_V])
    F2 = np.concatenate([F, Fi + len(V), np.array([[0, 1, 2]]) + len(V) + len(Vi)])
    return V2, F2


def test_compiled_outline_test_matches_the_ratio_and_the_ring_by_ring_growth():
    from meshlab_holefill.core.outlines import is_outline, outline_mask

    V, F = _islands_and_holes()
    loops = boundary_loops(F)
    incidence = vertex_face_incidence(F, len(V))
    compiled = [is_outline(V, F, loop, incidence) for loop in loops]
    ring_by_ring = [_is_outline_ring_by_ring(V, F, loop, incidence) for loop in loops]
    assert compiled == ring_by_ring == outline_mask(V, F, loops).tolist()
    assert sum(compiled) == 3  # the grid's outer rim and both islands; the two holes are not outlines


def test_grown_area_is_the_component_area_within_the_budget():
    from meshlab_holefill.core.outlines import _grown_area
    from meshlab_holefill.geometry.quality import face_areas

    V, F = _islands_and_holes()
    incidence = vertex_face_incidence(F, len(V))
    island = np.arange(len(F) - 9, len(F) - 1)  # the square island's eight faces
    area = face_areas(V, F[island]).sum()
    start = island[:1]
    pinch = np.zeros(len(V), bool)
    assert _grown_area(incidence.indptr, incidence.indices, V, F, pinch, start, 2 * area) == pytest.approx(area,
                                                                                                          rel=1e-12)
    assert _grown_area(incidence.indptr, incidence.indices, V, F, pinch, start, 0.5 * area) == -1.0


def _scan_with_debris(seed, islands):
    """A grid with holes and ``islands`` small square fragments (a range scan's debris) around it."""
    rng = np.random.default_rng(seed)
    V, F = grid(14, 14)
    _, F, _ = cut_disks(V, F, [(0.3, 0.3, 0), (0.7, 0.65, 0)], 0.1 + 0.05 * rng.random())
    Vi, Fi = grid(2 + seed % 3, 2 + seed % 3)
    parts_V, parts_F = [V], [F]
    count = len(V)
    for corner in rng.uniform(1.2, 3.0, (islands, 3)):
        parts_V.append(Vi * rng.uniform(0.05, 0.2) + corner)
        parts_F.append(Fi + count)
        count += len(Vi)
    return np.concatenate(parts_V), np.concatenate(parts_F)


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 10_000), islands=st.integers(0, 40))
def test_loops_measured_and_classed_at_once_as_one_by_one(seed, islands):
    from meshlab_holefill.core.outlines import hole_measures, holes_measures, loop_class, loop_classes, loops_measured

    V, F = _scan_with_debris(seed, islands)
    loops = [loop for loop in boundary_loops(F) if loop.closed and len(loop) >= 3]
    incidence = vertex_face_incidence(F, len(V))
    together = holes_measures(V, loops)
    classes = loop_classes(V, F, loops, incidence, [m["area"] for m in together])
    assert classes == [loop_class(V, F, loop, incidence) for loop in loops]
    # every growth stopped at once: the loops decided on the labelled components' areas
    assert loop_classes(V, F, loops, incidence, [m["area"] for m in together], growth_cap=0) == classes
    # and as the pipeline asks for them, by loop index, the measurable loops only
    every = boundary_loops(F)
    measured = loops_measured(V, F, every, incidence)
    assert sorted(measured) == [i for i, loop in enumerate(every) if loop.closed and len(loop) >= 3]
    assert [measured[i] for i in sorted(measured)] == list(zip(together, classes))
    assert classes.count("hole") == 2 and classes.count("outline") == islands + 1  # the grid's rim too
    for loop, measures in zip(loops, together):
        alone = hole_measures(V, loop)
        assert list(measures) == list(alone)
        for key in ("centroid", "perimeter", "diameter", "area"):
            np.testing.assert_allclose(measures[key], alone[key], rtol=1e-12, atol=1e-15)
        assert measures["planarity"] == pytest.approx(alone["planarity"], abs=1e-7)  # 0 but for rounding
    assert holes_measures(V, []) == [] and loop_classes(V, F, [], incidence) == []


def test_vector_area_has_np_cross_bits_and_is_exact_for_a_planar_square():
    from meshlab_holefill.core.outlines import vector_area

    rng = np.random.default_rng(3)
    for k in (3, 17, 400):
        P = rng.normal(size=(k, 3)) * 10.0 ** rng.integers(-3, 4)
        Q = P - P[0]  # taken about the loop's first vertex
        assert vector_area(P) == float(0.5 * np.linalg.norm(np.cross(Q, np.roll(Q, -1, axis=0)).sum(axis=0)))
    square = np.array([[0.0, 0, 1], [2, 0, 1], [2, 2, 1], [0, 2, 1]])
    assert vector_area(square) == 4.0


@settings(max_examples=30, deadline=None)
@given(offset=st.floats(-1e9, 1e9), scale=st.sampled_from([1e-3, 1.0, 1e3]))
def test_far_from_the_origin_holes_keep_their_area_and_are_not_taken_for_outlines(offset, scale):
    # Georeferenced scans: a 1-unit model 1e8 from the origin had every hole taken for an
    # island outline (the vector area of raw coordinates cancelled to noise).
    from meshlab_holefill.core.outlines import is_outline, outline_mask, vector_area

    V, F = _islands_and_holes()
    loops = boundary_loops(F)
    incidence = vertex_face_incidence(F, len(V))
    expected = [is_outline(V, F, loop, incidence) for loop in loops]
    areas = [vector_area(V[loop.vertices]) for loop in loops]
    W = V * scale + offset
    assert [is_outline(W, F, loop, incidence) for loop in loops] == expected
    assert outline_mask(W, F, loops).tolist() == expected
    rounding = np.spacing(abs(offset)) / scale  # the coordinates themselves are rounded by this much (per unit)
    for loop, area in zip(loops, areas):
        assert vector_area(W[loop.vertices]) == pytest.approx(area * scale**2, rel=1e-9 + 100 * rounding)


def test_a_three_edge_loop_outlines_one_face_only_when_one_face_holds_all_its_edges():
    from meshlab_holefill.core.outlines import outlines_one_face

    V, F = grid(5, 5)
    lone = np.concatenate([F, [[len(V), len(V) + 1, len(V) + 2]]])
    triangle = [lp for lp in boundary_loops(lone) if len(lp) == 3]
    assert len(triangle) == 1 and outlines_one_face(triangle[0])
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=2)
    Fs = ms.current_mesh().face_matrix()
    (hole,) = boundary_loops(np.delete(Fs, 0, axis=0))  # one face removed: its three neighbours hold the edges
    assert len(hole) == 3 and not outlines_one_face(hole)
    assert not any(outlines_one_face(lp) for lp in boundary_loops(F))


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 10_000), islands=st.integers(0, 12), held=st.booleans())
def test_component_areas_are_those_of_the_components_the_growth_joins(seed, islands, held):
    from scipy.sparse.csgraph import connected_components

    from meshlab_holefill.core.outlines import _component_areas, pinch_vertices
    from meshlab_holefill.geometry.quality import face_areas
    from meshlab_holefill.geometry.topology import face_adjacency

    V, F = _scan_with_debris(seed, islands)
    if held:  # and a fragment held to the grid's rim by one vertex
        n = len(V)
        V = np.concatenate([V, [[1.1, -0.05, 0.0], [1.15, 0.05, 0.0], [1.05, 0.1, 0.0]]])
        F = np.concatenate([F, [[13, n, n + 1], [13, n + 1, n + 2]]])
    V = np.concatenate([V, [[9.0, 9.0, 9.0]]])  # a vertex of no face
    pinch = pinch_vertices(boundary_loops(F), len(V))
    assert pinch.any() == held
    incidence = vertex_face_incidence(F, len(V))
    roots, area = _component_areas(incidence.indptr, incidence.indices, V, F, pinch, np.arange(len(F)))
    # the reference: faces sharing an edge, or a vertex that is not a pinch vertex
    shared = sp.coo_matrix((np.ones(3 * len(F)), (np.repeat(np.arange(len(F)), 3), F.ravel())),
                           shape=(len(F), len(V))).tocsc()[:, ~pinch]
    joined = (shared @ shared.T + face_adjacency(F)) > 0
    count, label = connected_components(joined, directed=False)
    assert len(np.unique(roots)) == count
    for r in np.unique(roots):
        members = roots == r
        assert len(np.unique(label[members])) == 1
        assert area[r] == pytest.approx(face_areas(V, F[members]).sum(), rel=1e-12)
    assert np.sum(area) == pytest.approx(face_areas(V, F).sum(), rel=1e-12)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10**6), k=st.integers(1, 300), scale=st.sampled_from([1e-3, 1.0, 1e5]),
       offset=st.sampled_from([0.0, 1e7]))
def test_diameter_has_the_bits_of_the_largest_pairwise_norm(seed, k, scale, offset):
    from meshlab_holefill.core.outlines import _diameter

    P = np.random.default_rng(seed).normal(size=(k, 3)) * scale + offset
    want = np.linalg.norm(P[:, None, :] - P[None, :, :], axis=2).max()
    assert _diameter(P) == want and loop_measures(P)["diameter"] == want


def test_diameter_of_more_than_2000_points_is_their_box_diagonal():
    from meshlab_holefill.core.outlines import _diameter

    t = np.linspace(0.0, 2.0 * np.pi, 2001, endpoint=False)
    P = np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], axis=1)
    assert _diameter(P) == np.linalg.norm(P.max(axis=0) - P.min(axis=0)) and _diameter(P[:2000]) <= 2.0


def _sheet_with_fragment():
    """A grid with a hole, and a small square fragment held to the grid's rim by one shared vertex."""
    V, F = grid(10, 10)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0)], 0.2)
    corner = 9  # (1, 0, 0): a vertex of the grid's rim
    square = np.array([[1.0, 0.0, 0.0], [1.1, -0.05, 0.0], [1.15, 0.05, 0.0], [1.05, 0.1, 0.0]])
    V2 = np.concatenate([V, square[1:]])
    n = len(V)
    F2 = np.concatenate([F, np.array([[corner, n, n + 1], [corner, n + 1, n + 2]])])
    return V2, F2


def test_a_fragment_held_by_one_vertex_is_an_outline_of_its_own():
    from meshlab_holefill.core.outlines import loops_measured, outline_mask, pinch_vertices

    V, F = _sheet_with_fragment()
    loops = boundary_loops(F)
    fragment = next(i for i, loop in enumerate(loops) if len(loop) == 4)
    incidence = vertex_face_incidence(F, len(V))
    classes = {i: c for i, (_, c) in loops_measured(V, F, loops, incidence).items()}
    assert classes[fragment] == "outline"
    assert [c for i, c in sorted(classes.items()) if i != fragment].count("hole") == 1  # the grid's hole
    assert outline_mask(V, F, loops, pinch_vertices(loops, len(V)))[fragment]
    # joined through the shared vertex, the fragment was a sliver of the sheet's component
    assert not outline_mask(V, F, loops, np.zeros(len(V), bool))[fragment]


def test_no_filter_caps_a_fragment_held_by_one_vertex():
    from meshlab_holefill import fill_holes

    V, F = _sheet_with_fragment()
    V2, F2, result = fill_holes(V, F, "min_angle_bilateral", workers=1)
    fragment = next(h for h in result["holes"] if h["boundary_edges"] == 4)
    assert fragment["status"] == "skipped" and "island outline" in fragment["reason"]
    assert result["closed_holes"] == 1
    np.testing.assert_array_equal(F2[:len(F)], F)


def _sphere_parts(angle):
    """A unit sphere's faces split by the cap of angular radius ``angle`` round +z: (V, cap faces, the rest)."""
    from meshlab_holefill.evaluation.analytic import analytic_mesh

    V, F = analytic_mesh("sphere")
    in_cap = V[F].mean(axis=1)[:, 2] / np.linalg.norm(V[F].mean(axis=1), axis=1) > np.cos(angle)
    return V, F[in_cap], F[~in_cap]


@settings(max_examples=8, deadline=None)
@given(degrees=st.floats(15.0, 80.0))
def test_a_cap_less_than_a_hemisphere_is_a_sheet_and_the_sphere_without_it_has_a_hole(degrees):
    from meshlab_holefill.core.outlines import loop_classes, loop_facings, outline_ratios

    V, cap, rest = _sphere_parts(np.radians(degrees))
    for F, expected in ((cap, "outline"), (rest, "hole")):
        used = np.unique(F)
        renumber = np.full(len(V), -1)
        renumber[used] = np.arange(len(used))
        W, G = V[used], renumber[F]
        loops = boundary_loops(G)
        assert len(loops) == 1
        incidence = vertex_face_incidence(G, len(W))
        assert loop_classes(W, G, loops, incidence) == [expected]
        # the rim of a cap wider than 41 degrees encloses less than 0.75 of its area: its faces face away
        facing, ratio = loop_facings(W, G, loops)[0], outline_ratios(W, G, loops)[0]
        assert (facing < -0.9 and ratio > 0.5) if expected == "outline" else (facing > 0.9 and ratio < 0.5)


def test_a_hole_in_a_fragment_held_by_one_vertex_stays_a_hole():
    """A ring of faces round a hole, held to a sheet's rim by one vertex: the ring's outer loop is its outline,
    the inner loop a hole, though the ring holds less area than the hole (a range scan's seen ring round an
    unseen patch)."""
    from meshlab_holefill.core.outlines import loops_measured, outline_mask, outline_ratios, pinch_vertices

    V, F = grid(10, 10)
    n = len(V)
    outer = np.array([[1.0, 0.0, 0.0], [1.4, 0.0, 0.0], [1.4, 0.4, 0.0], [1.0, 0.4, 0.0]])
    inner = np.array([[1.05, 0.05, 0.0], [1.35, 0.05, 0.0], [1.35, 0.35, 0.0], [1.05, 0.35, 0.0]])
    V2 = np.concatenate([V, outer[1:], inner])
    o = [9, n, n + 1, n + 2]  # the outer corners, the first the grid's rim vertex (1, 0, 0)
    i = [n + 3, n + 4, n + 5, n + 6]
    ring = [[o[k], o[(k + 1) % 4], i[(k + 1) % 4]] for k in range(4)] + [[o[k], i[(k + 1) % 4], i[k]] for k in range(4)]
    F2 = np.concatenate([F, np.array(ring)])
    loops = boundary_loops(F2)
    sizes = [len(loop) for loop in loops]
    assert sorted(sizes) == [4, 4, 36]
    classes = loops_measured(V2, F2, loops, vertex_face_incidence(F2, len(V2)))
    mask = outline_mask(V2, F2, loops, pinch_vertices(loops, len(V2)))
    ratios = outline_ratios(V2, F2, loops, pinch_vertices(loops, len(V2)))
    for k, loop in enumerate(loops):
        if len(loop) == 4 and 9 not in loop.vertices:  # the hole in the ring
            assert ratios[k] > 1.0 and not mask[k] and classes[k][1] == "hole"
        elif len(loop) == 4:  # the ring's outline
            assert mask[k] and classes[k][1] == "outline"
