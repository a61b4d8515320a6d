"""The pipeline through the MeshSet filters: self-intersection check, open chains, clashing patches, second pass."""
import numpy as np
import pymeshlab
import pytest

import meshlab_holefill  # noqa: F401  (registers the filters)
from meshlab_holefill.geometry.intersections import faces_intersecting
from meshlab_holefill.core.crossings import face_boxes_near, patch_intersections
from meshlab_holefill.core.parameters import resolve_params
from meshlab_holefill.core.pipeline import COMMON_PARAMS
from meshlab_holefill.meshlab.close_holes import close_holes
from meshlab_holefill.core.holes import boundary_halfedges, boundary_loops, nonmanifold_edges
from meshlab_holefill.core.parallel import available_workers
from meshlab_holefill.core.patch import Patch, validate_patch

from conftest import cut_disks, grid, mesh_arrays, meshset_from_arrays, sphere_with_holes

FILTERS = ["meshing_close_holes_min_angle_bilateral", "meshing_close_holes_curve_unfolding",
           "meshing_close_holes_lssvm_poisson", "meshing_close_holes_differential_evolution"]


def _plane_with_pierced_hole():
    """A flat grid with two holes; a thin closed tetrahedron pierces the first one only."""
    V, F = grid(21, 21)
    V, F, _ = cut_disks(V, F, [(0.3, 0.5, 0), (0.75, 0.5, 0)], 0.12)
    k = len(V)
    tetra = np.array([[0.3, 0.5, -0.2], [0.3, 0.5, 0.2], [0.25, 0.45, 0.01], [0.35, 0.55, -0.01]])
    V = np.concatenate([V, tetra])
    F = np.concatenate([F, k + np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])])
    return V, F


@pytest.mark.parametrize("name", FILTERS)
def test_patch_through_the_mesh_is_rejected_not_merged(name):
    V, F = _plane_with_pierced_hole()
    ms = meshset_from_arrays(V, F)
    res = getattr(ms, name)(maxholesize=30)  # the 80-edge outer border stays open
    assert res["closed_holes"] == 1 and res["failed_holes"] == 1, res["holes"]
    pierced = next(h for h in res["holes"] if h["status"] == "failed")
    assert "intersect" in pierced["reason"]
    V2, F2 = mesh_arrays(ms)
    np.testing.assert_array_equal(V2[:len(V)], V)
    np.testing.assert_array_equal(F2[:len(F)], F)
    # the pierced hole is left open: its border edges are still boundary edges
    assert sorted(len(loop) for loop in boundary_loops(F2)) == [20, 80]


def test_selfintersection_off_fills_the_pierced_hole():
    V, F = _plane_with_pierced_hole()
    ms = meshset_from_arrays(V, F)
    res = ms.meshing_close_holes_lssvm_poisson(selfintersection=False, split_boundary=False, maxholesize=30)
    assert res["failed_holes"] == 0 and res["closed_holes"] == 2


def test_a_lone_triangle_is_an_outline_whose_one_fill_is_refused():
    """A lone triangle's border is a 3-edge loop; capping it would duplicate the triangle."""
    V, F = grid(8, 8)
    k = len(V)
    V = np.concatenate([V, [[3.0, 0, 0], [4.0, 0, 0], [3.0, 1.0, 0]]])
    F = np.concatenate([F, [[k, k + 1, k + 2]]])
    ms = meshset_from_arrays(V, F)
    for filloutlines in (False, True):
        res = ms.meshing_close_holes_min_angle_bilateral(maxholesize=10, filloutlines=filloutlines)
        (entry,) = [h for h in res["holes"] if h["boundary_edges"] == 3]
        assert (entry["status"], entry["size_class"]) == ("skipped", "outline")
        assert "outlines a single face" in entry["reason"]
        assert len(mesh_arrays(ms)[1]) == len(F)


