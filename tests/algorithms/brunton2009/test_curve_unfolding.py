"""Brunton et al. 2009, curve unfolding: unfolding (Sec. 3.1), CDT (Sec. 3.2), refinement and
embedding (Sec. 3.3), and the filter end to end."""

import numpy as np
import pymeshlab
import pytest
import scipy.optimize
import scipy.sparse.linalg
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill import FILTERS, HoleFillError, fill_holes
from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
from meshlab_holefill.algorithms.brunton2009 import crossing_repair
from meshlab_holefill.algorithms.brunton2009 import planar_domains
from meshlab_holefill.algorithms.brunton2009 import quality_swaps
from meshlab_holefill.algorithms.brunton2009 import unfolded_triangulation as tri
from meshlab_holefill.algorithms.brunton2009.embedding import embed_patch, embedding_energy, energy_rows
from meshlab_holefill.algorithms.brunton2009.tangential_relaxation import tangential_relaxation, vertex_normals
from meshlab_holefill.algorithms.brunton2009.umbrella import umbrella_operator
from meshlab_holefill.algorithms.brunton2009.linear_motion import linear_motion_is_simple, project_to_best_plane
from meshlab_holefill.algorithms.brunton2009.annealing import anneal_loop, colour_classes, planarity_energy, planarity_terms
from meshlab_holefill.algorithms.brunton2009.unfolding import unfold_loop
from meshlab_holefill.geometry.development import MIN_CLOSURE_RATIO, boundary_gap_angles, close_lengths, developed_area, develop_loop, simple_development
from meshlab_holefill.evaluation.comparison import MeshCase, prepare_case
from meshlab_holefill.geometry.intersections import faces_intersecting
from meshlab_holefill.geometry.quality import corner_angles, triangle_quality
from meshlab_holefill.geometry.segments import min_segment_distance, segment_distances
from meshlab_holefill.geometry.triangulate import polygon_signed_area
from meshlab_holefill.core.holes import boundary_loops, hole_context, nonmanifold_edges
from meshlab_holefill.core.outlines import outline_ratios
from meshlab_holefill.evaluation.metrics import corner_quality_bound
from meshlab_holefill.core import examples
from meshlab_holefill.core.patch import validate_patch

from conftest import cut_disks, grid, mesh_arrays, meshset_from_arrays, sample, sphere_with_holes


# ----------------------------------------------------------------------------- shapes

def wrapped_rectangle(n_arc=20, n_side=3, wrap=200.0, height=1.0):
    """Boundary of a rectangle wrapped around the unit cylinder: its best-plane projection overlaps itself."""
    th = np.radians(np.linspace(0, wrap, n_arc))
    bottom = np.c_[np.cos(th), np.sin(th), np.zeros(n_arc)]
    top = np.c_[np.cos(th[::-1]), np.sin(th[::-1]), np.full(n_arc, height)]
    z = np.linspace(0, height, n_side + 1)[1:-1]
    up = np.c_[np.full_like(z, np.cos(th[-1])), np.full_like(z, np.sin(th[-1])), z]
    down = np.c_[np.ones_like(z), np.zeros_like(z), z[::-1]]
    return np.vstack([bottom, up, top, down])


def trefoil(n=36):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.c_[np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)]


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


def mean_edge(P):
    return float(np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1).mean())


def edge_set(F):
    return {tuple(e) for f in np.asarray(F).tolist() for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}


# ----------------------------------------------------------------------------- Sec. 3.1 building blocks

@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-2, 2), min_size=12, max_size=12), st.sampled_from(["general", "parallel", "point"]))
def test_segment_distance_is_exact(coords, kind):
    A0, A1, B0, B1 = np.reshape(coords, (4, 3))
    if kind == "parallel":
        B1 = B0 + 0.7 * (A1 - A0)
    elif kind == "point":
        A1 = A0.copy()
    d = float(segment_distances(A0, A1, B0, B1))
    s = np.linspace(0, 1, 301)
    X, Y = A0 + np.outer(s, A1 - A0), B0 + np.outer(s, B1 - B0)
    brute = np.sqrt(((X[:, None] - Y[None]) ** 2).sum(-1)).min()
    assert d <= brute + 1e-12  # never above a sampled distance ...
    step = max(np.linalg.norm(A1 - A0), np.linalg.norm(B1 - B0)) / 300
    assert brute - d <= step + 1e-12  # ... and within the sampling resolution of the true minimum


def test_planarity_energy_is_zero_for_a_convex_planar_loop_and_counts_inflections():
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    circle = np.c_[np.cos(t), np.sin(t), np.zeros(12)]
    assert planarity_energy(circle) == pytest.approx(0, abs=1e-12)
    # One reflex vertex flips one normal n_i: two terms of pi (angle between vectors, as written).
    L = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]], float)
    assert planarity_energy(L) == pytest.approx(2 * np.pi)
    # A non-planar loop has positive energy; the terms are angles in [0, pi].
    bent = circle + np.c_[np.zeros(12), np.zeros(12), 0.3 * np.sin(2 * t)]
    terms = planarity_terms(bent)
    assert np.all((terms >= 0) & (terms <= np.pi)) and terms.sum() > 0.1


@pytest.mark.parametrize("m", range(4, 23))
def test_colour_classes_partition_the_loop_into_independent_moves(m):
    classes = colour_classes(m)
    flat = np.concatenate(classes)
    assert sorted(flat.tolist()) == list(range(m))
    for c in classes:
        gap = np.abs(c[:, None] - c[None, :])
        gap = np.minimum(gap, m - gap)
        assert np.all(gap[~np.eye(len(c), dtype=bool)] >= 4)


def test_batched_moves_change_the_energy_by_the_sum_of_single_moves():
    rng = np.random.default_rng(3)
    P = np.c_[np.cos(np.linspace(0, 2 * np.pi, 16, endpoint=False)), np.sin(np.linspace(0, 2 * np.pi, 16, endpoint=False)),
              np.zeros(16)] + 0.1 * rng.normal(size=(16, 3))
    J = colour_classes(16)[0]
    moves = 0.05 * rng.normal(size=(len(J), 3))
    single = 0.0
    for j, dv in zip(J, moves):
        Q = P.copy()
        Q[j] += dv
        single += planarity_energy(Q) - planarity_energy(P)
    Q = P.copy()
    Q[J] += moves
    assert planarity_energy(Q) - planarity_energy(P) == pytest.approx(single, abs=1e-10)


def test_annealing_keeps_the_loop_simple_throughout(bunny_loops):
    V, _, loops = bunny_loops
    P = V[loops[0].vertices]
    eps = 1e-5 * mean_edge(P)
    states = [P]

    def check(Q):
        assert min_segment_distance(Q) > eps
        # No vertex moves by half d_MD or more: two segments d_MD apart cannot meet on the way,
        # so the motion between two states is free of crossings, not only the states.
        assert np.linalg.norm(Q - states[-1], axis=1).max() < 0.5 * min_segment_distance(states[-1])
        for t in (0.25, 0.5, 0.75):
            assert min_segment_distance((1 - t) * states[-1] + t * Q) > eps
        states.append(Q.copy())

    A, stats = anneal_loop(P, np.random.default_rng(0), eps=eps, sa_steps=40 * len(P), stop_when_simple=False,
                           on_move=check)
    assert stats["accepted"] > 0 and len(states) > 20
    assert stats["d_md"] > eps


