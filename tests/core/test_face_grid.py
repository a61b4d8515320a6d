"""The face grid answers a box query with exactly the faces the one-pass scan finds."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from meshlab_holefill.core.crossings import face_boxes_near
from meshlab_holefill.core.face_grid import face_grid


def _mesh(rng, kind, n=300, m=500):
    if kind == "flat":  # a scan-like sheet: every face in z = 0
        V = np.column_stack([rng.random((n, 2)), np.zeros(n)])
    elif kind == "far":  # georeferenced coordinates
        V = rng.random((n, 3)) + 1e6
    else:
        V = rng.random((n, 3))
    F = rng.integers(0, n, (m, 3))
    if kind == "slivers":  # long faces across many cells, and points
        F[: m // 10, 1] = F[: m // 10, 0]
        F[: m // 10, 2] = F[: m // 10, 0]
    return V, F


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), kind=st.sampled_from(["cube", "flat", "far", "slivers"]),
       dtype=st.sampled_from([np.int32, np.int64]), faces_per_cell=st.sampled_from([0.01, 1.0, 8.0, 1e4]))
def test_near_equals_the_scan_for_one_box(seed, kind, dtype, faces_per_cell):
    rng = np.random.default_rng(seed)
    V, F = _mesh(rng, kind)
    F = F.astype(dtype)
    grid = face_grid(V, F, faces_per_cell=faces_per_cell)
    lo_all, hi_all = V.min(axis=0), V.max(axis=0)
    for _ in range(5):
        a = lo_all + rng.uniform(-0.2, 1.1, 3) * (hi_all - lo_all)
        b = a + rng.uniform(0.0, 0.5, 3) * (hi_all - lo_all)
        box = np.stack([a, b])
        expected = face_boxes_near(V, F, box[None])
        got = grid.near(box)
        assert got[0].tolist() == expected[0].tolist()
        np.testing.assert_array_equal(got[1], expected[1])
        np.testing.assert_array_equal(got[2], expected[2])


def test_a_face_on_a_cell_edge_is_found_from_either_side():
    # The corners of a face exactly on cell boundaries: the closed-box test must see it.
    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [2.0, 2.0, 0.0], [3.0, 2.0, 0.0],
                  [2.0, 3.0, 0.0]])
    F = np.array([[0, 1, 2], [3, 4, 5]])
    grid = face_grid(V, F, faces_per_cell=1.0)
    assert grid.near(np.array([[1.0, 0.0, 0.0], [1.5, 0.5, 0.0]]))[0].tolist() == [0]
    assert grid.near(np.array([[1.5, 1.5, -1.0], [2.0, 2.0, 1.0]]))[0].tolist() == [1]
    assert grid.near(np.array([[1.1, 1.1, 0.0], [1.9, 1.9, 0.0]]))[0].tolist() == []


def test_the_grid_has_no_more_cells_than_faces():
    rng = np.random.default_rng(0)
    V = rng.random((1000, 3)) * [1000.0, 1.0, 1.0]  # long and thin, tiny faces
    F = np.arange(999)[:, None] + np.array([0, 1, 1])
    grid = face_grid(V, F)
    assert np.prod(grid.dims) <= len(F)
    assert len(grid.order) + len(grid.large) == len(F)


@pytest.mark.parametrize("shape", [(0, 3)])
def test_an_empty_mesh_gives_an_empty_answer(shape):
    V = np.zeros((3, 3))
    F = np.zeros(shape, np.int64)
    assert face_grid(V, F).near(np.array([[0.0] * 3, [1.0] * 3]))[0].tolist() == []


def test_workers_with_many_holes_check_their_patches_in_the_grid_and_fill_as_one_process(monkeypatch):
    from meshlab_holefill import fill_holes
    from meshlab_holefill.core import pipeline

    from conftest import sphere_with_holes

    centres = np.random.default_rng(5).normal(size=(40, 3))
    centres /= np.linalg.norm(centres, axis=1)[:, None]
    keep = [0]  # centres far enough apart that the holes stay separate
    for i in range(1, len(centres)):
        if np.min(np.linalg.norm(centres[keep] - centres[i], axis=1)) > 0.45:
            keep.append(i)
    V, F, _ = sphere_with_holes(subdiv=4, centers=centres[keep], radius=0.12)
    built = []
    real = pipeline.face_grid
    monkeypatch.setattr(pipeline, "face_grid", lambda V, F: built.append(len(F)) or real(V, F))
    V1, F1, one = fill_holes(V, F, "min_angle_bilateral", workers=1)
    assert not built
    V2, F2, two = fill_holes(V, F, "min_angle_bilateral", workers=2)
    holes = len(two["holes"])
    if pipeline.worker_count(2, holes) == 2:  # a machine with two cores or more
        assert holes >= pipeline.GRID_SCANS * 2 and built == [len(F)]
    assert one["closed_holes"] == holes and two["closed_holes"] == holes
    assert V1.tobytes() == V2.tobytes() and F1.tobytes() == F2.tobytes()