def _hole_with_a_hanging_triangle():
    """A sphere with the fan of one vertex removed, and a triangle in the hole held by one rim vertex."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    V, F = mesh_arrays(ms)
    fan = np.flatnonzero((F == 5).any(axis=1))
    rim = np.setdiff1d(np.unique(F[fan]), [5])
    centre, corner = V[5], V[rim[0]]
    k = len(V)
    V = np.concatenate([V, [centre * 0.98 + (corner - centre) * 0.2,
                            centre * 0.98 + np.cross(centre, corner - centre) * 0.3]])
    F = np.concatenate([np.delete(F, fan, axis=0), [[rim[0], k, k + 1]]])
    return V, F


@pytest.mark.parametrize("selfintersection", [True, False])
@pytest.mark.parametrize("name", FILTERS)
def test_a_pinched_triangle_outline_is_refused_and_the_hole_around_it_closed(name, selfintersection):
    """The hanging triangle's loop touches the mesh at one vertex: not an island, yet its only fill is that
    triangle again, which no crossing test sees; it is refused by name, and no face is doubled."""
    V, F = _hole_with_a_hanging_triangle()
    assert sorted(len(loop) for loop in boundary_loops(F)) == [3, 6]
    ms = meshset_from_arrays(V, F)
    res = getattr(ms, name)(selfintersection=selfintersection)
    (outline,) = [h for h in res["holes"] if h["boundary_edges"] == 3]
    assert outline["status"] == "skipped" and "outlines a single face" in outline["reason"]
    V2, F2 = mesh_arrays(ms)
    assert len(np.unique(np.sort(F2, axis=1), axis=0)) == len(F2)
    assert [len(loop) for loop in boundary_loops(F2)] == [3]


@pytest.mark.parametrize("name", FILTERS)
def test_a_curved_fragment_is_not_capped_unless_asked(name):
    """A loose spherical cap beside the mesh: its rim outlines the whole fragment (before, it was capped)."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    V, F = mesh_arrays(ms)
    cap = F[V[F].mean(axis=1)[:, 2] > 0.6]
    used = np.unique(cap)
    remap = np.full(len(V), -1)
    remap[used] = np.arange(len(used))
    Vc, Fc = V[used], remap[cap]
    Vg, Fg = grid(6, 6)
    Vg = Vg * 0.5 + [3.0, 0, 0]
    Vall, Fall = np.concatenate([Vg, Vc]), np.concatenate([Fg, Fc + len(Vg)])
    res = getattr(meshset_from_arrays(Vall, Fall), name)()
    (entry,) = [h for h in res["holes"] if h["centroid"][2] > 0.5]  # the cap's rim (the grid's border is one too)
    assert (entry["status"], entry["size_class"]) == ("skipped", "outline") and res["new_faces"] == 0
    capped = getattr(meshset_from_arrays(Vall, Fall), name)(filloutlines=True)
    assert [h["status"] for h in capped["holes"] if h["hole"] == entry["hole"]] != ["skipped"]


def test_every_closed_loop_reports_where_it_is_and_how_large():
    V, F, _ = sphere_with_holes(subdiv=3)
    res = meshset_from_arrays(V, F).meshing_close_holes_min_angle_bilateral()
    for h in res["holes"]:
        loop_points = V[[lp for lp in boundary_loops(F)][h["hole"]].vertices]
        np.testing.assert_allclose(h["centroid"], loop_points.mean(axis=0), rtol=1e-12, atol=1e-15)
        assert h["size_class"] == "hole" and 0 < h["area"] < np.pi * h["diameter"] ** 2 / 4 + 1e-9
        assert h["perimeter"] >= 2 * h["diameter"] - 1e-9


def test_the_run_reports_its_seconds_by_stage_in_order_adding_up_to_the_whole():
    from meshlab_holefill import fill_holes

    V, F, _ = sphere_with_holes(subdiv=3)
    res = meshset_from_arrays(V, F).meshing_close_holes_min_angle_bilateral()
    assert list(res["stage_seconds"]) == ["read layer", "edge table", "boundary loops", "hole selection", "kernels",
                                          "holes", "attributes", "write layer"]
    assert all(t >= 0 for t in res["stage_seconds"].values())
    assert sum(res["stage_seconds"].values()) == pytest.approx(res["seconds"], abs=0.01)
    # On arrays there is no layer to read or write.
    result = fill_holes(V, F, "meshing_close_holes_min_angle_bilateral")[2]
    assert list(result["stage_seconds"]) == ["edge table", "boundary loops", "hole selection", "kernels", "holes",
                                             "attributes"]
    assert sum(result["stage_seconds"].values()) <= result["seconds"]


