"""HPDE Sec. 4.6: the unfolded plane, the triangulation of the prediction points, the layouts and their attempt order."""
import numpy as np
import pymeshlab
import pytest

from meshlab_holefill.algorithms.xie_zou2013 import differential_evolution as hpde
from meshlab_holefill.algorithms.xie_zou2013 import folds as hpde_folds, triangulation as hpde_mesh, prediction as hpde_prediction, sections as hpde_sections, _algorithm2 as hpde_algorithm2
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.core.patch import validate_patch

import hpde_cases
from hpde_cases import check_patch, context

cube_edge_hole = hpde_cases.cube_edge_hole  # the shared module-scoped fixtures
sphere_hole = hpde_cases.sphere_hole


# ----------------------------------------------------------------- step 6: Sec. 4.6

def test_unfolding_two_planes_is_isometric(cube_edge_hole):
    _, _, _, ctx = cube_edge_hole
    base = hpde_sections.base_points(ctx.points, hpde_sections.ring_edge_length(ctx))
    normals = hpde_sections.base_point_normals(ctx.loop_normals, base)
    seg = hpde_sections.segment_boundary(base, normals, np.pi / 2)
    pmap = hpde_mesh.plane_map_for(base, normals, seg, True)
    assert pmap.segmented
    # A point on face y = 0 and one on face z = 0: the unfolded distance is the path over the edge.
    A, B = np.array([[0.5, 0.0, 0.2]]), np.array([[0.6, 0.3, 0.0]])
    a2, b2 = pmap.to_2d(A), pmap.to_2d(B)
    assert np.linalg.norm(a2 - b2) == pytest.approx(np.hypot(0.1, 0.2 + 0.3), rel=1e-9)
    assert pmap.side(A)[0] != pmap.side(B)[0]


def test_triangulation_keeps_every_loop_edge_and_detects_fold_overs(sphere_hole):
    _, _, _, ctx = sphere_hole
    e, base, normals, seg = hpde_algorithm2.boundary_step(ctx, 90.0)  # step 2 with the paper's A_c
    result = hpde_prediction.predict_points(ctx, base, normals, None, np.pi / 15, e,
                                 dict(N_factor=3, F=0.8, CR=0.05, generations=10, seed=0))
    V, F, ids = hpde_mesh.triangulate_layout(ctx, base, normals, seg, "plane", result, e, np.zeros(len(result[0]), bool))
    from meshlab_holefill.core.patch import Patch

    validate_patch(Patch(V[ctx.size:], F), ctx.points, ctx.forbidden_edges)
    assert np.array_equal(V[ctx.size:], result[0][ids])
    pmap = hpde_mesh.plane_map_for(base, normals, seg, False)
    ref = pmap.reference_normals(V, F, 1)
    assert not hpde_folds.fold_overs(V, F, ref).any()
    # Drag one predicted point across its ring within the plane: faces flip and are detected.
    free = np.flatnonzero(np.bincount(F.ravel(), minlength=len(V))[ctx.size:] >= 5)[0] + ctx.size
    nb = np.unique(F[np.any(F == free, axis=1)])
    far = nb[np.argmax(np.linalg.norm(V[nb] - V[free], axis=1))]
    W = V.copy()
    W[free] += 2.5 * (V[far] - V[free])
    assert hpde_folds.fold_overs(W, F, ref).any()
    assert hpde_folds.local_folds(W, F).any() and not hpde_folds.local_folds(V, F).any()


def test_disc_layout_keeps_chords_apart():
    Q, X = hpde_mesh.disc_coordinates(np.arange(12.0), 12.0, 12, np.array([1, 2, 3]), np.array([10, 9, 8]),
                                      np.array([0.5, 0.5, 0.5]))
    assert np.allclose(np.linalg.norm(Q, axis=1), 12 / (2 * np.pi))
    assert np.all(np.diff(X[:, 1]) > 0)  # nested, parallel chords


def test_development_layout_puts_base_points_on_the_developed_loop_and_points_on_their_chords():
    from meshlab_holefill.algorithms.xie_zou2013.sections import BasePoints

    Q = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 1.0], [0.0, 1.0]])  # a strip, 4 by 1
    base = BasePoints(points=np.zeros((4, 3)), edge=np.array([0, 0, 2, 2]), t=np.array([0.25, 0.75, 0.25, 0.75]),
                      perimeter=10.0)
    X = hpde_mesh.development_coordinates(Q, base, np.array([0, 1]), np.array([3, 2]), np.array([0.5, 0.25]))
    # BP_0 = (1, 0), BP_3 = (1, 1); BP_1 = (3, 0), BP_2 = (3, 1): chords straight across the strip
    assert np.allclose(X, [[1.0, 0.5], [3.0, 0.25]])