@pytest.mark.parametrize("step_bound", ["global", "local"])
def test_compiled_annealing_moves_equal_the_numpy_steps(bunny_loops, step_bound):
    # The kernels of _anneal_kernels against the numpy steps they replace: the same loop to the
    # last bit, the same statistics and the same generator state afterwards (restarts continue
    # from it), on wrapped, knotted and scanned loops, with uphill moves and cone directions.
    V, _, loops = bunny_loops
    for P in (wrapped_rectangle(), trefoil(), V[loops[0].vertices], V[loops[1].vertices]):
        eps = 1e-5 * mean_edge(P)
        runs = []
        for compiled in (True, False):
            rng = np.random.default_rng(5)
            A, stats = anneal_loop(P, rng, eps=eps, sa_steps=30 * len(P), step_bound=step_bound,
                                   stop_when_simple=False, compiled=compiled)
            runs.append((A, stats, rng.random()))
        (A, stats, after), (B, reference, after_reference) = runs
        assert np.array_equal(A, B)
        assert stats == reference and after == after_reference
        assert stats["accepted"] > 0


def test_warm_up_loads_the_annealing_kernels():
    from meshlab_holefill.algorithms.brunton2009 import _anneal_kernels as K
    cu.WARM_UP()
    for name in ("propose_moves", "apply_moves"):
        assert len(getattr(K, name).signatures) >= 1, name


def test_linear_motion_to_the_projection_is_checked_exactly(bunny_loops):
    V, _, loops = bunny_loops
    P = V[loops[0].vertices]
    A, _ = anneal_loop(P, np.random.default_rng(1), eps=1e-5 * mean_edge(P), sa_steps=20 * len(P),
                       stop_when_simple=False)
    Q, projected, normal = project_to_best_plane(A)
    assert np.abs((projected - projected.mean(0)) @ normal).max() < 1e-12  # planar
    if linear_motion_is_simple(Q, 1e-9):
        for t in np.linspace(0, 1, 11):
            assert min_segment_distance(A + t * (projected - A)) > 0
    # A loop wrapped around a cylinder collides with itself on the way to its projection.
    W = wrapped_rectangle()
    assert not linear_motion_is_simple(project_to_best_plane(W)[0], 1e-9)


