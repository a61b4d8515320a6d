"""evaluation.virtual_scan: what a scanner sees from one direction, and the holes it leaves with their ground truth."""
import numpy as np
import pytest

from meshlab_holefill.array_api import fill_holes
from meshlab_holefill.evaluation.analytic import analytic_mesh
from meshlab_holefill.evaluation.mesh_cases import prepare_case
from meshlab_holefill.evaluation.metrics import mesh_checks
from meshlab_holefill.evaluation.virtual_scan import GRAZING_DEGREES, virtual_scan_case, visible_faces
from meshlab_holefill.geometry.quality import cross_rows


def _facing(V, F, direction):
    N = cross_rows(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N /= np.linalg.norm(N, axis=1)[:, None]
    return -(N @ (direction / np.linalg.norm(direction))) > np.cos(np.radians(GRAZING_DEGREES))


def _edge(V, F):
    return float(np.linalg.norm(V[F[:, 1]] - V[F[:, 0]], axis=1).mean())


@pytest.mark.parametrize("direction", [(0.0, 0.0, -1.0), (1.0, 2.0, 0.5), (-0.3, 0.1, 1.0)])
def test_a_convex_surface_is_seen_wherever_it_faces_the_scanner(direction):
    V, F = analytic_mesh("sphere")
    direction = np.array(direction)
    np.testing.assert_array_equal(visible_faces(V, F, direction, 0.7 * _edge(V, F)), _facing(V, F, direction))


def test_a_ball_in_front_hides_the_faces_of_the_one_behind_in_its_shadow_only():
    V, F = analytic_mesh("sphere")  # unit sphere
    front = 0.5 * V + [0.3, 0.0, 2.0]  # a ball of radius 0.5 between the scanner (at +z) and the sphere
    both_V, both_F = np.vstack([V, front]), np.vstack([F, F + len(V)])
    seen = visible_faces(both_V, both_F, np.array([0.0, 0.0, -1.0]), 0.7 * _edge(V, F))
    centroid = V[F].mean(axis=1)
    off_axis = np.linalg.norm(centroid[:, :2] - [0.3, 0.0], axis=1)  # distance from the front ball's axis
    facing = _facing(V, F, np.array([0.0, 0.0, -1.0]))
    assert not seen[:len(F)][facing & (off_axis < 0.45)].any()  # in the shadow
    assert seen[:len(F)][facing & (off_axis > 0.55)].all()  # beside it
    assert seen[len(F):].sum() == _facing(front, F, np.array([0.0, 0.0, -1.0])).sum()  # the front ball unhidden


def _ball_before_sphere():
    """The unit sphere with a ball of radius 0.4 before it, seen by a scanner at +z."""
    V, F = analytic_mesh("sphere")
    return np.vstack([V, 0.4 * V + [0.2, 0.1, 2.0]]), np.vstack([F, F + len(V)]), len(F)


def test_the_shadow_a_ball_casts_on_a_sphere_is_a_hole_whose_ground_truth_is_the_hidden_surface():
    V, F, sphere_faces = _ball_before_sphere()
    case = virtual_scan_case("ball and sphere", V, F, direction=(0.0, 0.0, -1.0))
    assert 0 < len(case.F) < len(F) and np.unique(case.F).size == len(case.V)  # no unreferenced vertex
    prepared = prepare_case(case)
    (hole,) = prepared.holes
    truth_V, truth_F = hole.ground_truth
    centroid = truth_V[truth_F].mean(axis=1)
    # The shadow: on the sphere's near side, within the ball's radius of its axis.
    assert np.all(centroid[:, 2] > 0.0)
    assert np.all(np.linalg.norm(centroid[:, :2] - [0.2, 0.1], axis=1) < 0.45)
    assert hole.boundary_edges > 30


def test_scanner_noise_moves_the_scan_and_keeps_it_reproducible():
    V, F, _ = _ball_before_sphere()
    one = virtual_scan_case("s", V, F, (0.0, 0.0, -1.0), noise=0.15, seed=4)
    again = virtual_scan_case("s", V, F, (0.0, 0.0, -1.0), noise=0.15, seed=4)
    np.testing.assert_array_equal(one.V, again.V)
    np.testing.assert_array_equal(one.F, again.F)
    np.testing.assert_array_equal(one.removed, again.removed)
    clean = virtual_scan_case("s", V, F, (0.0, 0.0, -1.0))
    assert len(one.V) != len(clean.V) or not np.array_equal(one.V, clean.V)


def test_the_shadow_of_a_noisy_scan_closes_without_crossing_the_mesh():
    V, F, _ = _ball_before_sphere()
    prepared = prepare_case(virtual_scan_case("s", V, F, (0.0, 0.0, -1.0), noise=0.15, seed=2))
    V2, F2, result = fill_holes(prepared.V0, prepared.F0, "min_angle_bilateral", workers=1)
    np.testing.assert_array_equal(V2[:len(prepared.V0)], prepared.V0)
    np.testing.assert_array_equal(F2[:len(prepared.F0)], prepared.F0)
    checks = mesh_checks(prepared.V0, prepared.F0, V2, F2)
    assert checks["intersecting_new_faces"] == 0 and checks["nonmanifold_edges"] == 0
    statuses = {h["hole"]: h["status"] for h in result["holes"]}
    assert [statuses[h.index] for h in prepared.holes] == ["closed"] * len(prepared.holes)


@pytest.mark.parametrize("direction, pixel, match", [((0.0, 0.0, 0.0), 0.1, "non-zero 3-vector"),
                                                      ((np.nan, 0.0, 1.0), 0.1, "non-zero 3-vector"),
                                                      ((0.0, 1.0), 0.1, "non-zero 3-vector"),
                                                      ((0.0, 0.0, 1.0), 0.0, "positive length")])
def test_a_bad_direction_or_pixel_is_refused_by_name(direction, pixel, match):
    V, F = analytic_mesh("sphere")
    with pytest.raises(ValueError, match=match):
        visible_faces(V, F, direction, pixel)


def test_a_mesh_without_faces_is_refused_by_name():
    with pytest.raises(ValueError, match="no faces"):
        virtual_scan_case("empty", np.zeros((3, 3)), np.zeros((0, 3), np.int64), (0.0, 0.0, 1.0))