def _equatorial_band(width=0.1, x_from=-0.5):
    """pymeshlab's unit sphere (subdiv 4) without a band |z| < width round more than half of the equator."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=4)
    V, F = np.asarray(ms.current_mesh().vertex_matrix(), np.float64), ms.current_mesh().face_matrix()
    C = V[F].mean(axis=1)
    F = F[~((np.abs(C[:, 2]) < width) & (C[:, 0] > x_from))]
    (loop,) = boundary_loops(F)
    return hole_context(V, F, loop, rings=hpde.RINGS)


def test_a_long_curved_strip_takes_the_development_layout_where_the_disc_rounds_it(monkeypatch):
    ctx = _equatorial_band()
    patch = hpde.fill(ctx)
    bends = patch.info["border_bends"]
    assert patch.info["layout"] == "development" and bends["development"] < bends["disc"]
    off_sphere = lambda p: np.abs(np.linalg.norm(p.vertices, axis=1) - 1.0).mean()  # noqa: E731
    order = hpde_algorithm2.attempt_order
    monkeypatch.setattr(hpde_algorithm2, "attempt_order", lambda *a: [x for x in order(*a) if x[1] != "development"])
    monkeypatch.setattr(hpde_algorithm2, "_bends_more_than_loop_only", lambda *a: None)  # the disc as it is
    disc = hpde.fill(ctx)
    assert disc.info["layout"] == "disc"
    assert off_sphere(patch) < 0.1 * off_sphere(disc)  # measured 0.00054 and 0.0213


def test_a_fallback_patch_that_bends_more_than_the_loop_only_patch_gives_way_to_it(monkeypatch):
    """The band without its development: the disc rounds the strip, the loop's own triangulation follows it."""
    from meshlab_holefill.core.border_bend import border_bend

    ctx = _equatorial_band()
    order = hpde_algorithm2.attempt_order
    monkeypatch.setattr(hpde_algorithm2, "attempt_order", lambda *a: [x for x in order(*a) if x[1] != "development"])
    patch = hpde.fill(ctx)
    assert patch.info["layout"] == "loop only"
    assert "unsegmented prediction, disc: bends more against the surface than the loop-only patch" in \
        patch.info["attempts_failed"]
    check_patch(ctx, patch)
    monkeypatch.setattr(hpde_algorithm2, "_bends_more_than_loop_only", lambda *a: None)
    disc = hpde.fill(ctx)
    assert disc.info["layout"] == "disc"
    assert border_bend(ctx, patch.vertices, patch.faces) < border_bend(ctx, disc.vertices, disc.faces)
    off_sphere = lambda p: np.abs(np.linalg.norm(p.all_points(ctx.points), axis=1) - 1.0).mean()  # noqa: E731
    assert off_sphere(patch) < 0.2 * off_sphere(disc)  # measured 0.0012 and 0.0140


def test_the_papers_own_layout_is_kept_without_the_loop_only_patch_made(monkeypatch):
    """The guard is for fallbacks: where the paper's layout closes the hole, no loop-only patch is made."""
    from meshlab_holefill.core import examples

    V, F, loop = examples.bowl_with_hole()
    ctx = hole_context(V, F, loop, rings=hpde.RINGS)
    made = []
    loop_only = hpde_algorithm2.loop_only_patch
    monkeypatch.setattr(hpde_algorithm2, "loop_only_patch", lambda *a: made.append(1) or loop_only(*a))
    patch = hpde.fill(ctx)
    assert patch.info["layout"] == "plane" and not made


def test_a_cap_round_a_knob_keeps_the_disc_layout_whose_patch_bends_less():
    """The benchmark's bone.ply hole of 60 edges runs round the bone's end (4.7 rad of curvature inside)."""
    from meshlab_holefill.evaluation.comparison import MeshCase, prepare_case
    from meshlab_holefill.meshlab.mesh_files import load_mesh

    from conftest import sample

    V, F = load_mesh(sample("bone.ply"))
    case = prepare_case(MeshCase("bone.ply", V, F), holes=4, seed=0)
    loop = [lp for lp in boundary_loops(case.F0) if len(lp) == 60][0]
    patch = hpde.fill(hole_context(case.V0, case.F0, loop, rings=hpde.RINGS))
    bends = patch.info["border_bends"]
    assert patch.info["layout"] == "disc" and bends["disc"] < bends["development"]