def folded_circle(n=48, fold_degrees=90.0):
    """A unit circle drawn on a sheet folded along the x axis: the flank v > 0 turned up by ``fold_degrees``."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    x, v = np.cos(t), np.sin(t)
    a = np.radians(fold_degrees)
    up = v > 0
    return np.c_[x, np.where(up, v * np.cos(a), v), np.where(up, v * np.sin(a), 0.0)]


def test_unfolded_polygon_keeps_the_loop_edge_lengths_the_projection_shortens():
    # Around a crease the best plane tilts away from both flanks and the projection shortens
    # the edges; the unfolding read as a linkage's keeps them: the sheet's own (flat) circle.
    P = folded_circle()
    loop_edges = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)
    Q, info = unfold_loop(P, np.random.default_rng(0))
    R, reference = unfold_loop(P, np.random.default_rng(0), lengths="projection")
    assert info["loop_lengths"] and not reference["loop_lengths"]
    planar = lambda X: np.linalg.norm(np.roll(X, -1, axis=0) - X, axis=1)
    assert np.abs(planar(Q) / loop_edges - 1).max() < 0.02
    assert np.abs(planar(R) / loop_edges - 1).max() > 0.2
    flat = 0.5 * 48 * np.sin(2 * np.pi / 48)  # the flat circle's area (regular polygon of 48 sides)
    assert abs(abs(polygon_signed_area(Q)) / flat - 1) < 0.05 < abs(abs(polygon_signed_area(R)) / flat - 1)
    # the directions are the projection's: each edge turned by less than a degree
    cos = np.einsum("ij,ij->i", np.roll(Q, -1, axis=0) - Q, np.roll(R, -1, axis=0) - R) / (planar(Q) * planar(R))
    assert np.degrees(np.arccos(np.clip(cos, -1, 1))).max() < 1.0


def test_loop_lengths_and_the_development_bring_a_patch_across_a_crease_closer():
    # A round hole across the fold of a sheet bent by 90 degrees: mean distance of the patch's
    # vertices to the two half-planes, projection > loop lengths (default) > development (option).
    V, F = grid(25, 25)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0.0)], 0.3)
    up = V[:, 1] > 0.5
    V = np.c_[V[:, 0], np.where(up, 0.5, V[:, 1]), np.where(up, V[:, 1] - 0.5, 0.0)]
    ctx = hole_context(V, F, min(boundary_loops(F), key=len), rings=cu.RINGS)

    def off_sheet(X):
        y, z = X[:, 1] - 0.5, X[:, 2]
        corner = np.hypot(y, z)
        return np.minimum(np.where(y <= 0, np.abs(z), corner), np.where(z >= 0, np.abs(y), corner)).mean()

    patches = {name: cu.fill(ctx, **options) for name, options in
               [("projection", {"lengths": "projection", "domain": "unfolding"}), ("loop", {"domain": "unfolding"}),
                ("development", {"domain": "development"})]}
    for patch in patches.values():
        assert examples.is_disc_patch(patch, ctx)
    assert patches["loop"].info["loop_lengths"] and patches["development"].info["unfolding"] == "development"
    d = {name: off_sheet(patch.vertices) for name, patch in patches.items()}
    assert d["development"] < d["loop"] < 0.6 * d["projection"]


def test_annealing_unfolds_a_wrapped_loop_and_is_reproducible():
    W = wrapped_rectangle()
    Q, info = unfold_loop(W, np.random.default_rng(0))
    assert info["method"] == "annealing" and info["sa_steps"] > 0
    assert linear_motion_is_simple(Q, 1e-5 * mean_edge(W))
    Q2, info2 = unfold_loop(W, np.random.default_rng(0))
    assert np.array_equal(Q, Q2) and info == info2


def test_a_knotted_loop_fails_clearly_after_its_restarts():
    with pytest.raises(HoleFillError, match="unfolding failed: no annealing run out of 5 .*knotted"):
        unfold_loop(trefoil(), np.random.default_rng(0), max_restarts=5)


@pytest.mark.parametrize("loop, message", [
    (np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [1, 0, 0], [0, 1, 0]], float), "touches itself"),
    (np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], float), "zero-area"),
    (np.array([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]], float), "non-finite"),
    (np.array([[0, 0, 0], [2, 0, 0], [0, 1, 0], [2, 1, 0]], float), "touches itself"),  # a bow tie
])
def test_degenerate_loops_fail_clearly(loop, message):
    with pytest.raises(HoleFillError, match=message):
        unfold_loop(loop, np.random.default_rng(0))


def test_development_of_a_planar_hole_is_the_hole_itself():
    V, F = grid(14, 14)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0)], 0.3)
    loop = [lp for lp in boundary_loops(F) if len(lp) < 52][0]
    ctx = hole_context(V, F, loop, rings=2)
    Q = develop_loop(ctx.points, boundary_gap_angles(ctx.vertices, ctx.faces, ctx.size))
    D2 = np.linalg.norm(Q[:, None] - Q[None], axis=2)
    D3 = np.linalg.norm(ctx.points[:, None, :2] - ctx.points[None, :, :2], axis=2)
    assert np.abs(D2 - D3).max() < 1e-9  # congruent: same lengths and angles


# ----------------------------------------------------------------------------- Sec. 3.2 and 3.3

def star_polygon(radii):
    t = np.linspace(0, 2 * np.pi, len(radii), endpoint=False)
    return np.c_[np.cos(t), np.sin(t)] * np.asarray(radii)[:, None]


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(0.3, 1.0), min_size=5, max_size=30))
def test_cdt_keeps_every_boundary_edge_and_adds_no_steiner_point(radii):
    Q = star_polygon(radii)
    points, F = tri.constrained_delaunay(Q)
    m = len(Q)
    assert np.array_equal(points, Q) and len(F) == m - 2
    edges = edge_set(F)
    assert all((i, (i + 1) % m) in edges for i in range(m))  # every polygon edge, in the loop's direction
    A = points[F]
    cross = (A[:, 1, 0] - A[:, 0, 0]) * (A[:, 2, 1] - A[:, 0, 1]) - (A[:, 2, 0] - A[:, 0, 0]) * (A[:, 1, 1] - A[:, 0, 1])
    assert np.all(cross > 0)
    # Constrained Delaunay: every non-polygon edge is locally Delaunay (opposite angles sum <= pi).
    ang = corner_angles(np.c_[points, np.zeros(m)], F)
    opposite = {}
    for f, (a, b, c) in enumerate(F.tolist()):
        for (u, v), w in (((a, b), 2), ((b, c), 0), ((c, a), 1)):
            opposite.setdefault(tuple(sorted((u, v))), []).append(ang[f, w])
    for e, alphas in opposite.items():
        if len(alphas) == 2:
            assert alphas[0] + alphas[1] <= np.pi + 1e-9


def test_forbidden_chords_are_broken_by_a_steiner_point():
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    points, F = tri.constrained_delaunay(square, [[0, 2], [1, 3]])
    edges = {tuple(sorted(e)) for e in edge_set(F)}
    assert len(points) > 4 and (0, 2) not in edges and (1, 3) not in edges


def test_refinement_meets_chews_angle_and_length_bounds():
    h = 0.1
    m = 40
    Q = star_polygon(np.full(m, h / (2 * np.sin(np.pi / m))))  # regular polygon with edges h
    points, F = tri.refine_planar(Q, h)
    assert np.array_equal(points[:m], Q)  # boundary untouched: no Steiner point on it
    assert all((i, (i + 1) % m) in edge_set(F) for i in range(m))
    X = np.c_[points, np.zeros(len(points))]
    ang = np.degrees(corner_angles(X, F))
    assert ang.min() >= 30 - 1e-6 and ang.max() <= 120 + 1e-6
    E = np.array(sorted(edge_set(F)))
    assert np.linalg.norm(X[E[:, 0]] - X[E[:, 1]], axis=1).max() <= 2 * h


def test_planar_domain_is_scaled_to_the_loops_perimeter():
    P = np.array([[0, 0, 0], [2, 0, 1], [2, 2, 0], [0, 2, 1]], float)
    Qs, scale = tri.scale_to_loop(project_to_best_plane(P)[0], P)
    assert tri.polygon_perimeter(Qs) == pytest.approx(tri.polygon_perimeter(P))


def sphere_cap_domain():
    """A sphere hole's context and its refined planar domain (points, faces in patch numbering)."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    V, F = mesh_arrays(ms)
    _, F, _ = cut_disks(V, F, [(0, 0, 1)], 0.6)
    ctx = hole_context(V, F, boundary_loops(F)[0], rings=2)
    points, Fp = tri.refine_planar(tri.scale_to_loop(project_to_best_plane(ctx.points)[0], ctx.points)[0],
                                  float(ctx.edge_scale.mean()))
    return ctx, points, Fp


@pytest.mark.parametrize("energy, order", [("area", 1), ("area_interior", 1), ("fairing", 2)])
def test_embedding_solves_its_energy(energy, order):
    ctx, points, Fp = sphere_cap_domain()
    s = len(points) - ctx.size
    interior = embed_patch(ctx, s, Fp, energy=energy)
    n_ctx = len(ctx.vertices)
    joint = np.concatenate([ctx.faces, np.where(Fp < ctx.size, Fp, Fp - ctx.size + n_ctx)])
    free = np.arange(n_ctx + s) >= n_ctx
    R = energy_rows(joint, n_ctx + s, free, order, anchors=energy == "area")
    X = np.concatenate([ctx.vertices, interior])
    energy_value, gradient = embedding_energy(X, R, free)
    assert np.abs(gradient).max() < 1e-10
    if energy == "area":  # least-squares mesh: loop rows too, so U(p) cannot vanish everywhere
        assert s < R.shape[0] <= s + ctx.size and energy_value > 0
    # The paper's quasi-Newton solve (L-BFGS) reaches the same minimiser.
    start = X.copy()
    start[free] = ctx.points.mean(axis=0)

    def f(x):
        Y = start.copy()
        Y[free] = x.reshape(-1, 3)
        e, g = embedding_energy(Y, R, free)
        return e, g.ravel()

    res = scipy.optimize.minimize(f, start[free].ravel(), jac=True, method="L-BFGS-B",
                                  options={"maxiter": 20000, "gtol": 1e-12, "ftol": 1e-15})
    assert res.fun >= energy_value - 1e-12
    assert np.abs(res.x.reshape(-1, 3) - interior).max() < 1e-3


@pytest.mark.parametrize("energy", ["area", "fairing"])
def test_symmetric_mode_lu_moves_the_patch_by_rounding_only(energy, monkeypatch):
    # SuperLU's symmetric mode (minimum degree on A + A^T, diagonal pivots preferred) against its
    # default (COLAMD, partial pivoting), for the energy solve and the tangential relaxation.
    from meshlab_holefill.algorithms.brunton2009 import embedding, tangential_relaxation as relaxation
    ctx, points, Fp = sphere_cap_domain()
    s = len(points) - ctx.size
    fast = embed_patch(ctx, s, Fp, energy=energy, tangential=True)
    for module in (embedding, relaxation):
        monkeypatch.setattr(module, "symmetric_lu", lambda A: scipy.sparse.linalg.splu(A.tocsc()))
    reference = embed_patch(ctx, s, Fp, energy=energy, tangential=True)
    assert np.abs(fast - reference).max() < 1e-12 * np.abs(reference).max()


