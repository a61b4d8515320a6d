"""Curve unfolding Sec. 3.2 and 3.3: the planar domain (CDT, Chew refinement, scale) and its area guard."""

import numpy as np
import pymeshlab
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill import HoleFillError
from meshlab_holefill.algorithms.brunton2009 import planar_domains
from meshlab_holefill.algorithms.brunton2009 import unfolded_triangulation as tri
from meshlab_holefill.algorithms.brunton2009.linear_motion import project_to_best_plane
from meshlab_holefill.geometry.development import boundary_gap_angles, developed_area, develop_loop
from meshlab_holefill.geometry.quality import corner_angles
from meshlab_holefill.geometry.triangulate import polygon_signed_area
from meshlab_holefill.core.holes import boundary_loops, hole_context

from conftest import grid, mesh_arrays, meshset_from_arrays, sample


def edge_set(F):
    return {tuple(e) for f in np.asarray(F).tolist() for e in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))}


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
