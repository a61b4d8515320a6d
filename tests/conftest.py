"""Shared fixtures: pymeshlab sample meshes and analytic shapes with holes of known shape."""
import functools
import os

import numpy as np
import pymeshlab
import pytest

import meshlab_holefill  # noqa: F401  (registers the filters)
from hypothesis import settings

# Property tests draw their examples from a fixed seed, so a run is reproducible (CI runs the
# suite once on a fresh clone); HYPOTHESIS_PROFILE=explore draws new ones, and a failure found
# that way becomes an explicit @example of its test.
settings.register_profile("reproducible", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "reproducible"))

SAMPLES = os.path.join(os.path.dirname(pymeshlab.__file__), "tests", "sample_meshes")


def sample(name):
    return os.path.join(SAMPLES, name)


def mesh_arrays(ms):
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)


def meshset_from_arrays(V, F, name="mesh"):
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(V, np.float64), face_matrix=np.asarray(F, np.int32)), name)
    return ms


def cut_disks(V, F, centers, radius):
    """Remove faces whose centroid is within ``radius`` of any centre; returns (V, F_kept, F_removed)."""
    C = V[F].mean(axis=1)
    remove = np.zeros(len(F), bool)
    for c in np.atleast_2d(centers):
        remove |= np.linalg.norm(C - c, axis=1) < radius
    return V, F[~remove], F[remove]


def sphere_with_holes(subdiv=4, centers=((1, 0, 0), (0, 0, 1)), radius=0.35):
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=subdiv)
    V, F = mesh_arrays(ms)
    return cut_disks(V, F, np.asarray(centers, float), radius)


def grid(nx=12, ny=12, z=None):
    """Flat (or height-field) triangulated square grid in [0, 1]^2, counter-clockwise faces."""
    xs, ys = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, ny))
    V = np.stack([xs.ravel(), ys.ravel(), np.zeros(nx * ny)], axis=1)
    if z is not None:
        V[:, 2] = z(V[:, 0], V[:, 1])
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    F = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return V, F


@pytest.fixture
def bunny_scan():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("bunny10k_textured.obj"))
    return ms


def scan_with_loops(name):
    """A sample mesh's vertices, faces and boundary loops."""
    from meshlab_holefill.core.holes import boundary_loops

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample(name))
    V, F = mesh_arrays(ms)
    return V, F, boundary_loops(F)


@pytest.fixture(scope="session")
def face_scan():
    """face000.ply (range scan: jagged hole borders with long edges) and its boundary loops."""
    return scan_with_loops("rangemaps/face000.ply")


@pytest.fixture(scope="session")
def bunny_loops():
    """bunny10k_textured.obj (the bunny scan's 5 natural holes) and its boundary loops."""
    return scan_with_loops("bunny10k_textured.obj")


def random_planar_patch(k, points, seed):
    """A regular k-gon (loop first, counter-clockwise) with random inner points, Delaunay-triangulated in z = 0."""
    from scipy.spatial import Delaunay

    t = 2 * np.pi * np.arange(k) / k
    loop = np.stack([np.cos(t), np.sin(t)], axis=1)
    rng = np.random.default_rng(seed)
    # inside the inscribed circle, some right next to the loop: slivers
    r, a = 0.97 * np.cos(np.pi / k) * np.sqrt(rng.random(points)), 2 * np.pi * rng.random(points)
    inner = np.stack([r * np.cos(a), r * np.sin(a)], axis=1)
    P = np.concatenate([loop, inner])
    F = Delaunay(P).simplices.astype(np.int64)
    A = P[F]
    cw = (A[:, 1, 0] - A[:, 0, 0]) * (A[:, 2, 1] - A[:, 0, 1]) < (A[:, 1, 1] - A[:, 0, 1]) * (A[:, 2, 0] - A[:, 0, 0])
    F[cw] = F[cw][:, [0, 2, 1]]
    return np.column_stack([P, np.zeros(len(P))]), F


