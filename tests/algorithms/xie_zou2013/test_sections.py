"""HPDE Sec. 4.2-4.4: base points, segmentation (Eq. 8), base point pairing (Eq. 9-10) and section planes (Eq. 11)."""
import dataclasses
import itertools

import numpy as np
import pytest

from meshlab_holefill.algorithms.xie_zou2013 import sections as hpde_sections

import hpde_cases
from hpde_cases import context, cut, grid_plane

cube_edge_hole = hpde_cases.cube_edge_hole  # the shared module-scoped fixtures
sphere_hole = hpde_cases.sphere_hole


# ----------------------------------------------------------------- step 2: Sec. 4.2

def test_base_points_count_and_equal_arc_length(sphere_hole):
    _, _, _, ctx = sphere_hole
    e = hpde_sections.ring_edge_length(ctx)
    base = hpde_sections.base_points(ctx.points, e)
    perimeter = np.linalg.norm(np.roll(ctx.points, -1, axis=0) - ctx.points, axis=1).sum()
    assert len(base) == int(np.floor(perimeter / (0.8 * e)))
    # Each base point lies on its loop edge, at arc length j * BudLen / n.
    P, k = ctx.points, ctx.size
    on_edge = P[base.edge] + base.t[:, None] * (P[(base.edge + 1) % k] - P[base.edge])
    assert np.allclose(on_edge, base.points)
    seg = np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)
    arc = np.concatenate([[0], np.cumsum(seg)])[base.edge] + base.t * seg[base.edge]
    assert np.allclose(np.diff(arc), perimeter / len(base))


def test_ring_edge_length_is_mean_of_adjacent_triangles():
    V, F = grid_plane(10)
    F_cut, _ = cut(V, F, (0.5, 0.5, 0), 0.2)
    ctx = context(V, F_cut)
    assert hpde_sections.ring_edge_length(ctx) == pytest.approx(np.mean([0.1] * 2 + [0.1 * np.sqrt(2)]), rel=0.15)


def test_pca_segmentation_matches_brute_force_eq8():
    rng = np.random.default_rng(3)
    BP = rng.normal(size=(20, 3)) * [3, 2, 0.5]
    i0, j0, lams, _ = hpde_sections.pca_segmentation(BP, min_size=4)
    best, arg = np.inf, None
    for i, j in itertools.combinations(range(20), 2):
        ps2 = BP[i:j]
        ps1 = np.concatenate([BP[j:], BP[:i]])
        if len(ps1) < 4 or len(ps2) < 4:
            continue
        lam = max(np.linalg.eigvalsh(np.cov(ps1.T, bias=True))[0], np.linalg.eigvalsh(np.cov(ps2.T, bias=True))[0])
        if lam < best:
            best, arg = lam, (i, j)
    assert (i0, j0) == arg
    assert max(lams) == pytest.approx(best)


def _all_splits_argmin(C1, C2):
    """The Eq. 8 minimum through LAPACK on every split (what the screened search must return)."""
    lam1 = np.maximum(np.linalg.eigh(C1)[0][:, 0], 0.0)
    lam2 = np.maximum(np.linalg.eigh(C2)[0][:, 0], 0.0)
    return int(np.argmin(np.maximum(lam1, lam2)))


@pytest.mark.parametrize("shape", ["noisy", "planar", "bent", "circle"])
def test_screened_eq8_split_equals_lapack_on_every_split(shape):
    rng = np.random.default_rng(7)
    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    ring = np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], axis=1)
    if shape == "noisy":
        ring += rng.normal(scale=0.05, size=ring.shape)
    elif shape == "bent":
        ring[:, 2] = np.abs(ring[:, 0])  # two planes meeting along the y-axis
    elif shape == "circle":
        ring = ring[:, [0, 2, 1]] * 1e3 + 5e3  # far from the origin, another scale
    n = len(ring)
    X = ring - ring.mean(axis=0)
    S1 = np.concatenate([np.zeros((1, 3)), np.cumsum(X, axis=0)])
    S2 = np.concatenate([np.zeros((1, 3, 3)), np.cumsum(X[:, :, None] * X[:, None, :], axis=0)])
    i, j = np.triu_indices(n, k=1)
    c2 = (j - i).astype(np.float64)
    keep = (c2 >= 10) & (n - c2 >= 10)
    i, j, c2 = i[keep], j[keep], c2[keep]
    C2 = hpde_sections._moment_covariances(c2, S1[j] - S1[i], S2[j] - S2[i])
    C1 = hpde_sections._moment_covariances(n - c2, S1[n] - (S1[j] - S1[i]), S2[n] - (S2[j] - S2[i]))
    assert hpde_sections._eq8_best_split(C1, C2) == _all_splits_argmin(C1, C2)
    est = hpde_sections.smallest_eigenvalue_estimate(C1)
    norm = np.abs(np.linalg.eigvalsh(C1)).max(axis=1)
    assert np.all(np.abs(est - np.linalg.eigvalsh(C1)[:, 0]) <= 1e-7 * norm)


