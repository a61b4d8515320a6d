"""HPDE worst triangles: slivers lifted to the quality floor by the Sec. 4.7 steps and the quality pass."""
import os

import numpy as np
import pymeshlab
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.algorithms.xie_zou2013 import differential_evolution as hpde
from meshlab_holefill.algorithms.xie_zou2013 import folds as hpde_folds, sections as hpde_sections, _loop_only_patch as hpde_loop_only
from meshlab_holefill.geometry.quality import triangle_quality
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.core.patch import validate_patch

from hpde_cases import SAMPLES, check_patch, context, cut, grid_plane, patch_points


# ----------------------------------------------------------------------------- worst triangles (quality floor)

def sample_loop_context(path, size, centroid):
    """HoleContext of the boundary loop of ``size`` edges nearest to ``centroid`` in a pymeshlab sample mesh."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(SAMPLES, path))
    m = ms.current_mesh()
    V, F = np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)
    loops = [lp for lp in boundary_loops(F) if len(lp) == size]
    lp = min(loops, key=lambda lp: np.linalg.norm(V[lp.vertices].mean(axis=0) - centroid))
    return hole_context(V, F, lp, rings=hpde.RINGS)


@pytest.mark.parametrize("size, centroid", [
    (36, (-54.647, -25.625, -798.328)),  # face000.ply natural hole 10: min 0.180 before
    (14, (30.386, 14.379, -779.805)),    # hole 23: 0.148
    (12, (-13.94, -68.472, -788.99)),    # hole 25: 0.130
])
def test_long_loop_edges_leave_no_slivers(size, centroid):
    """Range-scan loops with edges of 2-4 EdgeLen: no sliver on a long loop edge (min 2r/R >= 0.3).

    The points near a long loop edge are left out (EDGE_CLEARANCE) and the quality pass
    (hpde_quality) lifts what the Sec. 4.7 optimisation leaves below the floor.
    """
    ctx = sample_loop_context(os.path.join("rangemaps", "face000.ply"), size, centroid)
    edge_len = hpde_sections.ring_edge_length(ctx)
    assert np.linalg.norm(np.roll(ctx.points, -1, axis=0) - ctx.points, axis=1).max() > 2 * edge_len
    patch = hpde.fill(ctx)
    X = check_patch(ctx, patch)
    q = triangle_quality(X, patch.faces)
    assert q.min() >= 0.3 and q.mean() >= 0.75
    assert patch.info["layout"] == "plane"


def test_loop_only_last_resort_is_lifted_by_the_quality_pass():
    """bunny10k hole 1: a border face folded over the hole makes every layout cross it; the loop-only
    patch gets interior vertices from the pass's splits (min 0.084 -> >= 0.3) and still crosses nothing."""
    ctx = sample_loop_context("bunny10k_textured.obj", 22, (-3.464, 3.604, 0.255))
    patch = hpde.fill(ctx)
    assert patch.info["layout"] == "loop only"
    validate_patch(patch, ctx.points, ctx.forbidden_edges)
    X = patch_points(ctx, patch)
    assert not hpde_folds.intersects_surroundings(ctx, X, patch.faces)
    assert not hpde_folds.local_folds(X, patch.faces, hpde_folds.border_normals(ctx),
                                      max_angle=hpde_loop_only.LAST_RESORT_ANGLE).any()
    q = triangle_quality(X, patch.faces)
    assert q.min() >= 0.3 and len(patch.vertices) > 0


def loop_only_with_and_without_fairing(monkeypatch, ctx):
    """HPDE's patches of ``ctx`` with every layout taken away (the loop-only last resort): as filled, then
    as filled without :func:`faired_where_less_bent` (neither faired nor refined)."""
    from meshlab_holefill.algorithms.xie_zou2013 import _algorithm2

    monkeypatch.setattr(_algorithm2, "attempt_order", lambda *a: [])
    filled = hpde.fill(ctx)
    monkeypatch.setattr(hpde_loop_only, "faired_where_less_bent", lambda ctx, patch, *a: patch)
    coarse = hpde.fill(ctx)
    assert filled.info["layout"] == coarse.info["layout"] == "loop only"
    return filled, coarse


@pytest.mark.parametrize("radius", [0.45, 0.7])
def test_the_loop_only_last_resort_is_faired_onto_the_sphere_where_that_bends_less(monkeypatch, radius):
    """A hole round the sphere's pole with every layout taken away: the loop-only patch, a near-flat
    sheet across the cap, is faired (thin-plate, the rings fixed) and kept so, being closer to the
    removed cap and bending less across the border; without the fairing it stays flat."""
    from meshlab_holefill.core.border_bend import border_bend

    from hpde_cases import sphere_mesh

    V, F = sphere_mesh(4)
    ctx = context(V, cut(V, F, (0, 0, 1.0), radius)[0])
    faired, flat = loop_only_with_and_without_fairing(monkeypatch, ctx)
    assert faired.info.get("faired") and not flat.info.get("faired")
    off_sphere = lambda p: np.abs(np.linalg.norm(p.vertices, axis=1) - 1.0).mean()  # noqa: E731
    assert off_sphere(faired) < 0.75 * off_sphere(flat)  # measured 0.0120 / 0.0254 and 0.0242 / 0.0367
    assert border_bend(ctx, faired.vertices, faired.faces) < border_bend(ctx, flat.vertices, flat.faces)
    check_patch(ctx, faired)
    assert triangle_quality(patch_points(ctx, faired), faired.faces).min() >= 0.3


