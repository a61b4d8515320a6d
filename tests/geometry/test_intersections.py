
import numpy as np
import pymeshlab
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from meshlab_holefill.geometry.intersections import faces_intersecting, intersecting_pairs


def meets(V, F, i=0, j=1, **kw):
    """Whether faces i and j intersect; also checks the answer is symmetric."""
    ab = len(intersecting_pairs(V, F, [i], [j], **kw)) > 0
    ba = len(intersecting_pairs(V, F, [j], [i], **kw)) > 0
    assert ab == ba
    return ab


def soup(*tris):
    """Mesh of triangles given by corner coordinates, sharing no vertex index."""
    V = np.array(tris, dtype=float).reshape(-1, 3)
    return V, np.arange(len(V)).reshape(-1, 3)


def uv_sphere(nu, nv, r=1.0, centre=(0.0, 0.0, 0.0)):
    """Closed UV sphere: nu segments, nv rings, triangle fans at the poles."""
    th = np.linspace(0, np.pi, nv + 1)[1:-1]
    ph = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    T, P = np.meshgrid(th, ph, indexing="ij")
    V = np.c_[np.sin(T).ravel() * np.cos(P).ravel(), np.sin(T).ravel() * np.sin(P).ravel(), np.cos(T).ravel()]
    V = np.vstack([V, [0, 0, 1], [0, 0, -1]]) * r + centre
    n, k = len(V) - 2, np.arange(nu)
    a = (np.arange(nv - 2)[:, None] * nu + k).ravel()
    b = (np.arange(nv - 2)[:, None] * nu + (k + 1) % nu).ravel()
    F = np.vstack([np.c_[a, a + nu, b], np.c_[b, a + nu, b + nu],
                   np.c_[np.full(nu, n), k, (k + 1) % nu],
                   np.c_[np.full(nu, n + 1), n - nu + (k + 1) % nu, n - nu + k]])
    return V, F


def icosphere():
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    return ms.current_mesh().vertex_matrix().copy(), ms.current_mesh().face_matrix().copy()


# Shared-topology configurations: (V, F with faces 0 and 1, expected intersection)
FLAT = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
CONFIGS = {
    "pierce_x": (*soup(FLAT, [[0.2, 0.2, -1], [0.3, 0.2, 1], [0.25, 2, 0.1]]), True),
    "parallel": (*soup(FLAT, np.add(FLAT, [0, 0, 0.5])), False),
    "coplanar_overlap": (*soup(FLAT, [[0.2, 0.2, 0], [2, 0.3, 0], [0.3, 2, 0]]), True),
    "coplanar_contained": (*soup([[0, 0, 0], [4, 0, 0], [0, 4, 0]], [[1, 1, 0], [1.5, 1, 0], [1, 1.5, 0]]), True),
    "coplanar_disjoint": (*soup(FLAT, np.add(FLAT, [1.2, 0.5, 0])), False),
    # shared edge 0-1; third vertices 2 and 3
    "strip": (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, -1, 0.]]), np.array([[0, 1, 2], [1, 0, 3]]), False),
    "folded": (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.8, 0.5, 0.]]), np.array([[0, 1, 2], [1, 0, 3]]), True),
    "right_angle": (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.5, 0, 1.]]), np.array([[0, 1, 2], [1, 0, 3]]), False),
    # shared vertex 0
    "fan_flat": (np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [-1, 1, 0], [-1, -0.2, 0]]),
                 np.array([[0, 1, 2], [0, 3, 4]]), False),
    "vertex_pierce": (np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [0.5, 0.5, 1], [0.5, 0.5, -1.]]),
                      np.array([[0, 1, 2], [0, 3, 4]]), True),
    "vertex_pierce_big": (np.array([[0, 0, 0], [0.2, 0, 0], [0, 0.2, 0], [5, 5, 4], [5, 5, -4.]]),
                          np.array([[0, 1, 2], [0, 3, 4]]), True),
    # edge 0-3 of face 1 lies in face 0's plane, runs through its interior and leaves it
    "vertex_edge_inside": (np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [2, 2, 0], [1, -1, 1.]]),
                           np.array([[0, 1, 2], [0, 3, 4]]), True),
    # the same with face 1 upright: the crossing point lies exactly on its boundary edge 0-3
    "vertex_edge_inside_upright": (np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [2, 2, 0], [0.5, 0.5, 1.]]),
                                   np.array([[0, 1, 2], [0, 3, 4]]), True),
    "vertex_coplanar_overlap": (np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [2, 1, 0], [1, 2, 0.]]),
                                np.array([[0, 1, 2], [0, 3, 4]]), True),
    "vertex_cone": (np.array([[0, 0, 1], [1, 0, 0], [0.5, 0.8, 0], [-1, 0, 0], [-0.5, -0.8, 0.]]),
                    np.array([[0, 1, 2], [0, 3, 4]]), False),
}


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_configurations(name):
    V, F, expected = CONFIGS[name]
    assert meets(V, F) == expected