def test_layouts_smoothest_makes_every_attempt_and_keeps_the_least_bent_patch():
    from meshlab_holefill.core import examples
    from meshlab_holefill.core.border_bend import border_bend

    V, F, loop = examples.bowl_with_hole()
    ctx = hole_context(V, F, loop, rings=hpde.RINGS)
    first = hpde.fill(ctx)
    assert "layout_bends" not in first.info  # the paper's choice: the first clean attempt
    patch = hpde.fill(ctx, layouts="smoothest")
    bends = patch.info["layout_bends"]
    order = [f"{'segmented' if s else 'unsegmented'} prediction, {layout}"
             for s, layout in hpde_algorithm2.attempt_order(*_attempt_inputs(ctx))]
    assert list(bends) == order  # every attempt made, in the order the paper's choice takes them
    assert border_bend(ctx, patch.vertices, patch.faces) == min(bends.values())
    assert border_bend(ctx, patch.vertices, patch.faces) <= border_bend(ctx, first.vertices, first.faces)
    validate_patch(patch, ctx.points, ctx.forbidden_edges)


@pytest.mark.parametrize("segmented", [False, True])
def test_after_the_papers_layout_the_loop_layouts_go_before_the_other_plane_layout(monkeypatch, segmented):
    # The other plane layout overrules the A_c test (two planes across a planar boundary, or one
    # plane across a crease); the development and the disc follow the loop, so they come first.
    monkeypatch.setattr(hpde_sections, "pairing_coverage", lambda *a: 1.0)  # both pairings cover the hole
    seg = {"split": (2, 6), "segmented": segmented}
    order = hpde_algorithm2.attempt_order(None, None, seg, np.radians(12.0))
    papers, other = ("two planes", "plane") if segmented else ("plane", "two planes")
    assert order[:4] == [(segmented, papers), (segmented, "development"), (segmented, "disc"), (segmented, other)]
    flipped_papers = "plane" if segmented else "two planes"
    assert order[4:] == [(not segmented, flipped_papers), (not segmented, papers), (not segmented, "development"),
                         (not segmented, "disc")]
    unsplit = hpde_algorithm2.attempt_order(None, None, {"split": None, "segmented": False}, np.radians(12.0))
    assert unsplit == [(False, "plane"), (False, "development"), (False, "disc")]


@pytest.mark.parametrize("segmented", [False, True])
def test_a_pairing_that_covers_under_half_the_base_points_yields_to_one_that_covers_more(monkeypatch, segmented):
    seg = {"split": (2, 6), "segmented": segmented}
    asked = []

    def coverage_of(shares):
        def coverage(base, normals, split, I_c):
            asked.append(split is not None)
            return shares[split is not None]
        return coverage

    monkeypatch.setattr(hpde_sections, "pairing_coverage", coverage_of({segmented: 0.3, not segmented: 0.9}))
    assert hpde_algorithm2.attempt_order(None, None, seg, np.radians(12.0))[0][0] == (not segmented)
    assert asked == [segmented, not segmented]
    asked.clear()
    monkeypatch.setattr(hpde_sections, "pairing_coverage", coverage_of({segmented: 0.3, not segmented: 0.2}))
    assert hpde_algorithm2.attempt_order(None, None, seg, np.radians(12.0))[0][0] == segmented
    asked.clear()
    # Covering at least half, the paper's choice stands and the other pairing is not even found.
    monkeypatch.setattr(hpde_sections, "pairing_coverage", coverage_of({segmented: 0.6, not segmented: 1.0}))
    assert hpde_algorithm2.attempt_order(None, None, seg, np.radians(12.0))[0][0] == segmented
    assert asked == [segmented]


def _attempt_inputs(ctx):
    """The arguments :func:`_algorithm2.patch_hole` passes to ``attempt_order`` for the default options."""
    _, base, normals, seg = hpde_algorithm2.boundary_step(ctx, 90.0)
    return base, normals, seg, np.radians(12.0)