def test_least_squares_mesh_rows_follow_the_surrounding_slope():
    # E_AREA over P_Int alone is a membrane spanning the loop; the least-squares mesh's loop
    # rows make the patch leave the loop along the sphere, much closer to it.
    ctx, points, Fp = sphere_cap_domain()
    s = len(points) - ctx.size
    off = {e: np.abs(np.linalg.norm(embed_patch(ctx, s, Fp, energy=e), axis=1) - 1).mean()
           for e in ("area", "area_interior", "fairing")}
    assert off["area"] < 0.5 * off["area_interior"]
    n_ctx = len(ctx.vertices)
    joint = np.concatenate([ctx.faces, np.where(Fp < ctx.size, Fp, Fp - ctx.size + n_ctx)])
    free = np.arange(n_ctx + s) >= n_ctx
    R = energy_rows(joint, n_ctx + s, free, 1, anchors=True)
    W = energy_rows(joint, n_ctx + s, np.ones(n_ctx + s, bool), 1)
    # the anchor rows are exactly the fixed vertices whose umbrella reaches a free vertex: the loop
    touching = np.flatnonzero(np.asarray(abs(W[:n_ctx, n_ctx:]).sum(axis=1)).ravel() > 0)
    assert 0 < len(touching) and touching.max() < ctx.size
    assert R.shape[0] == s + len(touching)


def test_energy_parameters_default_to_the_least_squares_mesh():
    names = {p.name: p for p in cu.PARAMS}
    assert names["energy"].default == "area" and names["area_rows"].default == "mesh"


# ----------------------------------------------------------------------------- fill() and the filter

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


# ----------------------------------------------------------------------------- the benchmark's wrapped torus hole

@pytest.fixture(scope="module")
def torus_wrapped_hole():
    """The benchmark's large torus hole: 211 edges, wrapped 255 degrees around the tube (seed 0)."""
    ms = pymeshlab.MeshSet()
    ms.create_torus(hradius=1.0, vradius=0.4, hsubdiv=192, vsubdiv=96)
    V, F = mesh_arrays(ms)
    case = prepare_case(MeshCase("torus", V, F), holes=4, seed=0)
    hole = max(case.holes, key=lambda h: h.boundary_edges)
    return hole_context(case.V0, case.F0, boundary_loops(case.F0)[hole.loop_index], rings=cu.RINGS)


def test_development_closure_never_reverses_an_edge():
    # A wide gap makes the plain least-squares closure (no bound) push the long last edge
    # past zero: reversed, it would turn the polygon's corners at its ends inside out.
    th = np.radians([0, 90, 180, 270, 430])
    lengths = np.array([1.0, 1.0, 1.0, 0.3, 2.0])
    D = np.c_[np.cos(th), np.sin(th)]
    plain = close_lengths(lengths, D, min_ratio=-np.inf)
    assert plain[4] < 0 and plain @ D == pytest.approx(np.zeros(2), abs=1e-12)
    closed = close_lengths(lengths, D)
    assert closed @ D == pytest.approx(np.zeros(2), abs=1e-12)
    assert np.all(closed >= MIN_CLOSURE_RATIO * lengths - 1e-12)
    # The active set gives the bounded minimiser of sum (dl_i / l_i)^2.
    res = scipy.optimize.minimize(lambda x: np.sum((x / lengths - 1.0) ** 2), lengths, method="SLSQP",
                                  bounds=[(MIN_CLOSURE_RATIO * v, None) for v in lengths],
                                  constraints={"type": "eq", "fun": lambda x: x @ D}, options={"ftol": 1e-14})
    assert closed == pytest.approx(res.x, abs=1e-6)
    # Without an edge at the bound the closure is the plain one.
    th2 = np.radians([0, 90, 180, 250, 300])
    D2 = np.c_[np.cos(th2), np.sin(th2)]
    ones = np.array([1.0, 1.0, 1.0, 1.0, 3.0])
    assert np.array_equal(close_lengths(ones, D2), close_lengths(ones, D2, min_ratio=-np.inf))


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
    assert q0.min() < 0.3 <= q1.min() and q1.mean() >= max(q0.mean(), 0.85)
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


# ----------------------------------------------------------------------------- tangential relaxation

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


# ----------------------------------------------------------------------------- repair

def test_repair_prefers_a_domain_whose_patch_clears_a_folded_border_to_a_sliver_ear(bunny_loops):
    """bunny10k_textured's loop 1 (22 edges): a border face folds back over the hole at loop vertex 1,
    so the annealed domain's patch crosses it; clipping the ear there leaves a 0.116 sliver (the
    corner is 152 degrees wide), while the 0.2-relaxed development's patch crosses nothing."""
    V, F, loops = bunny_loops
    ctx = hole_context(V, F, loops[1], rings=cu.RINGS)
    assert len(loops[1]) == 22 and corner_quality_bound(V, F, loops[1].vertices) > 0.3
    first, _ = unfold_loop(ctx.points, np.random.default_rng(0))
    X, Fp = tri.triangulate_and_embed(ctx, first, np.arange(ctx.size), [], "fairing", True, True)
    assert len(crossing_repair.crossing_faces(ctx, X, Fp)) > 0  # the paper's patch crosses the fold
    # Ear clipping alone (the first domain only) ends with a sliver ear.
    n_bad, Xe, Fe, clipped, _, _ = crossing_repair.repair_crossings(ctx, [(first, "annealing", None)], X, Fp, "fairing", True, True)
    assert n_bad == 0 and clipped > 0
    assert triangle_quality(np.concatenate([ctx.points, Xe]), Fe).min() < 0.3
    patch = cu.fill(ctx)
    q = triangle_quality(patch.all_points(ctx.points), patch.faces)
    assert patch.info["ears_clipped"] == 0 and patch.info["crossing_faces"] == 0
    assert patch.info["unfolding"] == "development" and patch.info["development_relax"] > 0
    assert q.min() >= 0.3
    assert len(crossing_repair.crossing_faces(ctx, patch.vertices, patch.faces)) == 0
    validate_patch(patch, ctx.points, ctx.forbidden_edges)


# ----------------------------------------------------------------------------- direct tests of building blocks

def flat_disk_hole(n=9, radius=0.3):
    """HoleContext of a disk cut from the middle of a flat n x n grid (a 20-vertex staircase for n = 9)."""
    V, F = grid(n, n)
    V, F, _ = cut_disks(V, F, [(0.5, 0.5, 0.0)], radius)
    return hole_context(V, F, min(boundary_loops(F), key=len), rings=cu.RINGS)