def test_edge_through_shared_vertex_inside_other_face_is_robust():
    # the only witness is a crossing exactly on a face boundary, so without growing faces
    # by tol in their plane the answer would follow the rounding of each rotation
    V, F, _ = CONFIGS["vertex_edge_inside_upright"]
    for seed in range(20):
        assert meets(Rotation.random(random_state=seed).apply(V) * 3 + 1, F)


@pytest.mark.parametrize("opening, expected", [(0.0, True), (1e-5, True), (2e-3, False), (0.3, False)])
def test_shared_edge_fold_threshold(opening, expected):
    third = [0.5, 0.5 * np.cos(opening), 0.5 * np.sin(opening)]  # rotated about the shared x axis
    V = np.array([[0, 0, 0], [1, 0, 0], [0.3, 1, 0], third])
    assert meets(V, [[0, 1, 2], [1, 0, 3]]) == expected
    assert meets(V, [[0, 1, 2], [1, 0, 3]], fold_angle=1.0)  # caller can widen the fold test


@pytest.mark.parametrize("apex_z", [0.0, 0.5, -2.0])
@pytest.mark.parametrize("valence", [3, 6, 40])
def test_fan_around_vertex_all_pairs_clear(apex_z, valence):
    ang = np.linspace(0, 2 * np.pi, valence, endpoint=False)
    ring = np.c_[np.cos(ang), np.sin(ang), 0.3 * np.sin(3 * ang)]  # wavy rim: a saddle for apex_z = 0
    V = np.vstack([[0, 0, apex_z], ring])
    k = np.arange(valence)
    F = np.c_[np.zeros(valence, int), k + 1, (k + 1) % valence + 1]
    allf = np.arange(len(F))
    assert intersecting_pairs(V, F, allf, allf).shape == (0, 2)


@pytest.mark.parametrize("mesh", ["ico", "uv"])
def test_closed_sphere_clean_then_pushed_vertex_intersects(mesh):
    V, F = icosphere() if mesh == "ico" else uv_sphere(32, 17)
    allf = np.arange(len(F))
    assert len(intersecting_pairs(V, F, allf, allf)) == 0
    V = V.copy()
    V[5] *= -1.5  # through the centre and out the far side
    pairs = intersecting_pairs(V, F, allf, allf)
    assert len(pairs) > 0
    moved = np.isin(F, 5).any(1)
    assert (moved[pairs[:, 0]] | moved[pairs[:, 1]]).all()


def _reference(t1, t2):
    """Interval test on the planes' common line; exact for triangles in general position."""
    n1 = np.cross(t1[1] - t1[0], t1[2] - t1[0])
    n2 = np.cross(t2[1] - t2[0], t2[2] - t2[0])
    d1, d2 = (t1 - t2[0]) @ n2, (t2 - t1[0]) @ n1
    if np.all(d1 > 0) or np.all(d1 < 0) or np.all(d2 > 0) or np.all(d2 < 0):
        return False
    D = np.cross(n1, n2)

    def span(t, d):
        s = [(t[i] + (t[j] - t[i]) * d[i] / (d[i] - d[j])) @ D
             for i, j in ((0, 1), (1, 2), (2, 0)) if d[i] * d[j] < 0]
        return min(s), max(s)

    (a0, a1), (b0, b1) = span(t1, d1), span(t2, d2)
    return a0 <= b1 and b0 <= a1


@pytest.mark.parametrize("seed", range(4))
def test_random_soup_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    n = 40
    T = rng.uniform(0, 3, (n, 1, 3)) + rng.normal(0, 0.4 * rng.uniform(0.2, 2, (n, 1, 1)), (n, 3, 3))
    V, F = T.reshape(-1, 3), np.arange(3 * n).reshape(-1, 3)
    expected = {(i, j) for i in range(n) for j in range(i + 1, n) if _reference(T[i], T[j])}
    allf = np.arange(n)
    assert {tuple(p) for p in intersecting_pairs(V, F, allf, allf)} == expected
    q, a = allf[:15], allf[15:]
    assert {tuple(p) for p in intersecting_pairs(V, F, q, a)} == {p for p in expected if p[0] < 15 <= p[1]}
    # one face against the rest: most of `against` lies outside its box and is dropped first
    for f in range(3):
        got = {tuple(sorted(p)) for p in intersecting_pairs(V, F, [f], allf)}
        assert got == {p for p in expected if f in p}
    assert len(expected) > 5  # the soup is dense enough to mean something