def test_a_diameter_bound_skips_wider_holes_as_a_length_or_a_percentage():
    V, F, _ = sphere_with_holes(subdiv=3)
    diameters = sorted(h["diameter"] for h in meshset_from_arrays(V, F).meshing_close_holes_min_angle_bilateral(
        maxholesize=3)["holes"])
    cut = (diameters[0] + diameters[1]) / 2 if diameters[1] > diameters[0] else diameters[0] * 0.99
    res = meshset_from_arrays(V, F).meshing_close_holes_min_angle_bilateral(maxholediameter=pymeshlab.PureValue(cut))
    assert sum(h["status"] == "skipped" and "maxholediameter" in h["reason"] for h in res["holes"]) >= 1
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    res = meshset_from_arrays(V, F).meshing_close_holes_min_angle_bilateral(
        maxholediameter=pymeshlab.PercentageValue(100 * cut / diag))
    assert sum("maxholediameter" in h.get("reason", "") for h in res["holes"]) >= 1


# ------------------------------------------------------------- open chains (inconsistent orientation)

def _grid_with_flipped_hole_border():
    """A 6 x 6 grid with a 10-edge hole whose border face of one loop edge is flipped.

    The hole's border then breaks into two open chains (9 edges and 1 edge), see
    test_holes.test_flipped_border_face_turns_the_hole_into_open_chains.
    """
    V, F = grid(6, 6)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0)], 0.25)
    inner = boundary_loops(F)[1]
    F = F.copy()
    F[inner.border_faces[0]] = F[inner.border_faces[0]][::-1]
    return V, F, inner


def test_open_boundary_chain_is_skipped_and_the_mesh_left_unchanged():
    V, F, inner = _grid_with_flipped_hole_border()
    ms = meshset_from_arrays(V, F)
    # maxholesize 12 skips the 20-edge outer border and would admit the 10-vertex chain
    res = ms.meshing_close_holes_min_angle_bilateral(maxholesize=12)
    chains = [h for h in res["holes"] if h["boundary_edges"] <= 12]
    assert len(chains) == 2
    for h in chains:
        assert h["status"] == "skipped" and "open boundary chain" in h["reason"], h
    assert (res["closed_holes"], res["failed_holes"], res["skipped_holes"]) == (0, 0, 3)
    assert res["new_faces"] == 0 and res["new_vertices"] == 0
    V2, F2 = mesh_arrays(ms)
    np.testing.assert_array_equal(V2, V)
    np.testing.assert_array_equal(F2, F)


def test_the_repair_an_open_chain_names_turns_it_into_a_hole_that_closes():
    V, F, inner = _grid_with_flipped_hole_border()
    ms = meshset_from_arrays(V, F)
    res = ms.meshing_close_holes_min_angle_bilateral(maxholesize=12)
    (reason,) = {h["reason"] for h in res["holes"] if h["boundary_edges"] <= 12}
    repair = reason.split("run ")[1].split()[0]
    assert repair == "meshing_re_orient_faces_coherently"
    getattr(ms, repair)()
    res = ms.meshing_close_holes_min_angle_bilateral(maxholesize=12)
    (hole,) = [h for h in res["holes"] if h["boundary_edges"] <= 12]
    assert hole["boundary_edges"] == len(inner) and hole["status"] == "closed"


def test_reported_boundary_edges_add_up_to_the_mesh_boundary_on_open_chains():
    V, F, inner = _grid_with_flipped_hole_border()
    res = meshset_from_arrays(V, F).meshing_close_holes_min_angle_bilateral(maxholesize=12)
    # 20 outer edges + the hole's 10 edges (in chains of 9 and 1)
    assert sum(h["boundary_edges"] for h in res["holes"]) == len(boundary_halfedges(F)[0]) == 30


# ------------------------------------------------------------------ patch folding over itself

def _one_cell_hole():
    """A 4 x 4-cell grid with one cell removed: a square 4-edge hole in z = 0, side 0.25."""
    V, F = grid(5, 5)
    _, F, _ = cut_disks(V, F, [(0.375, 0.375, 0)], 0.1)
    outer, inner = boundary_loops(F)
    return V, F, inner.vertices


# Two new vertices p = 4, q = 5 over a square loop 0..3: gables (1, 2, q) and (3, 0, p),
# slopes (0, 1, q) + (0, q, p) and (2, 3, p) + (2, p, q). A valid patch either way.
ROOF_FACES = np.array([[0, 1, 5], [0, 5, 4], [2, 3, 4], [2, 4, 5], [1, 2, 5], [3, 0, 4]])


