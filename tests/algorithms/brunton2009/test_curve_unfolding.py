"""Brunton et al. 2009, curve unfolding: fill() and the filter as a whole (registration, seeds, holes of a
sphere, a tube, the bunny and the benchmark's wrapped torus hole)."""

import numpy as np
import pymeshlab
import pytest

from meshlab_holefill import FILTERS, fill_holes
from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
from meshlab_holefill.algorithms.brunton2009 import crossing_repair
from meshlab_holefill.algorithms.brunton2009.embedding import embedding_energy, energy_rows
from meshlab_holefill.algorithms.brunton2009.linear_motion import linear_motion_is_simple
from meshlab_holefill.algorithms.brunton2009.annealing import planarity_energy
from meshlab_holefill.geometry.development import boundary_gap_angles, develop_loop, simple_development
from meshlab_holefill.evaluation.comparison import MeshCase, prepare_case
from meshlab_holefill.geometry.intersections import faces_intersecting
from meshlab_holefill.geometry.quality import triangle_quality
from meshlab_holefill.core.holes import boundary_loops, hole_context, nonmanifold_edges
from meshlab_holefill.core import examples
from meshlab_holefill.core.patch import validate_patch

from conftest import mesh_arrays, meshset_from_arrays, sphere_with_holes
from brunton_cases import mean_edge


def tube(n_around=36, n_up=10, height=3.0):
    """Open unit cylinder, outward-facing triangles."""
    th = np.linspace(0, 2 * np.pi, n_around, endpoint=False)
    T, Z = np.meshgrid(th, np.linspace(0, height, n_up))
    V = np.stack([np.cos(T).ravel(), np.sin(T).ravel(), Z.ravel()], axis=1)
    idx = np.arange(n_up * n_around).reshape(n_up, n_around)
    a, b = idx[:-1].ravel(), np.roll(idx, -1, axis=1)[:-1].ravel()
    c, d = np.roll(idx, -1, axis=1)[1:].ravel(), idx[1:].ravel()
    return V, np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def tube_hole_context(wrap=200.0):
    """A hole wrapped `wrap` degrees around a tube, z in [1, 2]: no side sees it without overlap."""
    V, F = tube()
    C = V[F].mean(axis=1)
    angle = np.degrees(np.arctan2(C[:, 1], C[:, 0])) % 360
    F = F[~((angle < wrap) & (C[:, 2] > 1) & (C[:, 2] < 2))]
    loop = [lp for lp in boundary_loops(F) if len(lp) != 36][0]
    return hole_context(V, F, loop, rings=cu.RINGS)


def test_same_seed_same_patch_and_annealing_reaches_the_filter():
    ctx = tube_hole_context()
    a = cu.fill(ctx, seed=1, fallback=False, domain="unfolding")
    b = cu.fill(ctx, seed=1, fallback=False, domain="unfolding")
    c = cu.fill(ctx, seed=2, fallback=False, domain="unfolding")
    assert a.info["unfolding"] == "annealing" and a.info["sa_steps"] > 0
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
    assert a.info["sa_steps"] != c.info["sa_steps"]
    validate_patch(a, ctx.points, ctx.forbidden_edges)


def test_wrapped_hole_on_a_tube_is_filled_on_the_tube():
    ctx = tube_hole_context()
    patch = cu.fill(ctx)
    validate_patch(patch, ctx.points, ctx.forbidden_edges)
    radius = np.hypot(patch.vertices[:, 0], patch.vertices[:, 1])
    assert np.abs(radius - 1).max() < 0.03
    q = triangle_quality(patch.all_points(ctx.points), patch.faces)
    assert q.mean() > 0.85 and q.min() > 0.3
    assert len(crossing_repair.crossing_faces(ctx, patch.vertices, patch.faces)) == 0


def test_filter_registration_and_paper_defaults():
    spec = FILTERS["meshing_close_holes_curve_unfolding"]
    assert spec.display_name == "Close Holes: Curve Unfolding"
    defaults = {p.name: p.default for p in spec.params}
    assert defaults["k"] == 0.9 and defaults["temperature"] == 0.5 and defaults["epsilon"] == 1e-5
    assert defaults["max_restarts"] == 100