def test_a_loop_only_patch_that_fairing_bends_no_less_is_refined_to_the_surrounding_density(monkeypatch):
    """A round hole in a flat grid with every layout taken away: fairing leaves the flat loop-only patch
    as flat, bending no less, so the patch is refined instead: at the grid's edge length, still in the
    plane, crossing nothing, with no triangle poorer than the unrefined patch's."""
    from meshlab_holefill.geometry.quality import edge_lengths

    V, F = grid_plane(24)
    ctx = context(V, cut(V, F, (0.5, 0.5, 0.0), 0.3)[0])
    refined, coarse = loop_only_with_and_without_fairing(monkeypatch, ctx)
    assert refined.info.get("refined") and not refined.info.get("faired")
    assert len(refined.vertices) > 2 * len(coarse.vertices)  # measured 134 against 57
    assert np.all(refined.vertices[:, 2] == 0.0)
    X, Y = check_patch(ctx, refined), patch_points(ctx, coarse)
    assert triangle_quality(X, refined.faces).min() >= triangle_quality(Y, coarse.faces).min()
    grid_edge = edge_lengths(V, F).mean()
    assert abs(edge_lengths(X, refined.faces).mean() / grid_edge - 1.0) < 0.1  # coarse: 1.24 times the grid's


def test_raise_min_quality_lifts_a_sliver_and_keeps_the_loop():
    """A free vertex pushed next to a loop edge (a sliver) is moved back; loop vertices stay, nothing folds."""
    from meshlab_holefill.algorithms.xie_zou2013 import quality_pass as hpde_quality

    V, F = grid_plane(6)
    F_cut, removed = cut(V, F, (0.5, 0.5, 0), 0.3)
    ctx = context(V, F_cut)
    patch = hpde.fill(ctx, quality_floor=0.0)
    k = ctx.size
    X = patch_points(ctx, patch).copy()
    F_p = patch.faces
    # Push the free vertex nearest the loop onto its nearest loop edge's midpoint, 5 % inside.
    free = np.arange(k, len(X))
    mids = 0.5 * (ctx.points + np.roll(ctx.points, -1, axis=0))
    d = np.linalg.norm(X[free, None] - mids[None], axis=2)
    v, e = np.unravel_index(np.argmin(d), d.shape)
    X[free[v]] = 0.95 * mids[e] + 0.05 * X[free[v]]
    q0 = triangle_quality(X, F_p)
    assert q0.min() < 0.2
    V2, F2, keep, stats = hpde_quality.raise_min_quality(X, F_p, k, ctx.forbidden_edges, hpde_folds.border_normals(ctx))
    assert np.array_equal(V2[:k], X[:k]) and np.array_equal(keep[:k], np.arange(k))
    q = triangle_quality(V2, F2)
    assert q.min() >= 0.3 and q.min() > q0.min()
    assert np.abs(V2[:, 2]).max() < 1e-12  # tangential moves keep the plane
    assert not hpde_folds.local_folds(V2, F2, hpde_folds.border_normals(ctx)).any()
    # Same area covered: nothing was folded or torn.
    from meshlab_holefill.geometry.quality import face_areas
    assert face_areas(V2, F2).sum() == pytest.approx(face_areas(X, F_p).sum())


@settings(max_examples=25, deadline=None)
@given(k=st.integers(6, 16), points=st.integers(3, 25), seed=st.integers(0, 10_000))
def test_quality_pass_never_lowers_the_minimum_and_keeps_the_disc(k, points, seed):
    from meshlab_holefill.algorithms.xie_zou2013 import quality_pass as hpde_quality
    from meshlab_holefill.geometry.quality import face_areas, face_normals

    from conftest import random_planar_patch

    X, F = random_planar_patch(k, points, seed)
    q0 = triangle_quality(X, F).min()
    V2, F2, keep, _ = hpde_quality.raise_min_quality(X, F, k)
    assert np.array_equal(V2[:k], X[:k]) and np.array_equal(keep[:k], np.arange(k))
    assert triangle_quality(V2, F2).min() >= q0 - 1e-12
    assert np.abs(V2[:, 2]).max() < 1e-12 and np.all(face_normals(V2, F2)[:, 2] > 0)  # no fold, no flip
    assert face_areas(V2, F2).sum() == pytest.approx(face_areas(X, F).sum())  # the same disc, no tear