def fill_rest(ctx, Q, keep, ears):
    """Ears plus a plain triangulation of the sub-loop ``keep``: a loop-only patch (Patch numbering)."""
    from meshlab_holefill.geometry.triangulate import triangulate_polygon

    _, T = triangulate_polygon(Q[keep])
    return np.concatenate([np.asarray(ears, np.int64).reshape(-1, 3), np.asarray(keep)[T]])


def test_clip_ears_cuts_exactly_the_convex_corners_of_a_staircase_hole():
    from meshlab_holefill.geometry.triangulate import polygon_signed_area
    from meshlab_holefill.core.patch import Patch

    ctx = flat_disk_hole()
    k, Q = ctx.size, ctx.points[:, :2]
    assert k == 20 and polygon_signed_area(Q) > 0
    # Turn of each corner (counter-clockwise loop): > 0 convex, < 0 reflex, 0 straight.
    d_in, d_out = Q - np.roll(Q, 1, axis=0), np.roll(Q, -1, axis=0) - Q
    turn = np.round(d_in[:, 0] * d_out[:, 1] - d_in[:, 1] * d_out[:, 0], 12)
    keep, ears, clipped = crossing_repair.clip_ears(ctx, Q, np.arange(k), [], list(range(k)))
    # Every vertex offends, yet a reflex ear would lie on the mesh and a straight one has no area:
    # exactly the 8 convex corners go, and never two neighbours in one round.
    assert clipped == len(ears) == 8
    assert sorted(e[1] for e in ears) == np.flatnonzero(turn > 0).tolist()
    assert keep.tolist() == np.flatnonzero(turn <= 0).tolist()
    assert all((e[0], e[2]) == ((e[1] - 1) % k, (e[1] + 1) % k) for e in ears)  # (prev, v, next) of the loop
    # The ears and the rest of the loop close the hole once, oriented like the loop.
    validate_patch(Patch(np.zeros((0, 3)), fill_rest(ctx, Q, keep, ears)), ctx.points, ctx.forbidden_edges)
    # Nothing offending, nothing clipped.
    keep, ears, clipped = crossing_repair.clip_ears(ctx, Q, np.arange(k), [], [])
    assert clipped == 0 and ears == [] and keep.tolist() == list(range(k))


def test_clip_ears_never_uses_a_chord_the_mesh_already_has():
    from meshlab_holefill.core.patch import Patch

    # A 2 x 2 block of squares cut from a 6 x 6 grid except the triangle (14, 15, 21) of its
    # lower-left square: the loop runs 14 -> 21 -> 15, and the chord (14, 15) is a mesh edge.
    V, F = grid(6, 6)
    cells = [2 * 5 + 2, 2 * 5 + 3, 3 * 5 + 2, 3 * 5 + 3]  # grid() puts the (a, b, c) halves first, then (a, c, d)
    removed = [c for c in cells if c != 12] + [25 + c for c in cells]
    F = np.delete(F, removed, axis=0)
    ctx = hole_context(V, F, min(boundary_loops(F), key=len), rings=cu.RINGS)
    assert ctx.loop[:3].tolist() == [14, 21, 15] and ctx.forbidden_edges.tolist() == [[0, 2]]
    Q = ctx.points[:, :2]
    keep, ears, clipped = crossing_repair.clip_ears(ctx, Q, np.arange(ctx.size), [], [1])
    assert clipped == 0 and ears == [] and keep.tolist() == list(range(ctx.size))
    # With every vertex offending, the corner at 21 still stays; what is clipped closes cleanly.
    keep, ears, clipped = crossing_repair.clip_ears(ctx, Q, np.arange(ctx.size), [], list(range(ctx.size)))
    assert clipped > 0 and 1 in keep.tolist() and all(e[1] != 1 for e in ears)
    validate_patch(Patch(np.zeros((0, 3)), fill_rest(ctx, Q, keep, ears)), ctx.points, ctx.forbidden_edges)
    # The rule on its own (that ear above also lies on the mesh face): on the staircase hole the
    # convex corner 0 is clipped unless its chord (19, 1) is declared a mesh edge (as across a
    # thin wall); the other seven convex corners go as before.
    import dataclasses

    ctx = flat_disk_hole()
    walled = dataclasses.replace(ctx, forbidden_edges=np.array([[1, 19]]))
    _, ears, clipped = crossing_repair.clip_ears(ctx, ctx.points[:, :2], np.arange(20), [], list(range(20)))
    assert 0 in [e[1] for e in ears] and clipped == 8
    keep, ears, clipped = crossing_repair.clip_ears(walled, ctx.points[:, :2], np.arange(20), [], list(range(20)))
    assert clipped == 7 and 0 in keep.tolist() and all(e[1] != 0 for e in ears)


def test_improve_by_swaps_undoes_a_bad_swap_and_keeps_the_energy_solved():
    from meshlab_holefill.geometry.quality import face_normals
    from meshlab_holefill.geometry.topology import interior_edges
    from meshlab_holefill.core.patch import Patch

    ctx = flat_disk_hole()
    k = ctx.size
    vertices, faces = tri.triangulate_and_embed(ctx, ctx.points[:, :2], np.arange(k), [], "area", True)
    s, X = len(vertices), np.concatenate([ctx.points, vertices])
    # Degrade the refined patch by its worst legal swap, then solve E_AREA on that connectivity.
    E, f1, c1, f2, c2 = interior_edges(faces, len(X))
    worst = None
    for i in range(len(E)):
        u, v, c = faces[f1[i], c1[i]], faces[f1[i], (c1[i] + 1) % 3], faces[f1[i], (c1[i] + 2) % 3]
        d = faces[f2[i], (c2[i] + 2) % 3]
        G = faces.copy()
        G[f1[i]], G[f2[i]] = (u, d, c), (d, v, c)
        try:
            validate_patch(Patch(vertices, G), ctx.points, ctx.forbidden_edges)
        except HoleFillError:
            continue
        if np.all(face_normals(X, G)[:, 2] > 0):
            q = triangle_quality(X, G).min()
            worst = (q, G) if worst is None or q < worst[0] else worst
    bad_faces = worst[1]
    bad_vertices = embed_patch(ctx, s, bad_faces, energy="area")
    q0 = triangle_quality(np.concatenate([ctx.points, bad_vertices]), bad_faces)
    out_vertices, out_faces, swaps = quality_swaps.improve_by_swaps(ctx, bad_vertices, bad_faces, "area")
    q1 = triangle_quality(np.concatenate([ctx.points, out_vertices]), out_faces)
    assert swaps > 0 and q1.min() > q0.min() + 0.1  # measured: 0.49 -> 0.82
    assert len(out_faces) == len(bad_faces) and len(out_vertices) == s
    validate_patch(Patch(out_vertices, out_faces), ctx.points, ctx.forbidden_edges)
    assert len(crossing_repair.crossing_faces(ctx, out_vertices, out_faces)) == 0
    assert np.abs(out_vertices[:, 2]).max() < 1e-12  # flat context, flat patch
    # The kept vertices minimise E_AREA on the kept connectivity, not on the one they came from.
    assert np.allclose(out_vertices, embed_patch(ctx, s, out_faces, energy="area"), atol=1e-12)
    # No new vertex, nothing to swap.
    assert quality_swaps.improve_by_swaps(ctx, np.zeros((0, 3)), bad_faces, "area")[2] == 0


