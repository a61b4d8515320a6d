"""Curve unfolding: the tangential relaxation of the embedded patch."""

import numpy as np
import pytest

from meshlab_holefill import fill_holes
from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
from meshlab_holefill.algorithms.brunton2009 import crossing_repair
from meshlab_holefill.algorithms.brunton2009.embedding import embed_patch
from meshlab_holefill.algorithms.brunton2009.tangential_relaxation import tangential_relaxation, vertex_normals
from meshlab_holefill.algorithms.brunton2009.umbrella import umbrella_operator
from meshlab_holefill.geometry.quality import triangle_quality
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.core.outlines import outline_ratios
from meshlab_holefill.evaluation.metrics import corner_quality_bound
from meshlab_holefill.core.patch import validate_patch

from brunton_cases import sphere_cap_domain


def sphere_cap_embedding(energy="fairing"):
    """A refined planar domain of a sphere hole embedded by E_DF: joint positions, faces, free vertices."""
    ctx, points, Fp = sphere_cap_domain()
    s = len(points) - ctx.size
    n_ctx = len(ctx.vertices)
    joint = np.concatenate([ctx.faces, np.where(Fp < ctx.size, Fp, Fp - ctx.size + n_ctx)])
    X = np.concatenate([ctx.vertices, embed_patch(ctx, s, Fp, energy=energy)])
    return ctx, X, joint, n_ctx + np.arange(s), Fp


def test_tangential_relaxation_cancels_the_tangential_umbrella_within_tangent_planes():
    ctx, X, joint, free, _ = sphere_cap_embedding()
    N = vertex_normals(X, joint)[free]
    W = umbrella_operator(joint, len(X))
    U0 = (W @ X)[free]
    tangential_part = lambda U: U - np.einsum("ij,ij->i", U, N)[:, None] * N
    assert np.abs(tangential_part(U0)).max() > 1e-3  # E_DF leaves a tangential umbrella
    Y = tangential_relaxation(X, joint, free)
    assert np.array_equal(Y[:free[0]], X[:free[0]])  # fixed vertices stay
    step = (Y - X)[free]
    assert np.abs(np.einsum("ij,ij->i", step, N)).max() < 1e-12  # moves only within the tangent planes
    assert np.abs(tangential_part((W @ Y)[free])).max() < 1e-10  # B_p^T U(p) = 0
    # E_DF's shape is kept: the patch is no farther from the unit sphere than E_DF put it.
    d0, d1 = (np.abs(np.linalg.norm(Z[free], axis=1) - 1) for Z in (X, Y))
    assert np.linalg.norm(step, axis=1).max() > 0.05 * float(ctx.edge_scale.mean())
    assert d1.max() <= d0.max() + 1e-3 and d1.mean() <= d0.mean() + 1e-3


@pytest.mark.parametrize("scatter", [0.05, 0.3])
def test_tangential_relaxation_never_turns_a_face_against_the_surface(scatter):
    """From a start whose full step would fold faces; a start folded already may only unfold."""
    ctx, X, joint, free, _ = sphere_cap_embedding()
    rng = np.random.default_rng(3)
    Xw = X.copy()
    Xw[free] += scatter * rng.standard_normal((len(free), 3)) * float(ctx.edge_scale.mean())
    star = joint[np.isin(joint, free).any(axis=1)]
    normal = lambda Z: np.cross(Z[star[:, 1]] - Z[star[:, 0]], Z[star[:, 2]] - Z[star[:, 0]])
    outward = lambda Z: np.einsum("ij,ij->i", normal(Z), Z[star].mean(axis=1)) > 0  # the unit sphere's outside
    Y = tangential_relaxation(Xw, joint, free)
    assert np.all(outward(Y) | ~outward(Xw))
    if outward(Xw).all():  # nothing folded: no face flips at all
        assert np.all(np.einsum("ij,ij->i", normal(Xw), normal(Y)) > 0)


