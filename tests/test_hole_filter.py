"""The shared pipeline's self-intersection check (hole_filter.face_boxes_near / patch_intersections)."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import meshlab_holefill  # noqa: F401  (registers the filters)
from meshlab_holefill.hole_filter import face_boxes_near
from meshlab_holefill.holes import boundary_loops

from conftest import cut_disks, grid, mesh_arrays, meshset_from_arrays

FILTERS = ["meshing_close_holes_min_angle_bilateral", "meshing_close_holes_curve_unfolding",
           "meshing_close_holes_lssvm_poisson", "meshing_close_holes_differential_evolution"]


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), n_boxes=st.integers(1, 4))
def test_face_boxes_near_matches_brute_force(seed, n_boxes):
    rng = np.random.default_rng(seed)
    V = rng.uniform(-1, 1, (60, 3))
    F = rng.integers(0, 60, (120, 3))
    centre = rng.uniform(-1, 1, (n_boxes, 3))
    half = rng.uniform(0.01, 0.5, (n_boxes, 3))
    boxes = np.stack([centre - half, centre + half], axis=1)
    near, lo, hi = face_boxes_near(V, F, boxes)
    corners = V[F]
    flo, fhi = corners.min(axis=1), corners.max(axis=1)
    union_lo, union_hi = boxes[:, 0].min(axis=0), boxes[:, 1].max(axis=0)
    expected = np.flatnonzero(np.all(fhi >= union_lo, axis=1) & np.all(flo <= union_hi, axis=1))
    np.testing.assert_array_equal(near, expected)
    np.testing.assert_array_equal(lo, flo[near])
    np.testing.assert_array_equal(hi, fhi[near])
    # every face overlapping any single box is among the candidates
    for b in boxes:
        each = np.flatnonzero(np.all(fhi >= b[0], axis=1) & np.all(flo <= b[1], axis=1))
        assert np.isin(each, near).all()


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


def test_island_outline_is_reported_as_not_a_hole():
    """A lone triangle's border is a 3-edge loop; capping it would duplicate the triangle."""
    V, F = grid(8, 8)
    k = len(V)
    V = np.concatenate([V, [[3.0, 0, 0], [4.0, 0, 0], [3.0, 1.0, 0]]])
    F = np.concatenate([F, [[k, k + 1, k + 2]]])
    ms = meshset_from_arrays(V, F)
    res = ms.meshing_close_holes_min_angle_bilateral(maxholesize=10)
    (entry,) = [h for h in res["holes"] if h["boundary_edges"] == 3]
    assert entry["status"] == "failed"
    assert "intersect" in entry["reason"] and "island" in entry["reason"]
    V2, F2 = mesh_arrays(ms)
    assert len(F2) == len(F)