@settings(max_examples=30, deadline=None)
@given(n=st.integers(4, 6), order=st.sampled_from([1, 2]), anchors=st.booleans(), seed=st.integers(0, 10_000))
def test_minimise_embedding_energy_matches_a_dense_least_squares_solve(n, order, anchors, seed):
    from meshlab_holefill.algorithms.brunton2009.embedding import minimise_embedding_energy

    V, F = grid(n, n)
    rng = np.random.default_rng(seed)
    X = rng.normal(size=V.shape)  # arbitrary fixed positions: the solve does not rely on a flat border
    free = np.ones(n * n, bool)
    ij = np.arange(n * n).reshape(n, n)
    free[np.r_[ij[0], ij[-1], ij[:, 0], ij[:, -1]]] = False
    R = energy_rows(F, n * n, free, order, anchors=anchors)
    assert R.shape[0] > free.sum() if anchors else R.shape[0] == free.sum()
    start = X.copy()
    start[free] = np.nan  # free rows of the input are ignored
    Y = minimise_embedding_energy(start, R, free)
    D = R.toarray()
    expected = np.linalg.lstsq(D[:, free], -D[:, ~free] @ X[~free], rcond=None)[0]
    assert np.array_equal(Y[~free], X[~free])
    assert np.allclose(Y[free], expected, atol=1e-10)
    assert np.abs(embedding_energy(Y, R, free)[1]).max() < 1e-9  # the gradient vanishes


def test_minimise_embedding_energy_without_free_rows_or_with_a_free_island():
    from meshlab_holefill.algorithms.brunton2009.embedding import minimise_embedding_energy

    V, F = grid(4, 4)
    R = energy_rows(F, 16, np.zeros(16, bool), 1)
    assert np.array_equal(minimise_embedding_energy(V, R, np.zeros(16, bool)), V)
    # A free triangle joined to nothing fixed makes R_f singular: the least-squares fallback is
    # still a minimiser (the island collapses to a point, the rest solved as usual).
    F2 = np.concatenate([F, [[16, 17, 18]]])
    free = np.zeros(19, bool)
    free[[5, 6, 9, 10, 16, 17, 18]] = True
    X = np.random.default_rng(0).normal(size=(19, 3))
    R = energy_rows(F2, 19, free, 1)
    Y = minimise_embedding_energy(X, R, free)
    D = R.toarray()
    best = np.linalg.lstsq(D[:, free], -D[:, ~free] @ X[~free], rcond=None)[0]
    assert np.allclose(Y[[5, 6, 9, 10]], best[:4], atol=1e-9)
    assert np.allclose(Y[16:], Y[16], atol=1e-9)
    assert embedding_energy(Y, R, free)[0] == pytest.approx(0.0, abs=1e-15)


# ----------------------------------------------------------------------------- domain area guard (beyond the paper)

def flat_strip_hole():
    """A flat grid with a strip one cell high and 0.8 long removed: a 66-edge loop around area 0.04."""
    V, F = grid(41, 21)
    C = V[F].mean(axis=1)
    remove = (C[:, 1] > 0.45) & (C[:, 1] < 0.5) & (np.abs(C[:, 0] - 0.5) < 0.4)
    return V, F[~remove]


def test_developed_area_of_a_planar_hole_is_its_area():
    V, F = flat_strip_hole()
    (loop,) = [lp for lp in boundary_loops(F) if len(lp) < 100]
    ctx = hole_context(V, F, loop, rings=2)
    area = developed_area(ctx.points, boundary_gap_angles(ctx.vertices, ctx.faces, ctx.size))
    assert len(loop) == 66
    assert area == pytest.approx(0.8 * 0.05, rel=1e-9)


def test_developed_area_of_a_degenerate_development_is_the_vector_area():
    # A skew quad of four equal edges whose surface leaves angles 0.05 and pi - 0.05 open
    # develops to a rhombus of area 1.25 sin(0.05) = 0.06; any surface spanning the loop has at
    # least its vector area, 1, which is then the estimate.
    P = np.array([[0, 0, 0], [1, 0, 0.5], [1, 1, 0], [0, 1, 0.5]], float)
    gaps = np.array([0.05, np.pi - 0.05, 0.05, np.pi - 0.05])
    Q = develop_loop(P, gaps)
    assert abs(polygon_signed_area(Q)) == pytest.approx(1.25 * np.sin(0.05), rel=1e-9)
    vector_area = 0.5 * np.linalg.norm(np.cross(P, np.roll(P, -1, axis=0)).sum(axis=0))
    assert vector_area == pytest.approx(1.0)
    assert developed_area(P, gaps) == pytest.approx(1.0, rel=1e-12)
    assert developed_area(P, np.full(4, np.pi / 2)) == pytest.approx(1.25, rel=1e-12)  # the square


def test_domains_much_larger_than_the_missing_surface_are_refused():
    V, F = flat_strip_hole()
    (loop,) = [lp for lp in boundary_loops(F) if len(lp) < 100]
    ctx = hole_context(V, F, loop, rings=2)
    gaps = boundary_gap_angles(ctx.vertices, ctx.faces, ctx.size)
    strip = (develop_loop(ctx.points, gaps), "development", 0.0)
    round_polygon = (develop_loop(ctx.points, gaps, relax=1.0), "development", 1.0)  # same edges, convex
    # the convex polygon of a 1.7-long perimeter encloses ~0.22, 5.7 times the strip's 0.04
    assert planar_domains.domains_within_area(ctx.points, gaps, [round_polygon, strip], 6.0) == [round_polygon, strip]
    assert planar_domains.domains_within_area(ctx.points, gaps, [round_polygon, strip], 5.0) == [strip]
    with pytest.raises(HoleFillError, match=r"at least 5\.\d times the area of the missing surface"):
        planar_domains.domains_within_area(ctx.points, gaps, [round_polygon], 5.0)