@pytest.mark.parametrize("edges", [31, 76, 86])
def test_tangential_relaxation_lifts_the_triangles_fairing_squeezes_on_scan_holes(face_scan, edges):
    V, F, loops = face_scan
    i = [j for j, lp in enumerate(loops) if len(lp) == edges][0]
    assert outline_ratios(V, F, [loops[i]])[0] < 0.9  # a hole, not an island's outline
    ctx = hole_context(V, F, loops[i], rings=cu.RINGS)
    bound = corner_quality_bound(V, F, loops[i].vertices)
    # The step on the energy's own patch (no resampling to the surrounding density, no sliver repair),
    # on the projection's domain (the loop-length domain happens not to squeeze these holes).
    options = dict(energy="fairing", density="equilateral", slivers=False, lengths="projection", domain="unfolding")
    faired = cu.fill(ctx, tangential=False, **options)
    relaxed = cu.fill(ctx, **options)
    q0 = triangle_quality(faired.all_points(ctx.points), faired.faces)
    q1 = triangle_quality(relaxed.all_points(ctx.points), relaxed.faces)
    # E_DF alone squeezes a triangle below 0.3 although no border corner forces it.
    assert q0.min() < 0.3 < bound
    assert q1.min() >= 0.3 and q1.mean() >= 0.85
    validate_patch(relaxed, ctx.points, ctx.forbidden_edges)
    assert len(crossing_repair.crossing_faces(ctx, relaxed.vertices, relaxed.faces)) == 0


def test_principal_entries_are_scipys_submatrix_triples():
    from conftest import grid
    from meshlab_holefill.algorithms.brunton2009.tangential_relaxation import _principal_entries

    rng = np.random.default_rng(0)
    _, F = grid(9)
    W = umbrella_operator(F, int(F.max()) + 1)
    for _ in range(20):
        rows = np.flatnonzero(rng.random(W.shape[0]) < 0.6)
        expected, got = W[rows][:, rows].tocoo(), _principal_entries(W, rows)
        assert got.shape == expected.shape
        assert sorted(zip(got.row.tolist(), got.col.tolist(), got.data.tolist())) == \
            sorted(zip(expected.row.tolist(), expected.col.tolist(), expected.data.tolist()))


def _annulus(n=64, inner=0.5, outer=1.0):
    """A flat ring one face wide: its inner 64-gon a hole whose surroundings reach far out."""
    t = 2.0 * np.pi * np.arange(n) / n
    V = np.concatenate([np.c_[inner * np.cos(t), inner * np.sin(t), 0 * t], np.c_[outer * np.cos(t), outer * np.sin(t), 0 * t]])
    i, j = np.arange(n), (np.arange(n) + 1) % n
    F = np.concatenate([np.c_[i, n + i, n + j], np.c_[i, n + j, j]])
    return V, F


def test_a_flat_hole_whose_energy_placement_folds_is_unfolded_by_the_tangential_relaxation():
    """E_AREA's least-squares mesh folds this patch in the plane (the far outer ring pulls on the loop's rows)."""
    V, F = _annulus()
    inner = min(boundary_loops(F), key=lambda loop: np.linalg.norm(V[loop.vertices], axis=1).max())
    ctx = hole_context(V, F, inner, rings=cu.RINGS)
    points = lambda patch: np.concatenate([ctx.points, patch.vertices])[patch.faces]
    up = lambda P: np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])[:, 2]
    placed = cu.fill(ctx, tangential=False, swaps=False, slivers=False, repair=False)
    assert np.any(up(points(placed)) < 0)  # the energy's placement alone folds
    patch = cu.fill(ctx)
    assert np.all(up(points(patch)) > 0) and np.all(patch.vertices[:, 2] == 0)
    V2, F2, result = fill_holes(V, F, "curve_unfolding")
    assert result["closed_holes"] == 1 and result["holes"][0]["status"] != "failed"
    new = F2[len(F):]
    assert np.all(up(V2[new]) > 0)