def assert_filled_cleanly(V0, F0, V1, F1, faces_kept=True):
    """The filled mesh: no border left, 2-manifold, consistently oriented, no new face crossing the mesh.

    Original vertex positions stay bit-exact; with ``faces_kept`` the original faces too (the
    LS-SVM filter splits long border edges, Sec. 3.1, and so replaces some border faces).
    """
    from meshlab_holefill.geometry.intersections import faces_intersecting
    from meshlab_holefill.core.holes import boundary_loops, nonmanifold_edges

    assert np.array_equal(V1[:len(V0)], V0)
    if faces_kept:
        assert np.array_equal(F1[:len(F0)], F0)
    assert boundary_loops(F1) == []
    assert len(nonmanifold_edges(F1)) == 0
    directed = np.concatenate([F1[:, [0, 1]], F1[:, [1, 2]], F1[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed), "a directed edge twice: orientation flips"
    if faces_kept:
        new = np.arange(len(F0), len(F1))
    else:
        old = set(map(tuple, F0.tolist()))
        new = np.array([i for i, f in enumerate(map(tuple, F1.tolist())) if f not in old], np.int64)
    assert len(faces_intersecting(V1, F1, new, np.arange(len(F1)))) == 0


def assert_one_hole_filled_cleanly(V0, F0, V1, F1):
    """One hole of a mesh with many filled: one boundary loop fewer, originals bit-exact, 2-manifold,
    consistently oriented, no new face crossing the mesh."""
    from meshlab_holefill.geometry.intersections import faces_intersecting
    from meshlab_holefill.core.holes import boundary_loops, nonmanifold_edges

    assert np.array_equal(V1[:len(V0)], V0) and np.array_equal(F1[:len(F0)], F0)
    assert len(boundary_loops(F1)) == len(boundary_loops(F0)) - 1
    assert len(nonmanifold_edges(F1)) == len(nonmanifold_edges(F0))
    directed = np.concatenate([F1[:, [0, 1]], F1[:, [1, 2]], F1[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed), "a directed edge twice: orientation flips"
    assert len(faces_intersecting(V1, F1, np.arange(len(F0), len(F1)), np.arange(len(F1)))) == 0


@functools.cache
def noisy_cow_scan(seed):
    """A virtual range scan of cow.obj Loop-subdivided twice, with noise of 0.15 mean edges along the normals,
    from the direction drawn with ``seed`` (the benchmark's noisy scans): (V, F) of the seen sheet, whose holes
    are what the scanner did not see (occlusion shadows, grazing strips; many pinched, some slit-like)."""
    from meshlab_holefill.evaluation.comparison import prepare_case
    from meshlab_holefill.evaluation.virtual_scan import virtual_scan_case

    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(sample("cow.obj"))
    ms.meshing_surface_subdivision_loop(iterations=2, threshold=pymeshlab.PercentageValue(0))
    V, F = mesh_arrays(ms)
    direction = np.random.default_rng(seed).normal(size=3)
    case = prepare_case(virtual_scan_case("cow scan", V, F, direction, noise=0.15, seed=seed))
    return case.V0, case.F0


def loop_nearest(V, F, point):
    """(index, BoundaryLoop) of the boundary loop whose vertices' centroid is nearest ``point``: a hole found by
    where it is, which stays the same hole where a change elsewhere renumbers the loops."""
    from meshlab_holefill.core.holes import boundary_loops

    loops = boundary_loops(F)
    i = int(np.argmin([np.linalg.norm(V[loop.vertices].mean(axis=0) - point) for loop in loops]))
    return i, loops[i]


@functools.cache
def numpy_products_round_as_the_kernels():
    """Whether numpy's (s, 3) @ (3,) product here rounds as the compiled kernels' copy of it (``gemv_row``).

    The copy follows OpenBLAS's dgemv kernel of the machines the package is developed on (one
    fused multiply-add order); BLAS kernels for other processors (AVX-512 ones, for example) may
    round the last bit differently, and compiled steps then differ from their numpy references in
    that bit: bit-for-bit comparisons between the two apply only where this holds.
    """
    from meshlab_holefill.algorithms.xie_zou2013._quality_pass_kernels import gemv_row

    rng = np.random.default_rng(7)
    for rows in (1, 2, 3, 5, 8):
        A = rng.standard_normal((rows, 3))
        b = rng.standard_normal(3)
        got = np.array([gemv_row(A[i], b, rows) for i in range(rows)])
        if got.tobytes() != (A @ b).tobytes():
            return False
    return True