def test_planar_domains_sharing_their_developments_answer_as_fresh_ones(monkeypatch):
    # Two fills of one hole (domain='smoothest') share the developments: each is made once, and
    # every object reports only what it was asked for (no blend before its fallback is asked).
    V, F = flat_strip_hole()
    (loop,) = [lp for lp in boundary_loops(F) if len(lp) < 100]
    ctx = hole_context(V, F, loop, rings=2)
    gaps = boundary_gap_angles(ctx.vertices, ctx.faces, ctx.size)
    Q = develop_loop(ctx.points, gaps, relax=1.0)
    calls = []
    counted = planar_domains.simple_development
    monkeypatch.setattr(planar_domains, "simple_development", lambda *a: calls.append(a) or counted(*a))
    fresh = [planar_domains.PlanarDomains(ctx.points, gaps, 1e-5, True, 6.0) for _ in range(2)]
    shared = {}
    first, second = (planar_domains.PlanarDomains(ctx.points, gaps, 1e-5, True, 6.0, shared) for _ in range(2))
    assert first.fallback() is second.fallback() and np.array_equal(first.fallback(), fresh[0].fallback())
    assert len(calls) == 2  # one for the fresh object, one for both shared ones
    assert first.relax == second.relax == fresh[0].relax
    third = planar_domains.PlanarDomains(ctx.points, gaps, 1e-5, True, 6.0, shared)
    assert third.relax is None  # not asked yet
    for a, b in zip(third.all(Q, "annealing"), fresh[1].all(Q, "annealing")):
        assert np.array_equal(a[0], b[0]) and a[1:] == b[1:]


def test_max_domain_area_reaches_the_filter_and_fails_the_hole_cleanly():
    V, F = flat_strip_hole()
    ms = meshset_from_arrays(V, F)
    res = ms.meshing_close_holes_curve_unfolding(max_domain_area=0.5)
    (hole,) = [h for h in res["holes"] if h["boundary_edges"] == 66]
    assert hole["status"] == "failed" and "1.0 times the area of the missing surface" in hole["reason"]
    V2, F2 = mesh_arrays(ms)
    assert np.array_equal(V2, V) and np.array_equal(F2, F)  # untouched (the grid's outer border is not filled)
    ms = meshset_from_arrays(V, F)
    res = ms.meshing_close_holes_curve_unfolding()
    assert [h["status"] for h in res["holes"] if h["boundary_edges"] == 66] == ["closed"]


def test_a_long_strip_hole_of_the_bunny_fails_fast_instead_of_bulging():
    """Fuzzing found it: 697 border edges around a strip 1.6 edges wide across bunny.obj.

    The annealing and every simple development unfold it to round polygons 15 to 27 times the
    strip's area, whose patches (50k and 88k faces) crossed the mesh; the repair then clipped
    ears for 158 s before the hole failed. Now it fails at once and names the reason.
    """
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("bunny.obj"))
    V, F = mesh_arrays(ms)
    rng = np.random.default_rng(4)
    C = V[F].mean(axis=1)
    d = rng.normal(size=3); d /= np.linalg.norm(d)
    e = np.cross(d, rng.normal(size=3)); e /= np.linalg.norm(e)
    p0 = V[rng.integers(len(V))]
    diag = np.linalg.norm(V.max(0) - V.min(0))
    edge = np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1).mean()
    strip = ((np.abs((C - p0) @ d) < 0.8 * edge) & (np.abs((C - p0) @ e) < 0.5 * diag)
             & ((C - p0) @ np.cross(d, e) > -0.1 * diag) & (np.linalg.norm(C - p0, axis=1) < 0.6 * diag))
    ms = meshset_from_arrays(V, F[~strip])
    res = ms.meshing_close_holes_curve_unfolding()
    (hole,) = res["holes"]
    assert hole["boundary_edges"] == 697 and hole["status"] == "failed"
    assert "times the area of the missing surface" in hole["reason"] and "strip-shaped" in hole["reason"]
    assert np.array_equal(mesh_arrays(ms)[1], F[~strip])


def _scipy_umbrella(F, n):
    """U built by scipy's sparse algebra, diags(1 / degree) @ (A - diags(degree)): the oracle."""
    import scipy.sparse as sp
    from meshlab_holefill.geometry.laplacian import uniform_laplacian

    L = uniform_laplacian(np.asarray(F, np.int64), n)
    degree = -L.diagonal()
    return (sp.diags(np.where(degree > 0, 1.0 / np.maximum(degree, 1.0), 0.0)) @ L).tocsr()


