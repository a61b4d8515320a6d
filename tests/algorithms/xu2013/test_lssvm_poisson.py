"""Xu et al. 2013: the LS-SVM Poisson hole-filling filter as a whole (MeshSet runs, parameters, whole holes)."""
import itertools

import numpy as np
import pymeshlab
import pytest

from meshlab_holefill.algorithms.xu2013 import lssvm_poisson as xu
from meshlab_holefill.core.holes import boundary_loops, hole_context, nonmanifold_edges
from meshlab_holefill.core.patch import validate_patch
from meshlab_holefill.geometry.intersections import faces_intersecting
from meshlab_holefill.geometry.quality import triangle_quality

from conftest import assert_filled_cleanly, cut_disks, grid, mesh_arrays, meshset_from_arrays
from xu2013_cases import context_of, sphere_hole, surface_area

NAME = "meshing_close_holes_lssvm_poisson"


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


def test_parameters_are_exposed_and_validated(bunny_scan):
    from meshlab_holefill import FilterParameterError

    for name in ("split_boundary", "split_factor", "layers", "gamma", "kernel_width", "poisson_iterations",
                 "laplacian_prediction", "merge_factor"):
        assert name in [p.name for p in xu.PARAMS]
    with pytest.raises(FilterParameterError, match=r"'laplacian_prediction': expected one of \['lssvm', 'zero'\]"):
        getattr(bunny_scan, NAME)(laplacian_prediction="cubic")
    with pytest.raises(FilterParameterError, match="'layers': 9 is above the maximum 5"):
        getattr(bunny_scan, NAME)(layers=9)


@pytest.mark.parametrize("scale", [1e-6, 1e-3, 1e3, 1e9])
def test_the_patch_does_not_depend_on_the_unit(scale):
    """Every tolerance of the front is relative: the same hole in other units gets the same patch."""
    from conftest import sphere_with_holes

    V, F, _ = sphere_with_holes(subdiv=3, centers=[(0, 0, 1)], radius=0.3)
    ref = xu.fill(hole_context(V, F, boundary_loops(F)[0], rings=xu.RINGS))
    patch = xu.fill(hole_context(V * scale, F, boundary_loops(F)[0], rings=xu.RINGS))
    assert np.array_equal(patch.faces, ref.faces) and patch.info["afm_rejected"] == ref.info["afm_rejected"]
    np.testing.assert_allclose(patch.vertices / scale, ref.vertices, rtol=0, atol=1e-9)


def _reposition_unshaped(monkeypatch, calls):
    """Make the first ``calls`` repositionings report no Poisson solve kept (positions as computed)."""
    real, made = xu.reposition, []

    def reposition(*args, **kwargs):
        X, F, info = real(*args, **kwargs)
        made.append(1)
        if len(made) <= calls:
            info = dict(info, poisson_solves=0)
        return X, F, info

    monkeypatch.setattr(xu, "reposition", reposition)
    return made


def test_an_initial_patch_no_solve_was_kept_for_gives_way_to_one_the_solve_shapes(monkeypatch):
    V, F, _ = sphere_hole()
    ctx = context_of(V, F)
    assert xu.fill(ctx).info["afm_domain"] == "3d"
    _reposition_unshaped(monkeypatch, calls=1)
    patch = xu.fill(ctx)
    assert patch.info["afm_domain"] != "3d" and patch.info["poisson_solves"] >= 1
    assert patch.info["fallback_reasons"].startswith("3d patch: no Poisson solve could be kept")
    validate_patch(patch, ctx.points, ctx.forbidden_edges)  # a disc closing the loop once


def test_the_unshaped_patch_is_kept_where_no_initial_patch_is_shaped(monkeypatch):
    V, F, _ = sphere_hole()
    ctx = context_of(V, F)
    made = _reposition_unshaped(monkeypatch, calls=100)
    patch = xu.fill(ctx)
    assert len(made) > 1  # the later initial patches were tried
    assert patch.info["afm_domain"] == "3d" and "fallback_reasons" not in patch.info


def test_the_scans_8_edge_hole_takes_an_initial_patch_the_solve_shapes(bunny_scan, monkeypatch):
    """bunny10k_textured.obj's 8-edge hole: every solve of its 3D, developed and projected patches is discarded."""
    from meshlab_holefill import fill_holes
    from meshlab_holefill.core.border_bend import border_bend

    V, F = mesh_arrays(bunny_scan)
    _, _, result = fill_holes(V, F, "lssvm_poisson", workers=1)
    (entry,) = [h for h in result["holes"] if h["boundary_edges"] == 8]
    assert entry["status"] == "closed" and entry["poisson_solves"] >= 1 and entry["afm_domain"] == "ears"
    assert "3d patch: no Poisson solve could be kept" in entry["fallback_reasons"]
    # The shaped patch meets the scan more smoothly than the unshaped 3D one, kept when it is the only patch.
    (loop,) = [lp for lp in boundary_loops(F) if len(lp) == 8]
    ctx = hole_context(V, F, loop, rings=xu.RINGS)
    shaped = xu.fill(ctx)
    patches = xu.initial_patches
    monkeypatch.setattr(xu, "initial_patches", lambda *a: itertools.islice(patches(*a), 1))
    unshaped = xu.fill(ctx)
    assert (shaped.info["afm_domain"], unshaped.info["afm_domain"]) == ("ears", "3d")
    assert shaped.info["poisson_solves"] >= 1 and unshaped.info["poisson_solves"] == 0
    assert border_bend(ctx, shaped.vertices, shaped.faces) < border_bend(ctx, unshaped.vertices, unshaped.faces)


def test_a_shaped_patch_yields_to_the_unshaped_one_only_for_a_poor_triangle_the_other_has_not():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    good = np.array([[0, 1, 2], [0, 2, 3]])
    centre = np.vstack([square, [[0.5, 0.5, 0.0]]])
    fan = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    sliver = np.vstack([square, [[0.5, 0.02, 0.0]]])  # a fan apex next to edge 0-1: quality about 0.08
    assert xu._poorer(sliver, fan, square, good)
    assert not xu._poorer(centre, fan, square, good)
    # a poor triangle the unshaped patch is as poor in does not count against the shaped one
    assert not xu._poorer(sliver, fan, sliver, fan)