def test_cube_edge_hole_is_segmented_along_the_characteristic_line(cube_edge_hole):
    _, _, _, ctx = cube_edge_hole
    e = hpde_sections.ring_edge_length(ctx)
    base = hpde_sections.base_points(ctx.points, e)
    normals = hpde_sections.base_point_normals(ctx.loop_normals, base)
    seg = hpde_sections.segment_boundary(base, normals, np.pi / 2)
    assert seg["segmented"]
    assert np.degrees(seg["dihedral"]) == pytest.approx(90.0, abs=1.0)
    i0, j0 = seg["split"]
    # Each run lies on one face of the cube (y = 0 or z = 0); the split points on the edge.
    runs = [np.r_[np.arange(j0, len(base)), np.arange(0, i0)], np.arange(i0, j0)]
    faces = []
    for run in runs:
        inner = base.points[run[1:-1]]
        on_y, on_z = np.all(np.abs(inner[:, 1]) < 1e-9), np.all(np.abs(inner[:, 2]) < 1e-9)
        assert on_y != on_z
        faces.append(on_y)
    assert faces[0] != faces[1]


@pytest.mark.parametrize("tilt_deg, segmented", [(0.02, True), (-0.5, True), (0.5, False)])
def test_cube_edge_tilted_by_the_tessellation_is_still_segmented(cube_edge_hole, tilt_deg, segmented):
    # Fitted planes of a remeshed right-angled edge meet at 90.007-90.021 degrees: within the slack of
    # A_c they are the cube's edge; a face tilted by half a degree opens the edge beyond it.
    _, _, _, ctx = cube_edge_hole
    base = hpde_sections.base_points(ctx.points, hpde_sections.ring_edge_length(ctx))
    normals = hpde_sections.base_point_normals(ctx.loop_normals, base)
    on_y0 = np.abs(base.points[:, 1]) < 1e-9  # face y = 0; the other run lies on z = 0
    c, s = np.cos(np.radians(tilt_deg)), np.sin(np.radians(tilt_deg))
    tilted = base.points.copy()
    # Rotate face y = 0 about the edge (the x axis) away from face z = 0: the dihedral grows by the tilt.
    y, z = tilted[on_y0, 1], tilted[on_y0, 2]
    tilted[on_y0, 1], tilted[on_y0, 2] = c * y - s * z, s * y + c * z
    seg = hpde_sections.segment_boundary(dataclasses.replace(base, points=tilted), normals, np.pi / 2)
    assert np.degrees(seg["dihedral"]) == pytest.approx(90.0 + tilt_deg, abs=1e-6)
    assert seg["segmented"] == segmented


def test_planar_hole_is_not_segmented():
    V, F = grid_plane(24)
    F_cut, _ = cut(V, F, (0.5, 0.5, 0), 0.3)
    ctx = context(V, F_cut)
    base = hpde_sections.base_points(ctx.points, hpde_sections.ring_edge_length(ctx))
    seg = hpde_sections.segment_boundary(base, hpde_sections.base_point_normals(ctx.loop_normals, base), np.pi / 2)
    assert not seg["segmented"] and np.degrees(seg["dihedral"]) > 170


# ----------------------------------------------------------------- step 3: Sec. 4.3