def test_random_shared_vertex_pairs_match_reference():
    rng = np.random.default_rng(1)
    k = 400
    pts = rng.normal(size=(k, 5, 3)) + 100.0 * np.arange(k)[:, None, None]  # groups far apart
    V = pts.reshape(-1, 3)
    base = 5 * np.arange(k)[:, None]
    F = np.vstack([np.c_[base, base + 1, base + 2], np.c_[base, base + 3, base + 4]])

    def reach(S, a, b, n, D):  # signed extent along D of triangle S,a,b on the plane with normal n
        da, db = (a - S) @ n, (b - S) @ n
        return 0.0 if da * db > 0 else (a + (b - a) * da / (da - db) - S) @ D

    expected = set()
    for g, (S, a1, b1, a2, b2) in enumerate(pts):
        n1, n2 = np.cross(a1 - S, b1 - S), np.cross(a2 - S, b2 - S)
        D = np.cross(n1, n2)
        if reach(S, a1, b1, n2, D) * reach(S, a2, b2, n1, D) > 0:
            expected.add((g, g + k))
    got = {tuple(p) for p in intersecting_pairs(V, F, np.arange(k), np.arange(k, 2 * k))}
    assert got == expected
    assert 0.1 * k < len(expected) < 0.9 * k


angles = st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 0.1)
motions = st.tuples(angles, st.floats(1e-2, 1e2), st.lists(st.floats(-10, 10), min_size=3, max_size=3))


@settings(max_examples=60, deadline=None)
@given(motion=motions, name=st.sampled_from(sorted(CONFIGS)))
def test_similarity_transform_preserves_answer(motion, name):
    quat, scale, shift = motion
    V, F, expected = CONFIGS[name]
    V2 = Rotation.from_quat(quat).apply(V) * scale + shift
    assert meets(V2, F) == expected


@settings(max_examples=60, deadline=None)
@given(tri=st.lists(st.floats(-5, 5), min_size=9, max_size=9),
       direction=st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(lambda d: np.linalg.norm(d) > 0.1),
       dist=st.floats(1.01, 1e3))
def test_far_translated_copy_never_intersects(tri, direction, dist):
    t = np.reshape(tri, (3, 3))
    size = np.linalg.norm(t.max(0) - t.min(0))
    shift = np.asarray(direction) / np.linalg.norm(direction) * (dist * size + 1e-3)
    V, F = soup(t, t + shift)
    assert not meets(V, F)


def test_result_format_indices_into_F_query_first():
    V, F = uv_sphere(12, 7)
    n = len(F)
    spikes = [[[0.5, 0, 0], [1.5, 0.1 * k, 0.2], [1.5, -0.1, -0.2 - 0.1 * k]] for k in range(3)]
    V = np.vstack([V, np.reshape(spikes, (-1, 3))])  # 3 faces poking out through the sphere
    F = np.vstack([F, len(V) - 9 + np.arange(9).reshape(3, 3)])
    query, against = np.array([n + 2, n, n + 1, n]), np.arange(n)
    pairs = intersecting_pairs(V, F, query, against)
    assert pairs.dtype == np.int64 and pairs.ndim == 2 and pairs.shape[1] == 2
    assert len(pairs) > 0
    assert np.isin(pairs[:, 0], query).all() and np.isin(pairs[:, 1], against).all()
    assert len(np.unique(pairs, axis=0)) == len(pairs)
    hits = faces_intersecting(V, F, query, against)
    assert np.array_equal(hits, np.unique(pairs[:, 0]))

    allf = np.arange(len(F))
    selfp = intersecting_pairs(V, F, allf, allf)
    assert (selfp[:, 0] != selfp[:, 1]).all()
    assert len({frozenset(p) for p in selfp}) == len(selfp)
    assert {frozenset(p) for p in pairs} <= {frozenset(p) for p in selfp}
    hit_all = faces_intersecting(V, F, allf, allf)
    assert np.array_equal(hit_all, np.unique(selfp))  # both partners count


def test_empty_inputs():
    V, F = soup(FLAT, FLAT)
    assert intersecting_pairs(V, F, [], [0, 1]).shape == (0, 2)
    assert faces_intersecting(V, F, [0], []).shape == (0,)
    assert intersecting_pairs(V, F, [0], [0]).shape == (0, 2)  # never with itself


def test_duplicate_face_intersects():
    V = np.array(FLAT, float)
    assert meets(V, [[0, 1, 2], [2, 1, 0]])