def test_umbrella_operator_is_scipys_matrix_entry_for_entry():
    """Same stored entries, in the same order within each row, so later products and LU factors are identical."""
    from conftest import grid

    rng = np.random.default_rng(0)
    _, F = grid(7)
    cases = [(F, int(F.max()) + 4)]  # isolated vertices at the end
    cases += [(F[rng.choice(len(F), size=len(F) // 2, replace=False)], int(F.max()) + 1) for _ in range(5)]
    cases += [(rng.integers(0, 25, (15, 3)), 25) for _ in range(20)]  # some faces degenerate
    for F, n in cases:
        got, expected = umbrella_operator(F, n), _scipy_umbrella(F, n)
        for attr in ("indptr", "indices", "data"):
            np.testing.assert_array_equal(getattr(got, attr), getattr(expected, attr))
        W = got.toarray()
        used = np.abs(W).sum(axis=1) > 0
        np.testing.assert_allclose(W[used].sum(axis=1), 0.0, atol=1e-12)  # U of a constant is zero


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


# ----------------------------------------------------------------------------- domain='smoothest' (beyond the paper)

from meshlab_holefill.algorithms.brunton2009.domain_choice import DOMAINS, smoothest_patch  # noqa: E402
from meshlab_holefill.core.border_bend import border_bend  # noqa: E402
from meshlab_holefill.core.patch import Patch  # noqa: E402


def _bent_sheet_hole():
    """A round hole across the fold of a sheet bent by 90 degrees (a crease through the hole)."""
    V, F = grid(25, 25)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0.0)], 0.3)
    up = V[:, 1] > 0.5
    V = np.c_[V[:, 0], np.where(up, 0.5, V[:, 1]), np.where(up, V[:, 1] - 0.5, 0.0)]
    return hole_context(V, F, min(boundary_loops(F), key=len), rings=cu.RINGS)


def test_smoothest_is_the_whole_fill_of_the_domain_whose_patch_bends_less():
    ctx = _bent_sheet_hole()
    chosen = cu.fill(ctx, domain="smoothest")
    own = {domain: cu.fill(ctx, domain=domain) for domain in DOMAINS}
    bends = chosen.info["border_bends"]
    for domain, patch in own.items():
        assert bends[domain] == border_bend(ctx, patch.vertices, patch.faces)
    winner = min(DOMAINS, key=bends.get)
    assert chosen.info["domain"] == winner
    assert np.array_equal(chosen.vertices, own[winner].vertices) and np.array_equal(chosen.faces, own[winner].faces)
    assert examples.is_disc_patch(chosen, ctx)


@pytest.mark.parametrize("name", ["creased_box", "bevelled_box", "cylinder_rims", "union"])
def test_smoothest_patches_of_cad_like_holes_are_no_farther_than_either_domains(name):
    """Coarse versions of the benchmark's creased cases, every hole crossed by a crease or rim: the kept
    patches' new vertices are as close to the removed surface as the better domain's, or closer."""
    from meshlab_holefill.array_api import fill_holes
    from meshlab_holefill.evaluation.creased import creased_case
    from meshlab_holefill.evaluation.metrics import closest_faces

    case = prepare_case(creased_case(name, 0.08))
    truths = [h.ground_truth for h in case.holes]

    def distance(domain):
        V, F, result = fill_holes(case.V0, case.F0, "curve_unfolding", domain=domain, workers=1)
        assert result["closed_holes"] == len(case.holes)
        new = V[len(case.V0):]
        return np.min([closest_faces(new, gV, gF)[0] for gV, gF in truths], axis=0).mean()

    d = {domain: distance(domain) for domain in ("unfolding", "development", "smoothest")}
    assert d["smoothest"] <= min(d["unfolding"], d["development"]) + 1e-12


def test_smoothest_keeps_the_unfolding_where_it_continues_a_curved_surface_better():
    # A large hole of a sphere: the development of a long loop on a curved surface drifts.
    V, F, _ = sphere_with_holes(subdiv=4, centers=((0, 0, 1),), radius=0.8)
    ctx = hole_context(V, F, boundary_loops(F)[0], rings=cu.RINGS)
    chosen = cu.fill(ctx, domain="smoothest")
    bends = chosen.info["border_bends"]
    assert chosen.info["domain"] == "unfolding" and bends["unfolding"] < bends["development"]
    unfolded = cu.fill(ctx, domain="unfolding")
    assert np.array_equal(chosen.vertices, unfolded.vertices) and np.array_equal(chosen.faces, unfolded.faces)
    # and it is the closer patch to the sphere
    developed = cu.fill(ctx, domain="development")
    off = {name: np.abs(np.linalg.norm(p.vertices, axis=1) - 1).mean() for name, p in
           (("unfolding", unfolded), ("development", developed))}
    assert off["unfolding"] < off["development"]


def _sphere_without(z_below):
    """pymeshlab's unit sphere (subdiv 3) keeping only the faces whose centroids lie below z = ``z_below``."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    m = ms.current_mesh()
    V, F = np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)
    F = F[V[F].mean(axis=1)[:, 2] < z_below]
    return hole_context(V, F, boundary_loops(F)[0], rings=cu.RINGS)


def test_the_development_competes_only_for_a_loop_round_less_than_a_full_turn_of_curvature():
    from meshlab_holefill.algorithms.brunton2009.domain_choice import development_is_candidate
    from meshlab_holefill.geometry.development import boundary_gap_angles, enclosed_curvature

    m = 12
    for K, competes in ((2 * np.pi - 0.05, True), (2 * np.pi + 0.05, False), (-2 * np.pi - 0.05, False), (0.0, True)):
        gaps = np.full(m, ((m - 2) * np.pi + K) / m)
        assert enclosed_curvature(gaps) == pytest.approx(K) and development_is_candidate(gaps) == competes
    # More than a hemisphere removed (K = 2 pi (1 + 0.3) = 8.2): the unfolding alone, filled once.
    ctx = _sphere_without(-0.3)
    assert enclosed_curvature(boundary_gap_angles(ctx.vertices, ctx.faces, ctx.size)) > 2 * np.pi
    chosen = cu.fill(ctx, domain="smoothest")
    unfolded = cu.fill(ctx, domain="unfolding")
    assert chosen.info["domain"] == "unfolding" and "border_bends" not in chosen.info
    assert np.array_equal(chosen.vertices, unfolded.vertices) and np.array_equal(chosen.faces, unfolded.faces)
    # Less than a hemisphere (K = 4.4): both domains compete.
    assert "border_bends" in cu.fill(_sphere_without(0.3), domain="smoothest").info


def _flat_fan(ctx, height=0.0, crossing=0):
    k = ctx.size
    centre = ctx.points.mean(axis=0, keepdims=True) + [0, 0, height]
    return Patch(vertices=centre, faces=np.array([[k, i, (i + 1) % k] for i in range(k)]),
                 info={"crossing_faces": crossing})


def test_smoothest_prefers_a_patch_that_crosses_nothing_and_survives_one_failed_domain():
    V, F = grid(9, 9)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0.0)], 0.25)
    ctx = hole_context(V, F, min(boundary_loops(F), key=len), rings=2)
    flat, lifted = _flat_fan(ctx), _flat_fan(ctx, height=0.3)
    assert smoothest_patch(ctx, {"unfolding": lifted, "development": flat}.get).info["domain"] == "development"
    flat_crossing = _flat_fan(ctx, crossing=2)
    assert smoothest_patch(ctx, {"unfolding": lifted, "development": flat_crossing}.get).info["domain"] == "unfolding"

    def development_fails(domain):
        if domain == "development":
            raise HoleFillError("no domain")
        return lifted

    kept = smoothest_patch(ctx, development_fails)
    assert kept.info["domain"] == "unfolding" and kept.info["border_bends"]["development"] is None

    def both_fail(domain):
        raise HoleFillError(f"{domain} failed")

    with pytest.raises(HoleFillError, match="unfolding failed"):
        smoothest_patch(ctx, both_fail)


def large_hole(name, seed, hole):
    """(V, F, HoleContext) of one hole of ``scripts/large_holes.py``: the sample Loop-subdivided twice, that hole cut."""
    from meshlab_holefill.core.holes import boundary_loops, hole_context
    from meshlab_holefill.evaluation.cut_holes import cut_holes

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample(name))
    ms.meshing_surface_subdivision_loop(iterations=2, threshold=pymeshlab.PercentageValue(0))
    V, F = mesh_arrays(ms)
    _, holes = cut_holes(V, F, sizes=["irregular", "irregular", "large"], seed=seed, strict=False)
    removed = np.zeros(len(F), bool)
    removed[holes[hole].face_indices] = True
    F = F[~removed]
    return V, F, hole_context(V, F, max(boundary_loops(F), key=len), rings=cu.RINGS)


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


def test_where_the_unfolding_is_the_development_the_smoothest_domain_fills_the_hole_once(monkeypatch):
    """A 154-edge hole of bone.ply Loop-subdivided twice (``scripts/large_holes.py``, seed 1): the annealing
    gives up and falls back to the development, so both domains are one; the second is not filled again."""
    _, _, ctx = large_hole("bone.ply", seed=1, hole=2)
    unfolding, development = cu.fill(ctx, domain="unfolding"), cu.fill(ctx, domain="development")
    assert unfolding.info["unfolding"] == "development"  # the annealing's fallback
    assert np.array_equal(unfolding.vertices, development.vertices)
    calls = []
    embed = cu.triangulate_and_embed
    monkeypatch.setattr(cu, "triangulate_and_embed", lambda *a, **kw: calls.append(1) or embed(*a, **kw))
    patch = cu.fill(ctx)
    once = len(calls)
    calls.clear()
    cu.fill(ctx, domain="unfolding")
    assert once == len(calls) > 0
    assert np.array_equal(patch.vertices, unfolding.vertices) and np.array_equal(patch.faces, unfolding.faces)
    assert patch.info["domain"] == "unfolding" and patch.info["sa_steps"] == unfolding.info["sa_steps"]


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