def _roof(P, folded):
    """Roof patch over the square loop P (patch orientation, normal up).

    Unfolded: the ridge p-q runs parallel to edge 0-1 above the hole. Folded: p is pushed out
    beyond edge 0-1 and q beyond edge 2-3, so slope (0, 1, q) climbs over the hole to the back
    while (2, 3, p) climbs to the front: the two cross in mid-air, well above the mesh.
    """
    c = P.mean(axis=0)
    side = np.linalg.norm(P[1] - P[0])
    up = np.cross(P[1] - P[0], P[3] - P[0])
    up /= np.linalg.norm(up)
    if folded:
        # p 0.1 in front of edge 0-1, q 0.1 behind edge 2-3, both 0.2 up (side 0.25)
        p = c + 1.8 * ((P[0] + P[1]) / 2 - c) + 0.8 * side * up
        q = c + 1.8 * ((P[2] + P[3]) / 2 - c) + 0.8 * side * up
    else:
        p = c + 0.25 * (P[0] - P[1]) + 0.4 * side * up
        q = c + 0.25 * (P[1] - P[0]) + 0.4 * side * up
    return Patch(np.stack([p, q]), ROOF_FACES.copy())


def _patch_hits(V, F, loop, patch):
    points = patch.all_points(V[loop])
    lo, hi = points.min(axis=0), points.max(axis=0)
    candidates = face_boxes_near(V, F, np.stack([lo - 1e-9, hi + 1e-9])[None])
    return patch_intersections(points, patch.faces, V, F, candidates, loop)


def test_patch_folding_over_itself_is_reported_though_clear_of_the_mesh():
    V, F, loop = _one_cell_hole()
    P = V[loop]
    roof, folded = _roof(P, folded=False), _roof(P, folded=True)
    for patch in (roof, folded):
        validate_patch(patch, P)  # both are topologically sound: only geometry tells them apart
        assert patch.vertices[:, 2].min() == pytest.approx(0.1 if patch is roof else 0.2)  # above the mesh (z = 0)
    assert len(_patch_hits(V, F, loop, roof)) == 0
    # The folded patch meets no mesh face (tested against the mesh faces alone) ...
    to_global = np.concatenate([loop, len(V) + np.arange(len(folded.vertices))])
    allF = np.concatenate([to_global[folded.faces], F])
    q = len(folded.faces)
    assert len(faces_intersecting(np.concatenate([V, folded.vertices]), allF, np.arange(q), np.arange(q, len(allF)))) == 0
    hits = _patch_hits(V, F, loop, folded)
    # ... but its slopes (0, 1, q) and (2, 3, p) cross each other in mid-air
    assert {0, 2} <= set(hits.tolist()), hits


COMMON = {**resolve_params(COMMON_PARAMS, {}, "test", bbox_diagonal=1e300), "maxholesize": 4}


def test_pipeline_rejects_a_patch_folding_over_itself():
    V, F, loop = _one_cell_hole()
    ms = meshset_from_arrays(V, F)
    res = close_holes(ms, lambda ctx: _roof(ctx.points, folded=True), COMMON)  # maxholesize 4: the border is skipped
    (hole,) = [h for h in res["holes"] if h["boundary_edges"] == 4]
    assert hole["status"] == "failed" and "intersect" in hole["reason"], hole
    assert res["closed_holes"] == 0 and res["new_faces"] == 0
    V2, F2 = mesh_arrays(ms)
    np.testing.assert_array_equal(V2, V)
    np.testing.assert_array_equal(F2, F)
    # the same hole with the unfolded roof is closed
    res = close_holes(meshset_from_arrays(V, F), lambda ctx: _roof(ctx.points, folded=False), COMMON)
    assert res["closed_holes"] == 1 and res["new_faces"] == 6 and res["new_vertices"] == 2


# ------------------------------------------------------------------ patches clashing with each other