def test_unwelded_vertices_count_as_shared():
    V, F, _ = CONFIGS["fan_flat"]
    V2 = np.vstack([V, V[0]])  # face 1 uses a coincident copy of vertex 0
    assert not meets(V2, [[0, 1, 2], [5, 3, 4]])
    Vs, Fs, _ = CONFIGS["strip"]
    assert not meets(np.vstack([Vs, Vs[:2]]), [[0, 1, 2], [5, 4, 3]])


def test_degenerate_faces():
    needle = [[0.2, 0.2, -1], [0.2, 0.2, 1], [0.2, 0.2, 0.5]]  # collinear: zero area
    V, F = soup(FLAT, needle)
    assert meets(V, F)  # a needle through a face is reported
    V, F = soup(needle, np.add(needle, [0, 0, 0.3]))
    assert not meets(V, F)  # two degenerate faces never intersect
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.5, 0, 0]])
    assert not meets(V, [[0, 1, 2], [0, 1, 3]])  # degenerate face on a shared edge
    V[3] = [0.3, 0.3, 0]
    assert meets(V, [[0, 1, 2], [0, 0, 3]])  # repeated vertex index: a needle into the face
    V[3] = [-0.3, 0.3, 0]
    assert not meets(V, [[0, 1, 2], [0, 0, 3]])  # ... and one pointing away from it
    V = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0], [1, 1, 0], [2, 2, 0]])
    assert meets(V, [[0, 1, 2], [0, 3, 4]])  # needle from the shared vertex through the face
    V2 = V.copy()
    V2[3:] *= [1, -1, 1]  # same needle pointing away from the face
    assert not meets(V2, [[0, 1, 2], [0, 3, 4]])
    V = np.array([[0, 0, 0], [1, 0, 0], [0.3, 1, 0], [0.5, 1e-14, 0]])
    assert not meets(V, [[0, 1, 2], [1, 0, 3]])  # sliver flatter than tol along a shared edge


def test_sharp_corner_does_not_reach_out():
    # corner of 1e-4 rad at the origin; an edge of the other face passes 100 tol beyond it,
    # where the sliver's edge lines grown by tol would still overlap (up to 2e4 tol)
    turn = Rotation.from_euler("xyz", [0.3, 0.5, 0.7])  # so that bounding boxes do not decide
    sliver = [[0, 0, 0], [1, 5e-5, 0], [1, -5e-5, 0]]
    V, F = soup(sliver, [[-1e-4, 0, -1], [-1e-4, 0, 1], [-1, 0.5, 0]])
    assert not meets(turn.apply(V), F, tol=1e-6)
    V, F = soup(sliver, [[1e-4, 0, -1], [1e-4, 0, 1], [-1, 0.5, 0]])
    assert meets(turn.apply(V), F, tol=1e-6)


@pytest.mark.parametrize("gap, tol, expected", [(5e-7, 1e-6, True), (1e-5, 1e-6, False),
                                                (1e-12, None, True), (1e-6, None, False)])
def test_tolerance_near_touch(gap, tol, expected):
    V, F = soup(FLAT, [[0.3, 0.3, gap], [0.4, 0.3, 1], [0.3, 0.4, 1]])  # vertex hovering over face 0
    assert meets(V, F, tol=tol) == expected


def test_two_crossing_spheres_meet_along_one_curve():
    # Sized like the benchmark's use (3000 query faces against 50000); its time is reported
    # by scripts/benchmark.py, not asserted here.
    V1, F1 = uv_sphere(160, 158)
    V2, F2 = uv_sphere(40, 39, 1.0, (0.3, 0.1, 0.05))
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    against, query = np.arange(len(F1)), np.arange(len(F1), len(F))
    assert len(against) > 50_000 and len(query) > 3000
    hits = faces_intersecting(V, F, query, against)
    assert 0 < len(hits) < len(query)


