"""Curve unfolding: the planar polygon's edge lengths (loop lengths) and the development of the loop."""

import numpy as np
import pytest
import scipy.optimize

from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
from meshlab_holefill.algorithms.brunton2009.unfolding import unfold_loop
from meshlab_holefill.geometry.development import MIN_CLOSURE_RATIO, boundary_gap_angles, close_lengths, develop_loop
from meshlab_holefill.geometry.triangulate import polygon_signed_area
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.core import examples

from conftest import cut_disks, grid


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


def test_development_of_a_planar_hole_is_the_hole_itself():
    V, F = grid(14, 14)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0)], 0.3)
    loop = [lp for lp in boundary_loops(F) if len(lp) < 52][0]
    ctx = hole_context(V, F, loop, rings=2)
    Q = develop_loop(ctx.points, boundary_gap_angles(ctx.vertices, ctx.faces, ctx.size))
    D2 = np.linalg.norm(Q[:, None] - Q[None], axis=2)
    D3 = np.linalg.norm(ctx.points[:, None, :2] - ctx.points[None, :, :2], axis=2)
    assert np.abs(D2 - D3).max() < 1e-9  # congruent: same lengths and angles


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