def test_best_start_minimises_eq10_by_brute_force():
    rng = np.random.default_rng(0)
    angle = np.sort(rng.uniform(0, 2 * np.pi, 31))
    BP = np.stack([3 * np.cos(angle), np.sin(angle), 0 * angle], axis=1)
    sp, dist = hpde_sections.best_start(BP)
    n = len(BP)
    brute = [sum(np.linalg.norm(BP[(s + i) % n] - BP[(s - 1 - i) % n]) for i in range(n // 2)) for s in range(n)]
    assert np.allclose(dist, brute)
    assert sp == int(np.argmin(brute))


def test_ellipse_pairs_cross_the_short_way_and_respect_ic():
    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    BP = np.stack([3 * np.cos(t), np.sin(t), 0 * t], axis=1)
    normals = np.tile([0, 0, 1.0], (60, 1))
    tangent, inward = hpde_sections.boundary_frames(BP, normals)
    I_c = np.pi / 15
    pairs, info = hpde_sections.correspondences(BP, tangent, inward, None, I_c)
    assert len(pairs) > 15
    chords = BP[pairs[:, 1]] - BP[pairs[:, 0]]
    # Chords across the short axis (y), never along the long one.
    assert np.all(np.abs(chords[:, 1]) > np.abs(chords[:, 0]))
    for a, b in pairs:
        line = (BP[b] - BP[a]) / np.linalg.norm(BP[b] - BP[a])
        ang = hpde_sections.intersection_angle(np.stack([line, -line]), tangent[[a, b]], inward[[a, b]])
        assert np.all(ang >= I_c) and np.all(ang <= np.pi - I_c)
    # Near the ends of the axis the chords are nearly tangent: those base points are skipped.
    assert info["skipped"] > 0


def test_forced_pairing_eq9_keeps_the_index_sum(cube_edge_hole):
    _, _, _, ctx = cube_edge_hole
    base = hpde_sections.base_points(ctx.points, hpde_sections.ring_edge_length(ctx))
    normals = hpde_sections.base_point_normals(ctx.loop_normals, base)
    i0, j0 = hpde_sections.segment_boundary(base, normals, np.pi / 2)["split"]
    tangent, inward = hpde_sections.boundary_frames(base.points, normals)
    # I_c = -pi switches the modification off: the pure Eq. 9 pairing.
    pairs, _ = hpde_sections.correspondences(base.points, tangent, inward, (i0, j0), I_c=-np.pi)
    n = len(base)
    self_paired = 1 if n % 2 else (2 if (i0 + j0) % 2 == 0 else 0)  # a with 2 a = i0 + j0 (mod n)
    assert len(pairs) == (n - self_paired) // 2
    assert np.all((pairs.sum(axis=1) - (i0 + j0)) % n == 0)
    assert any(set(p) == {i0, j0} for p in pairs.tolist())


# ----------------------------------------------------------------- step 4: Sec. 4.4

def test_section_planes_contain_the_chord_and_cut_the_ring_triangles(sphere_hole):
    _, _, _, ctx = sphere_hole
    e = hpde_sections.ring_edge_length(ctx)
    base = hpde_sections.base_points(ctx.points, e)
    normals = hpde_sections.base_point_normals(ctx.loop_normals, base)
    tangent, inward = hpde_sections.boundary_frames(base.points, normals)
    pairs, _ = hpde_sections.correspondences(base.points, tangent, inward)
    a, b = pairs[:, 0], pairs[:, 1]
    Nv, _ = hpde_sections.section_normals(base.points, pairs, normals[a] + normals[b])
    lv = base.points[a] - base.points[b]
    assert np.allclose(np.einsum("ij,ij->i", Nv, lv), 0, atol=1e-9)
    W = hpde_sections.border_third_vertices(ctx)
    AP, TV = hpde_sections.ring_intersections(ctx.points, base.edge[a], base.points[a], Nv, W[base.edge[a]])
    # AP lies on the section plane and on an edge of the ring triangle of the base point.
    assert np.allclose(np.einsum("ij,ij->i", AP - base.points[a], Nv), 0, atol=1e-9)
    k = ctx.size
    Q0, Q1, Wa = ctx.points[base.edge[a]], ctx.points[(base.edge[a] + 1) % k], W[base.edge[a]]
    d0 = np.linalg.norm(np.cross(AP - Q0, Wa - Q0), axis=1)
    d1 = np.linalg.norm(np.cross(AP - Q1, Wa - Q1), axis=1)
    assert np.all(np.minimum(d0, d1) < 1e-9)
    # TV points from the ring into the hole: towards the chord's other end.
    assert np.mean(np.einsum("ij,ij->i", TV, base.points[b] - base.points[a]) > 0) > 0.8


def test_section_normal_eq11_for_parallel_chords():
    # Chords across a rectangle in z = 0: Nv is along x, the direction the chain advances.
    x = np.linspace(0, 4, 9)
    BP = np.concatenate([np.stack([x, 0 * x, 0 * x], 1), np.stack([x[::-1], 0 * x + 1, 0 * x], 1)])
    pairs = np.stack([np.arange(9), 17 - np.arange(9)], axis=1)
    Nv, fallback = hpde_sections.section_normals(BP, pairs, np.tile([0, 0, 1.0], (9, 1)))
    assert not fallback.any()
    assert np.allclose(np.abs(Nv[:, 0]), 1.0)


# ----------------------------------------------------------------- direct tests of building blocks

def _circle_frames(n):
    t = 2 * np.pi * np.arange(n) / n
    BP = np.stack([np.cos(t), np.sin(t), np.zeros(n)], axis=1)  # counter-clockwise, hole inside
    tangent, inward = hpde_sections.boundary_frames(BP, np.tile([0.0, 0.0, 1.0], (n, 1)))
    return BP, tangent, inward


def test_pair_chain_on_a_circle_skips_only_the_grazing_end_pairs():
    # On a circle the chord from a to b meets the boundary at half the arc a -> b (tangent-chord
    # angle): with n = 16 the adjacent pairs at both ends of the axis graze at 11.25 or 168.75
    # degrees, outside [12, 168] (I_c = pi / 15), so both ends are skipped; the rest pair up.
    BP, tangent, inward = _circle_frames(16)
    pairs, skipped = hpde_sections.pair_chain(BP, tangent, inward, 0, 15)
    assert pairs.tolist() == [[i, 15 - i] for i in range(1, 7)] and skipped == 4
    # Indices wrap around the loop.
    pairs, skipped = hpde_sections.pair_chain(BP, tangent, inward, 5, 4)
    assert pairs.tolist() == [[6, 3], [7, 2], [8, 1], [9, 0], [10, 15], [11, 14]] and skipped == 4


@pytest.mark.parametrize("flipped, expected", [
    (3, [[1, 14], [2, 13], [4, 12], [5, 11], [6, 10], [7, 9]]),    # a's pointer advances alone
    (12, [[1, 14], [2, 13], [3, 11], [4, 10], [5, 9], [6, 8]]),    # b's pointer advances alone
])
def test_pair_chain_skips_one_failing_end_and_shifts_the_following_pairs(flipped, expected):
    # Turning one base point's into-hole direction outwards makes every line from it fail I_c at
    # that end only (Fig. 2): that point is skipped and the pairing after it shifts by one.
    BP, tangent, inward = _circle_frames(16)
    inward[flipped] *= -1
    pairs, skipped = hpde_sections.pair_chain(BP, tangent, inward, 0, 15)
    assert pairs.tolist() == expected and skipped == 3


def test_base_point_pairs_are_found_once_per_pairing(cube_edge_hole):
    _, _, _, ctx = cube_edge_hole
    base = hpde_sections.base_points(ctx.points, hpde_sections.ring_edge_length(ctx))
    normals = hpde_sections.base_point_normals(ctx.loop_normals, base)
    seg = hpde_sections.segment_boundary(base, normals, np.pi / 2)
    for split in (seg["split"], None):
        got = hpde_sections.base_point_pairs(base, normals, split, np.radians(12))
        tangent, inward = hpde_sections.boundary_frames(base.points, normals)
        pairs, info = hpde_sections.correspondences(base.points, tangent, inward, split, np.radians(12))
        assert np.array_equal(got[2], pairs) and got[3] == info and np.array_equal(got[0], tangent)
        assert hpde_sections.base_point_pairs(base, normals, split, np.radians(12))[2] is got[2]
    assert hpde_sections.base_point_pairs(base, normals.copy(), None, np.radians(12))[2] is not got[2]