def test_weld_labels_join_exactly_the_equal_used_vertices_and_boxes_and_radius_ratios_equal_numpy():
    from meshlab_holefill.geometry import _broad_phase_kernels as broad
    from meshlab_holefill.geometry.intersections import _sorted_unique

    rng = np.random.default_rng(0)
    for t in range(200):
        V = rng.integers(-2, 3, (30, 3)).astype(float) * 0.5  # many equal rows, and -0.0 against 0.0
        V[rng.random((30, 3)) < 0.1] *= -0.0
        V[rng.random(30) < 0.05, 1] = np.nan
        F = rng.integers(0, 30, (20, 3))
        faces = rng.integers(0, 20, int(rng.integers(1, 15)))
        used = np.unique(F[faces])
        label = broad.weld_labels(V, F, faces)
        # == welds -0.0 to 0.0 and a NaN to nothing (a vertex is itself by index)
        same = np.all(V[used, None] == V[None, used], axis=2) | np.eye(len(used), dtype=bool)
        np.testing.assert_array_equal(label[used, None] == label[None, used], same)
        np.testing.assert_array_equal(label[used], used[np.argmax(same, axis=1)])
        lo_q, lo_a = rng.normal(size=(int(rng.integers(1, 9)), 3)), rng.normal(size=(int(rng.integers(1, 9)), 3))
        lo_q[rng.random(lo_q.shape) < 0.02] = np.nan
        hi_q, hi_a = lo_q + 1.0, lo_a + 1.0
        lo, hi, far = broad.common_box(lo_q, hi_q, lo_a, hi_a)
        np.testing.assert_array_equal(lo, np.minimum(lo_q.min(0), lo_a.min(0)))
        np.testing.assert_array_equal(hi, np.maximum(hi_q.max(0), hi_a.max(0)))
        if not np.isnan(lo_q).any():
            assert far == max(np.abs(lo).max(), np.abs(hi).max())
        rq, ra = rng.random(len(lo_q)) ** 9, rng.random(len(lo_a)) * (t % 3)  # some all zero
        top = max(rq.max(), ra.max(), np.finfo(float).tiny)
        np.testing.assert_array_equal(broad.radius_ratios(rq, ra), np.maximum(np.concatenate([rq, ra]), 1e-300) / top)
        x = rng.integers(0, 30, int(rng.integers(0, 20)))
        x = np.unique(x) if t % 2 else x
        np.testing.assert_array_equal(_sorted_unique(x), np.unique(x))


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 100_000), n_query=st.integers(1, 12), n_also=st.integers(0, 12),
       weld=st.booleans(), far=st.sampled_from([0.0, 1e3, 1e7]))
def test_queries_against_fixed_faces_give_the_pairs_of_the_plain_query(seed, n_query, n_also, weld, far):
    # A patch (query), faces of its own tested too (also), then fixed faces whose bounds are built once:
    # the answer is that of intersecting_pairs against both sets, bit for bit, shared vertices and all.
    from meshlab_holefill.geometry.intersections import FixedFaces, intersecting_pairs_with_fixed
    rng = np.random.default_rng(seed)
    n_fixed = int(rng.integers(0, 30))
    n = n_query + n_also + n_fixed
    V = rng.uniform(0, 2, (n + 6, 3)) + far
    V[-3:] = V[:3]  # coincident vertices, for the weld
    F = rng.integers(0, len(V), (n, 3))
    F[: n // 3, 0] = 0  # faces sharing a vertex
    start = n_query + n_also
    fixed = FixedFaces(V, F[start:])
    also = np.arange(n_query, start) if n_also and rng.random() < 0.5 else np.arange(start)
    got = intersecting_pairs_with_fixed(V, F, np.arange(n_query), fixed, start, also=also, weld=weld)
    against = np.concatenate([also, np.arange(start, n)])
    assert np.array_equal(got, intersecting_pairs(V, F, np.arange(n_query), against, weld=weld))
    # the fixed faces' numbering within F is the caller's: the same bounds serve them anywhere after `also`
    moved = np.concatenate([F[:start], np.zeros((5, 3), np.int64), F[start:]])
    shifted = intersecting_pairs_with_fixed(V, moved, np.arange(n_query), fixed, start + 5, also=also, weld=weld)
    expected = intersecting_pairs(V, moved, np.arange(n_query), np.concatenate([also, np.arange(start + 5, n + 5)]),
                                  weld=weld)
    assert np.array_equal(shifted, expected)


def test_queries_against_no_fixed_faces_and_no_query():
    from meshlab_holefill.geometry.intersections import FixedFaces, intersecting_pairs_with_fixed
    V, F = soup([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0.2, 0.2, -1], [0.2, 0.2, 1], [0.3, 0.9, 0]])
    none = FixedFaces(V, F[:0])
    assert none.count == 0 and none.box[0].shape == (0, 3)
    assert np.array_equal(intersecting_pairs_with_fixed(V, F, [0], none, 2, also=[1]), [[0, 1]])
    assert intersecting_pairs_with_fixed(V, F, [0], none, 2).shape == (0, 2)
    assert intersecting_pairs_with_fixed(V, F, [], FixedFaces(V, F[1:]), 1).shape == (0, 2)
    assert np.array_equal(intersecting_pairs_with_fixed(V, F, [0], FixedFaces(V, F[1:]), 1), [[0, 1]])