def test_sphere_holes_are_closed_on_the_sphere():
    V, F, _ = sphere_with_holes()
    ms = meshset_from_arrays(V, F)
    res = ms.meshing_close_holes_curve_unfolding()
    assert res["closed_holes"] == 2 and res["failed_holes"] == 0
    V1, F1 = mesh_arrays(ms)
    assert np.array_equal(V1[:len(V)], V) and np.array_equal(F1[:len(F)], F)
    assert boundary_loops(F1) == [] and len(nonmanifold_edges(F1)) == 0
    new = np.arange(len(F), len(F1))
    assert len(faces_intersecting(V1, F1, new, np.arange(len(F1)))) == 0
    assert np.abs(np.linalg.norm(V1[len(V):], axis=1) - 1).max() < 0.01  # E_DF follows the sphere
    q = triangle_quality(V1, F1[len(F):])
    assert q.mean() >= 0.85 and q.min() >= 0.3


@pytest.mark.parametrize("energy", ["area", "fairing"])
def test_bunny_scan_natural_holes_all_closed(bunny_scan, energy):
    V0, F0 = mesh_arrays(bunny_scan)
    res = bunny_scan.meshing_close_holes_curve_unfolding(energy=energy, seed=0)
    assert res["closed_holes"] == 5 and res["failed_holes"] == 0
    for hole in res["holes"]:
        assert {"restarts", "unfolding_seconds", "embedding_seconds"} <= set(hole)
    V1, F1 = mesh_arrays(bunny_scan)
    assert np.array_equal(V1[:len(V0)], V0) and np.array_equal(F1[:len(F0)], F0)
    assert boundary_loops(F1) == [] and len(nonmanifold_edges(F1)) == 0


@pytest.fixture(scope="module")
def torus_wrapped_hole():
    """The benchmark's large torus hole: 211 edges, wrapped 255 degrees around the tube (seed 0)."""
    ms = pymeshlab.MeshSet()
    ms.create_torus(hradius=1.0, vradius=0.4, hsubdiv=192, vsubdiv=96)
    V, F = mesh_arrays(ms)
    case = prepare_case(MeshCase("torus", V, F), holes=4, seed=0)
    hole = max(case.holes, key=lambda h: h.boundary_edges)
    return hole_context(case.V0, case.F0, boundary_loops(case.F0)[hole.loop_index], rings=cu.RINGS)


def test_relaxed_development_unfolds_the_wrapped_torus_hole(torus_wrapped_hole):
    ctx = torus_wrapped_hole
    P, m = ctx.points, ctx.size
    eps = 1e-5 * mean_edge(P)
    gaps = boundary_gap_angles(ctx.vertices, ctx.faces, m)
    assert not linear_motion_is_simple(develop_loop(P, gaps), eps)  # the plain development touches itself
    Q, relax = simple_development(P, gaps, eps)
    assert relax is not None and 0 < relax <= 0.1
    assert linear_motion_is_simple(Q, eps)
    # relax = 1 turns equally everywhere: a convex polygon (E_PE = 0 once lifted to a plane).
    C = develop_loop(P, gaps, relax=1.0)
    assert planarity_energy(np.c_[C, np.zeros(m)]) == pytest.approx(0, abs=1e-9)
    patch = cu.fill(ctx, max_restarts=2)
    validate_patch(patch, ctx.points, ctx.forbidden_edges)
    assert patch.info["unfolding"] == "development" and patch.info["development_relax"] == relax
    assert len(crossing_repair.crossing_faces(ctx, patch.vertices, patch.faces)) == 0
    X = patch.all_points(ctx.points)
    tube = np.hypot(np.hypot(X[:, 0], X[:, 1]) - 1.0, X[:, 2]) - 0.4
    assert np.abs(tube).mean() < 0.01  # on the torus, not a membrane across the tube