def _two_wedges_and_a_square_hole():
    """Two holes sharing two pinched vertices, plus an unrelated hole.

    Of an octahedron (0: +x, 1: -x, 2: +y, 3: -y, 4: +z, 5: -z) only the wedges (+x, -y, +-z) and
    (-x, +y, +-z) are kept: the wedges meet at +z and -z only, and their 8 border edges form two
    4-edge holes through both poles, with no mesh edge between the poles. Beside it lies a grid
    with a one-cell hole.
    """
    V = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    F = np.array([[4, 3, 0], [0, 3, 5], [4, 2, 1], [1, 2, 5]])
    Vg, Fg, square = _one_cell_hole()
    return np.concatenate([V, Vg + [5, 0, 0]]), np.concatenate([F, Fg + len(V)]), square + len(V)


def _split_at_the_poles(ctx):
    """Two triangles per 4-edge hole, split by the chord between the poles 4 and 5 where the loop has both."""
    loop = ctx.loop.tolist()
    i = loop.index(4) if {4, 5} <= set(loop) else 0
    j = (i + 2) % 4
    return Patch(np.zeros((0, 3)), np.array([[i, (i + 1) % 4, j], [j, (j + 1) % 4, i]]))


def test_of_two_patches_sharing_a_chord_the_first_is_kept_and_the_rest_closed():
    V, F, square = _two_wedges_and_a_square_hole()
    loops = boundary_loops(F)
    assert sorted((len(lp), bool(lp.pinched)) for lp in loops) == [(4, False), (4, True), (4, True), (16, False)]
    ms = meshset_from_arrays(V, F)
    res = close_holes(ms, _split_at_the_poles, {**COMMON, "filloutlines": True})  # each wedge pair outlines itself
    # Alone, each pole hole's patch is valid; together they put 4 faces on the chord 4-5.
    # The first (hole 1) is kept, the second withdrawn whole; the square hole is closed.
    outcome = [(h["hole"], h["boundary_edges"], h["pinched"], h["status"]) for h in res["holes"]]
    assert outcome == [(0, 16, False, "skipped"), (1, 4, True, "closed"), (2, 4, True, "failed"),
                       (3, 4, False, "closed")]
    failed = res["holes"][2]
    assert "clashes with another patch" in failed["reason"] and "new_faces" not in failed
    assert (res["closed_holes"], res["failed_holes"], res["skipped_holes"]) == (2, 1, 1)
    assert res["new_faces"] == 4 and res["new_vertices"] == 0
    V2, F2 = mesh_arrays(ms)
    np.testing.assert_array_equal(V2, V)
    np.testing.assert_array_equal(F2[:len(F)], F)
    assert len(nonmanifold_edges(F2)) == 0
    assert set(square.tolist()) <= set(F2[len(F):].ravel().tolist())
    # the second pole hole stays open, the first and the square hole are gone
    left = boundary_loops(F2)
    assert sorted(len(lp) for lp in left) == [4, 16]
    assert {tuple(sorted(lp.vertices.tolist())) for lp in left if len(lp) == 4} == {
        tuple(sorted(loops[2].vertices.tolist()))}