def test_narrow_bent_hole_is_projected_on_a_plane_facing_the_surface():
    # A strip 0.4 rad wide and 2 rad long around the unit sphere: its smallest principal spread
    # is across the strip, so the PCA plane of Sec. 4.6 stands across the surface and the
    # projected loop is not simple (the plane layout failed, the disc or the loop-only last
    # resort took over). The plane nearest the surface normal projects it simply.
    from meshlab_holefill.evaluation.papers import hpde_sphere as hpde_experiment

    V, F = hpde_experiment.uv_sphere()
    removed = hpde_experiment.ellipse_hole(V, F, 0.0, 0.0, 1.0, 0.2)
    F_cut = F[~removed]
    ctx = context(V, F_cut)
    patch = hpde.fill(ctx, seed=0)
    check_patch(ctx, patch)
    assert patch.info["layout"] == "plane" and "attempts_failed" not in patch.info
    assert np.abs(np.linalg.norm(patch.vertices, axis=1) - 1.0).max() < 0.5 * hpde_sections.ring_edge_length(ctx)
    base = hpde_sections.base_points(ctx.points, hpde_sections.ring_edge_length(ctx))
    normals = hpde_sections.base_point_normals(ctx.loop_normals, base)
    _, n = hpde_mesh.fitting_plane(base.points, normals)
    assert n @ np.array([1.0, 0, 0]) > 0.9  # the strip is centred at (1, 0, 0)


# ----------------------------------------------------------------- direct tests of building blocks

@pytest.mark.parametrize("reverse", [False, True])
def test_triangulate_planar_drops_outside_near_and_duplicate_points_and_keeps_the_loop_orientation(reverse):
    from meshlab_holefill.core.patch import Patch

    # Square [0, 2]^2 with its edge midpoints (k = 8), lifted onto the plane z = 0.1 x.
    Q = np.array([[0, 0], [1, 0], [2, 0], [2, 1], [2, 2], [1, 2], [0, 2], [0, 1.0]])
    X = np.array([[0.7, 0.8],    # 0 inside: kept
                  [3.0, 1.0],    # 1 outside the polygon
                  [1.0, 0.05],   # 2 within the clearance 0.2 of edge (0, 1)
                  [1.3, 1.2],    # 3 inside: kept
                  [0.7, 0.8],    # 4 exact duplicate of 0: the later one goes
                  [1.0, 1.9]])   # 5 within the clearance of edge (4, 5)
    if reverse:  # a clockwise polygon: faces must still follow the loop
        Q = Q[::-1].copy()
    P = np.column_stack([Q, 0.1 * Q[:, 0]])
    predicted = np.column_stack([X, 0.1 * X[:, 0] + 1.0])
    V, F, orientation, kept = hpde_mesh.triangulate_planar(P, predicted, Q, X, clearance=0.2)
    assert orientation == (-1 if reverse else 1)
    assert kept.tolist() == [0, 3]
    assert np.array_equal(V, np.concatenate([P, predicted[[0, 3]]]))
    assert len(F) == 8 + 2 * 2 - 2  # convex polygon, k boundary and q inner points: k + 2q - 2 triangles
    validate_patch(Patch(V[8:], F), P)  # every loop edge once, in loop direction


def test_retriangulation_rounds_give_triangulate_polygons_faces():
    from meshlab_holefill.errors import HoleFillError
    from meshlab_holefill.geometry.triangulate import triangulate_polygon

    rng = np.random.default_rng(5)
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    Q = np.stack([np.cos(t), 0.6 * np.sin(t)], axis=1) * (1 + 0.1 * np.cos(5 * t))[:, None]
    X = rng.uniform(-0.5, 0.5, (60, 2)) * [1.0, 0.5]
    T, checked = hpde_mesh._retriangulation(Q, X)
    _, T_ref = triangulate_polygon(Q, extra_points=X)
    assert not checked
    assert np.array_equal(np.sort(np.sort(T, axis=1), axis=0), np.sort(np.sort(T_ref, axis=1), axis=0))
    bow_tie = np.array([[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]])
    with pytest.raises(HoleFillError, match="constrained triangulation|not simple"):
        triangulate_polygon(bow_tie)
    with pytest.raises(HoleFillError, match="constrained triangulation|not simple"):
        hpde_mesh._retriangulation(bow_tie, np.zeros((0, 2)))