def test_edge_swaps_lift_squeezed_triangles_and_keep_the_energy_solved(torus_wrapped_hole):
    ctx = torus_wrapped_hole
    # tangential=False: the swaps alone, and the energy must then be solved exactly. The step on the
    # energy's own patch (density='equilateral': no resampling afterwards; no sliver repair).
    plain = cu.fill(ctx, max_restarts=2, swaps=False, tangential=False, energy="fairing", density="equilateral", slivers=False)
    swapped = cu.fill(ctx, max_restarts=2, tangential=False, energy="fairing", density="equilateral", slivers=False)
    q0 = triangle_quality(plain.all_points(ctx.points), plain.faces)
    q1 = triangle_quality(swapped.all_points(ctx.points), swapped.faces)
    assert q0.min() < 0.3 and q1.min() > q0.min() and q1.mean() >= max(q0.mean(), 0.85)
    k = ctx.size
    for face in swapped.faces[q1 < 0.3]:  # what is left below 0.3 lies on a border edge, which no swap changes
        loop = np.sort(face[face < k])
        assert len(loop) >= 2 and any((b - a) % k in (1, k - 1) for a, b in zip(loop, np.roll(loop, -1)))
    assert swapped.info["edge_swaps"] > 0 and len(swapped.faces) == len(plain.faces)
    validate_patch(swapped, ctx.points, ctx.forbidden_edges)
    assert len(crossing_repair.crossing_faces(ctx, swapped.vertices, swapped.faces)) == 0
    # Interior vertices still minimise E_DF on the swapped connectivity.
    n_ctx, s = len(ctx.vertices), len(swapped.vertices)
    joint = np.concatenate([ctx.faces, np.where(swapped.faces < ctx.size, swapped.faces,
                                                swapped.faces - ctx.size + n_ctx)])
    free = np.arange(n_ctx + s) >= n_ctx
    _, gradient = embedding_energy(np.concatenate([ctx.vertices, swapped.vertices]),
                                   energy_rows(joint, n_ctx + s, free, 2), free)
    assert np.abs(gradient).max() < 1e-10
    # Likewise the least-squares mesh (E_AREA with the loop rows) after its own swaps.
    swapped = cu.fill(ctx, max_restarts=2, tangential=False, energy="area", density="equilateral", slivers=False)
    assert swapped.info["edge_swaps"] > 0
    s = len(swapped.vertices)
    joint = np.concatenate([ctx.faces, np.where(swapped.faces < ctx.size, swapped.faces,
                                                swapped.faces - ctx.size + n_ctx)])
    free = np.arange(n_ctx + s) >= n_ctx
    _, gradient = embedding_energy(np.concatenate([ctx.vertices, swapped.vertices]),
                                   energy_rows(joint, n_ctx + s, free, 1, anchors=True), free)
    assert np.abs(gradient).max() < 1e-10


def test_a_patch_the_tangential_relaxation_folds_is_made_again_without_it(monkeypatch):
    """Where the relaxed patch crosses itself and the patch made without the relaxation does not, the filter
    keeps the latter (``info['fallback']``). The fold is forced: the relaxed patch's two new vertices farthest
    apart trade places, so their fans span the patch (on a real hole, a 308-edge hole of cow.obj Loop-subdivided
    twice, whether the relaxation folds hangs on the processor's last bits)."""
    from dataclasses import replace

    V, F, loop = examples.bowl_with_hole(n=21)
    ctx = hole_context(V, F, loop, rings=cu.RINGS)
    made = cu._fill_steps

    def folded_when_relaxed(ctx, **params):
        patch = made(ctx, **params)
        if not params["tangential"]:
            return patch
        P = patch.vertices
        a, b = np.unravel_index(np.argmax(np.linalg.norm(P[:, None] - P[None], axis=2)), (len(P), len(P)))
        P = P.copy()
        P[[a, b]] = P[[b, a]]
        return replace(patch, vertices=P, info=dict(patch.info, crossing_faces=len(crossing_repair.crossing_faces(ctx, P, patch.faces))))

    monkeypatch.setattr(cu, "_fill_steps", folded_when_relaxed)
    options = dict(domain="unfolding")
    relaxed = cu._fill_steps(ctx, **dict({p.name: p.default for p in cu.PARAMS}, **options))
    assert len(crossing_repair.crossing_faces(ctx, relaxed.vertices, relaxed.faces)) > 10
    patch = cu.fill(ctx, **options)
    assert patch.info["fallback"] == "no tangential relaxation"
    assert len(crossing_repair.crossing_faces(ctx, patch.vertices, patch.faces)) == 0
    assert np.array_equal(patch.vertices, made(ctx, **dict({p.name: p.default for p in cu.PARAMS}, **options, tangential=False)).vertices)
    V2, F2, result = fill_holes(V, F, "curve_unfolding", workers=1, maxholesize=len(loop) + 1, **options)
    closed = [h for h in result["holes"] if h["status"] == "closed"]
    assert len(closed) == 1 and closed[0]["fallback"] == "no tangential relaxation"
    assert np.array_equal(V2[:len(V)], V) and np.array_equal(F2[:len(F)], F)
    assert len(boundary_loops(F2)) == 1  # the grid's outer border alone
    assert len(faces_intersecting(V2, F2, np.arange(len(F), len(F2)), np.arange(len(F2)))) == 0