def _sphere_with_an_unfillable_hole():
    """A 12-edge hole on top with a zero-length border edge (it cannot be filled) and a 36-edge one below."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    V, F = mesh_arrays(ms)
    C = V[F].mean(axis=1)
    top = np.unique(F[(F == 0).any(axis=1)])
    F = F[~np.isin(F, top).any(axis=1) & (C[:, 2] > -0.8)]
    loops = boundary_loops(F)
    assert sorted(len(lp) for lp in loops) == [12, 36]
    small = next(lp.vertices for lp in loops if len(lp) == 12)
    V = V.copy()
    V[small[1]] = V[small[0]]
    return V, F, small


def test_a_hole_that_fails_after_its_border_was_refined_is_left_as_it_was():
    """LS-SVM refines long border edges before filling (Sec. 3.1); a hole that then fails is
    left exactly as it was (the filter fills again without it), and the other hole closes."""
    V, F, small = _sphere_with_an_unfillable_hole()
    ms = meshset_from_arrays(V, F)
    res = ms.meshing_close_holes_lssvm_poisson()
    status = {h["boundary_edges"]: h for h in res["holes"]}
    assert status[12]["status"] == "failed" and status[12]["split_boundary_edges"] == 0
    assert status[36]["status"] == "closed"
    V1, F1 = mesh_arrays(ms)
    np.testing.assert_array_equal(V1[:len(V)], V)
    assert res["split_boundary_edges"] == status[36]["split_boundary_edges"]
    # the failed hole's loop is still there, unchanged
    left = boundary_loops(F1)
    assert [sorted(lp.vertices.tolist()) for lp in left] == [sorted(small.tolist())]


def test_the_second_pass_does_not_fill_again_a_hole_whose_surroundings_are_unchanged(monkeypatch):
    from meshlab_holefill.algorithms.xu2013 import lssvm_poisson

    V, F, _ = _sphere_with_an_unfillable_hole()
    fill, sizes = lssvm_poisson.fill, []

    def counting_fill(ctx, **kwargs):
        sizes.append(ctx.size)
        return fill(ctx, **kwargs)

    from meshlab_holefill.core import pipeline as hole_filter

    key = hole_filter._context_key
    monkeypatch.setattr(hole_filter, "_context_key", lambda ctx: object())  # never equal: every pass refills
    reference = meshset_from_arrays(V, F)
    reference.meshing_close_holes_lssvm_poisson()
    monkeypatch.setattr(hole_filter, "_context_key", key)
    monkeypatch.setattr(lssvm_poisson, "fill", counting_fill)
    ms = meshset_from_arrays(V, F)
    res = ms.meshing_close_holes_lssvm_poisson(workers=1)  # counted in this process
    # pass 1 fills the large hole and refuses the small one (split to 13 edges) before its fill, for its
    # zero-length border edge; pass 2, without the failed hole's split, finds the large hole's
    # surroundings unchanged and reuses its patch
    assert sizes == [36]
    assert [h["status"] for h in sorted(res["holes"], key=lambda h: h["boundary_edges"])] == ["failed", "closed"]
    np.testing.assert_array_equal(ms.current_mesh().vertex_matrix(), reference.current_mesh().vertex_matrix())
    np.testing.assert_array_equal(ms.current_mesh().face_matrix(), reference.current_mesh().face_matrix())


def _tent_over_the_other_hole(ctx):
    """A fan from the 4-edge loop to one apex 0.3 above the centre of the other hole (x mirrored about 0.5)."""
    c = ctx.points.mean(axis=0)
    apex = np.array([[1.0 - c[0], c[1], 0.3]])
    k = ctx.size
    return Patch(apex, np.array([[i, (i + 1) % k, k] for i in range(k)]))


def test_of_two_patches_crossing_in_mid_air_the_first_is_kept():
    """Each tent alone is clear of the mesh; together they cross above the strip between the holes."""
    V, F = grid(9, 9)
    _, F, _ = cut_disks(V, F, [(0.3125, 0.4375, 0), (0.6875, 0.4375, 0)], 0.05)
    loops = boundary_loops(F)
    assert sorted(len(lp) for lp in loops) == [4, 4, 32]
    ms = meshset_from_arrays(V, F)
    res = close_holes(ms, _tent_over_the_other_hole, COMMON)
    holes = [h for h in res["holes"] if h["boundary_edges"] == 4]
    assert [h["status"] for h in holes] == ["closed", "failed"]
    assert holes[1]["reason"] == f"patch would intersect the patch of hole {holes[0]['hole']}"
    V2, F2 = mesh_arrays(ms)
    assert len(F2) == len(F) + 4 and len(V2) == len(V) + 1
    assert len(faces_intersecting(V2, F2, np.arange(len(F), len(F2)), np.arange(len(F2)))) == 0
    # without the check (selfintersection=False) both tents go in, crossing each other
    ms = meshset_from_arrays(V, F)
    res = close_holes(ms, _tent_over_the_other_hole, dict(COMMON, selfintersection=False))
    V3, F3 = mesh_arrays(ms)
    assert res["closed_holes"] == 2
    assert len(faces_intersecting(V3, F3, np.arange(len(F), len(F3)), np.arange(len(F3)))) > 0


# ------------------------------------------------------------- holes filled in worker processes

@pytest.mark.parametrize("name", FILTERS)
def test_the_mesh_is_the_same_whatever_the_number_of_workers(name):
    V, F, _ = sphere_with_holes(subdiv=3, centers=((1, 0, 0), (0, 0, 1), (0, -1, 0), (-0.6, 0.6, -0.5)), radius=0.3)
    meshes = []
    for workers in (1, 2):
        ms = meshset_from_arrays(V, F)
        res = getattr(ms, name)(workers=workers)
        meshes.append((mesh_arrays(ms), [(h["status"], h.get("new_faces")) for h in res["holes"]]))
    (one, statuses_one), (two, statuses_two) = meshes
    assert statuses_one == statuses_two and all(s == "closed" for s, _ in statuses_one)
    np.testing.assert_array_equal(one[0], two[0])
    np.testing.assert_array_equal(one[1], two[1])


@pytest.mark.skipif(available_workers() < 2, reason="needs two CPUs and fork")
def test_with_workers_each_hole_is_prepared_filled_and_checked_by_one_process(monkeypatch):
    """Each hole's context is built by the process that fills it, and this process fills holes too."""
    import os

    from meshlab_holefill.core import pipeline

    V, F, _ = _one_cell_hole()
    copies = 6
    V, F = np.concatenate([V + [2 * c, 0, 0] for c in range(copies)]), np.concatenate([F + c * len(V) for c in range(copies)])
    built = pipeline.hole_context

    def context_noting_its_process(*args, **kwargs):
        ctx = built(*args, **kwargs)
        ctx.extra["built_by"] = os.getpid()
        return ctx

    def slow_roof_noting_its_process(ctx):
        import time

        time.sleep(0.05)  # long enough for the forked child to take holes too
        patch = _roof(ctx.points, folded=False)
        patch.info.update(built_by=ctx.extra["built_by"], filled_by=os.getpid())
        return patch

    monkeypatch.setattr(pipeline, "hole_context", context_noting_its_process)
    res = close_holes(meshset_from_arrays(V, F), slow_roof_noting_its_process, dict(COMMON, workers=2))
    holes = [h for h in res["holes"] if h["boundary_edges"] == 4]
    assert len(holes) == copies and all(h["status"] == "closed" for h in holes)
    assert all(h["built_by"] == h["filled_by"] for h in holes)
    assert os.getpid() in {h["filled_by"] for h in holes} and len({h["filled_by"] for h in holes}) == 2


