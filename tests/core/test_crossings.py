"""core.crossings: the candidate faces near patches, found in one pass; folds of the mesh beside a hole."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from meshlab_holefill.core import examples
from meshlab_holefill.core.crossings import face_boxes_near, surroundings_crossing_themselves
from meshlab_holefill.core.holes import hole_context, vertex_face_incidence


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
    meets = np.zeros(len(F), bool)
    for b in boxes:  # the candidates are exactly the faces overlapping one of the boxes
        meets |= np.all(fhi >= b[0], axis=1) & np.all(flo <= b[1], axis=1)
    np.testing.assert_array_equal(near, np.flatnonzero(meets))
    np.testing.assert_array_equal(lo, flo[near])
    np.testing.assert_array_equal(hi, fhi[near])
    # every face overlapping any single box is among the candidates
    for b in boxes:
        each = np.flatnonzero(np.all(fhi >= b[0], axis=1) & np.all(flo <= b[1], axis=1))
        assert np.isin(each, near).all()


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), int32=st.booleans())
def test_faces_near_boxes_are_those_whose_own_box_meets_one_of_them(seed, int32):
    rng = np.random.default_rng(seed)
    V = rng.random((60, 3))
    F = rng.integers(0, 60, (80, 3)).astype(np.int32 if int32 else np.int64)
    lo = rng.random((3, 3)) * 0.7
    boxes = np.stack([lo, lo + rng.random((3, 3)) * 0.3], axis=1)
    near, face_lo, face_hi = face_boxes_near(V, F, boxes)
    corners = V[F]
    box_lo, box_hi = corners.min(axis=1), corners.max(axis=1)
    meets = [any(np.all(box_hi[f] >= b[0]) and np.all(box_lo[f] <= b[1]) for b in boxes) for f in range(len(F))]
    assert near.tolist() == np.flatnonzero(meets).tolist()
    np.testing.assert_array_equal(face_lo, box_lo[near])
    np.testing.assert_array_equal(face_hi, box_hi[near])


def test_the_crossing_kernels_are_loaded_for_the_mesh_face_type_before_any_hole_is_filled(monkeypatch):
    from meshlab_holefill import fill_holes
    from meshlab_holefill.core import pipeline

    from conftest import meshset_from_arrays, sphere_with_holes

    V, F, _ = sphere_with_holes()
    loaded = []
    real = pipeline.load_crossing_kernels
    monkeypatch.setattr(pipeline, "load_crossing_kernels", lambda faces: loaded.append(faces.dtype) or real(faces))
    ms = meshset_from_arrays(V, F)  # pymeshlab hands the pipeline int32 faces
    ms.meshing_close_holes_min_angle_bilateral(workers=2)
    fill_holes(V, F, "min_angle_bilateral", workers=1)  # the array door: int64 faces, this process
    assert loaded == [np.dtype(np.int32), np.dtype(np.int64)]
    fill_holes(V, F, "min_angle_bilateral", selfintersection=False)  # no crossing check: nothing to load
    assert len(loaded) == 2
    from meshlab_holefill.core.crossings import _faces_meeting_boxes

    assert any(sig[1].dtype.name == "int32" and sig[1].layout == "C" for sig in _faces_meeting_boxes.signatures)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_a_patch_is_tested_against_exactly_the_faces_whose_box_meets_its_padded_box(seed):
    from meshlab_holefill.core import crossings

    rng = np.random.default_rng(seed)
    V = rng.random((80, 3))
    F = rng.integers(0, 80, (120, 3))
    loop = np.unique(rng.integers(0, 80, 4))
    points = np.concatenate([V[loop], rng.random((2, 3)) * 0.5 + 0.25])
    faces = rng.integers(0, len(points), (3, 3))
    candidates = face_boxes_near(V, F, np.array([[[-1.0] * 3, [2.0] * 3]]))
    seen = []
    real = crossings.intersecting_pairs
    crossings.intersecting_pairs = lambda X, allF, *args, **kw: seen.append(len(allF)) or real(X, allF, *args, **kw)
    try:
        crossings.patch_intersections(points, faces, V, F, candidates, loop)
    finally:
        crossings.intersecting_pairs = real
    lo, hi = points.min(axis=0), points.max(axis=0)
    pad = 1e-9 * float(np.linalg.norm(hi - lo))
    corners = V[F]
    meets = np.all(corners.max(axis=1) >= lo - pad, axis=1) & np.all(corners.min(axis=1) <= hi + pad, axis=1)
    assert seen == [len(faces) + int(meets.sum())]


def _context_crossings_as_the_whole_query(seed, obstacles):
    """Patches pushed through the surroundings (and obstacles beyond the rings): context_crossings gives the faces
    faces_intersecting finds on the patch and the surroundings joined, the surroundings' bounds built once.
    Returns whether the patch crossed anything."""
    from meshlab_holefill.core import examples
    from meshlab_holefill.core.crossings import context_crossings
    from meshlab_holefill.core.holes import hole_context, vertex_face_incidence
    from meshlab_holefill.geometry.intersections import faces_intersecting
    V, F, loop = examples.bowl_with_hole()
    incidence = vertex_face_incidence(F, len(V))
    near = np.arange(len(F)) if obstacles else None
    ctx = hole_context(V, F, loop, incidence, rings=1, obstacles=near)
    rng = np.random.default_rng(seed)
    k = ctx.size
    inner = ctx.points.mean(axis=0) + rng.normal(0.0, 0.3, (6, 3)) * ctx.mean_edge_length * [4, 4, 8]
    points = np.concatenate([ctx.points, inner])
    faces = np.concatenate([np.c_[np.arange(k), (np.arange(k) + 1) % k, k + np.arange(k) % 6],
                            rng.integers(k, k + 6, (4, 3))])
    S_points, S_faces = ctx.surroundings()
    X = np.concatenate([points, S_points[k:]])
    allF = np.concatenate([faces, np.where(S_faces >= k, S_faces + 6, S_faces)])
    expected = faces_intersecting(X, allF, np.arange(len(faces)), np.arange(len(allF)))
    assert np.array_equal(context_crossings(ctx, points, faces), expected)
    first = ctx.surrounding_bounds
    assert np.array_equal(context_crossings(ctx, points, faces), expected) and ctx.surrounding_bounds is first
    assert first.count == len(S_faces)
    # a loop moved away from the context's own: the faces are bounded again, the answer the same
    moved = points.copy()
    moved[0] += ctx.mean_edge_length
    X[0] = moved[0]
    assert np.array_equal(context_crossings(ctx, moved, faces),
                          faces_intersecting(X, allF, np.arange(len(faces)), np.arange(len(allF))))
    return len(expected) > 0


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), obstacles=st.booleans())
def test_context_crossings_read_the_kept_bounds_and_answer_as_the_whole_query(seed, obstacles):
    _context_crossings_as_the_whole_query(seed, obstacles)


def test_context_crossings_of_patches_that_cross():
    crossed = [_context_crossings_as_the_whole_query(seed, seed % 2 == 0) for seed in range(12)]
    assert sum(crossed) >= 4  # the patches above do cross the surroundings


def _jittered_bowl(seed, far_from_loop=0.0):
    """The example bowl with a hole, its vertices jittered by half an edge (those beyond ``far_from_loop`` of the loop's centre)."""
    V, F, loop = examples.bowl_with_hole(n=21)
    edge = 2.0 / 20
    moved = np.linalg.norm(V[:, :2], axis=1) > far_from_loop
    W = V.copy()
    W[moved] += np.random.default_rng(seed).normal(0.0, 0.5 * edge, (int(moved.sum()), 3))
    return V, W, F, loop


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_surroundings_crossing_themselves_counts_the_folds_beside_a_hole(seed):
    V, W, F, loop = _jittered_bowl(seed)
    incidence = vertex_face_incidence(F, len(V))
    assert surroundings_crossing_themselves(V, F, loop, incidence) == 0
    ring_faces = len(hole_context(W, F, loop, incidence, rings=2).faces)
    assert 0 < surroundings_crossing_themselves(W, F, loop, incidence) <= ring_faces
    # Folds more than two rings away are not the hole's: jitter only beyond them.
    _, far, _, _ = _jittered_bowl(seed, far_from_loop=0.45 + 4 * 2.0 / 20)
    assert surroundings_crossing_themselves(far, F, loop, incidence) == 0