def _slow_roof(ctx):
    import time

    if len(ctx.loop) > 8:  # working in Python lines, where a time limit can stop it
        deadline = time.perf_counter() + 5
        while time.perf_counter() < deadline:
            pass
    return _roof(ctx.points, folded=False)


@pytest.mark.parametrize("workers", [1, 2])
def test_a_hole_over_the_time_limit_fails_and_the_others_are_filled(workers):
    V, F, square = _two_wedges_and_a_square_hole()
    Vs, Fs, _ = sphere_with_holes(subdiv=3, centers=((1, 0, 0),), radius=0.3)
    V, F = np.concatenate([V, Vs + [0, 10, 0]]), np.concatenate([F, Fs + len(V)])
    params = {**COMMON, "maxholesize": 100, "timelimit": 0.5, "workers": workers}
    res = close_holes(meshset_from_arrays(V, F), _slow_roof, params)
    slow = [h for h in res["holes"] if h["boundary_edges"] > 8 and h["status"] != "skipped"]
    assert slow and all(h["status"] == "failed" and "time limit of 0.5 s" in h["reason"] for h in slow)
    assert any(h["status"] == "closed" for h in res["holes"])


def test_workers_check_their_own_patches_against_the_mesh_with_the_same_verdicts():
    """With workers each patch is checked against the mesh by the worker that filled it: same mesh, same reasons."""
    V, F, _ = _one_cell_hole()
    V, F = np.concatenate([V, V + [2, 0, 0], V + [4, 0, 0]]), np.concatenate([F, F + len(V), F + 2 * len(V)])

    def roof_folded_in_the_middle_grid(ctx):
        return _roof(ctx.points, folded=bool(1.5 < ctx.points[:, 0].mean() < 3.5))

    outcomes = []
    for workers in (1, 2):
        ms = meshset_from_arrays(V, F)
        res = close_holes(ms, roof_folded_in_the_middle_grid, dict(COMMON, workers=workers))
        outcomes.append((mesh_arrays(ms), [(h["status"], h.get("reason"), h.get("new_faces"))
                                           for h in res["holes"] if h["boundary_edges"] == 4]))
    (one, holes_one), (two, holes_two) = outcomes
    assert holes_one == holes_two
    assert sorted(status for status, _, _ in holes_one) == ["closed", "closed", "failed"]
    assert any(reason and "intersect the mesh" in reason for _, reason, _ in holes_one)
    np.testing.assert_array_equal(one[0], two[0])
    np.testing.assert_array_equal(one[1], two[1])
