"""Shared cases of the HPDE tests: meshes with holes cut in them, their hole contexts, problems and patch checks."""
import itertools
import os

import numpy as np
import pymeshlab
import pytest

from meshlab_holefill.algorithms.xie_zou2013 import differential_evolution as hpde
from meshlab_holefill.algorithms.xie_zou2013 import folds as hpde_folds, prediction as hpde_prediction
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.core.patch import validate_patch


SAMPLES = os.path.join(os.path.dirname(pymeshlab.__file__), "tests", "sample_meshes")


def grid_plane(n=24, size=1.0):
    """Flat square grid in z = 0, (V, F) with upward normals."""
    t = np.linspace(0, size, n + 1)
    X, Y = np.meshgrid(t, t, indexing="ij")
    V = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], axis=1)
    idx = np.arange(V.shape[0]).reshape(n + 1, n + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return V, np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def grid_cube(n=16):
    """Closed unit cube [0, 1]^3, n x n squares per face, outward normals."""
    index, V, F = {}, [], []

    def vid(key):
        if key not in index:
            index[key] = len(V)
            V.append(np.array(key, float) / n)
        return index[key]

    for axis in range(3):
        u, w = [a for a in range(3) if a != axis]
        for side in (0, n):
            out = np.zeros(3)
            out[axis] = 1.0 if side else -1.0
            for i, j in itertools.product(range(n), range(n)):
                def corner(a, b):
                    key = [0, 0, 0]
                    key[axis], key[u], key[w] = side, a, b
                    return vid(tuple(key))
                q = [corner(i, j), corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1)]
                for tri in ((q[0], q[1], q[2]), (q[0], q[2], q[3])):
                    P = np.array([V[x] for x in tri])
                    if np.cross(P[1] - P[0], P[2] - P[0]) @ out < 0:
                        tri = (tri[0], tri[2], tri[1])
                    F.append(tri)
    return np.array(V), np.array(F, np.int64)


def cut(V, F, center, radius):
    """Remove the faces whose centroid is within radius of center; returns (F_cut, removed faces)."""
    inside = np.linalg.norm(V[F].mean(axis=1) - np.asarray(center), axis=1) < radius
    return F[~inside], F[inside]


def context(V, F_cut):
    """HoleContext of the cut hole (the smallest loop: a grid plane also has its outer border)."""
    loops = boundary_loops(F_cut)
    return hole_context(V, F_cut, loops[-1], rings=hpde.RINGS)


def sphere_mesh(subdiv=4):
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=subdiv)
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)


def sphere_hole_case():
    """The ``sphere_hole`` fixture: a hole round the north pole of the unit sphere, (V, F_cut, removed, ctx)."""
    V, F = sphere_mesh(4)
    F_cut, removed = cut(V, F, (0, 0, 1.0), 0.55)
    return V, F_cut, removed, context(V, F_cut)


def cube_edge_hole_case():
    """The ``cube_edge_hole`` fixture: a hole across an edge of the unit cube, (V, F_cut, removed, ctx)."""
    V, F = grid_cube(16)
    F_cut, removed = cut(V, F, (0.5, 0.0, 0.0), 0.3)
    return V, F_cut, removed, context(V, F_cut)


def patch_points(ctx, patch):
    return patch.all_points(ctx.points)


def check_patch(ctx, patch):
    validate_patch(patch, ctx.points, ctx.forbidden_edges)
    X = patch_points(ctx, patch)
    assert not hpde_folds.local_folds(X, patch.faces, hpde_folds.border_normals(ctx)).any()
    assert not hpde_folds.intersects_surroundings(ctx, X, patch.faces)
    return X


def make_problem(theta_l, theta_u, m, L=3.0):
    """One section plane with end tangents at theta_l (leaving P1) and -theta_u (arriving at P2)."""
    tv1 = np.array([np.cos(theta_l), np.sin(theta_l), 0])
    tv2 = np.array([np.cos(-theta_u), np.sin(-theta_u), 0])
    problem, frames = hpde_prediction.section_problems(
        np.zeros((1, 3)), np.array([[L, 0, 0]]), tv1[None], tv2[None], np.array([[0, 0, 1.0]]), np.array([m]))
    return problem, frames


def _cyclic(face):
    """A face as a tuple starting at its smallest index (same cyclic order, same orientation)."""
    f = [int(x) for x in face]
    i = f.index(min(f))
    return tuple(f[i:] + f[:i])


@pytest.fixture(scope="module")
def sphere_hole():
    """:func:`sphere_hole_case`, built once per test module."""
    return sphere_hole_case()


@pytest.fixture(scope="module")
def cube_edge_hole():
    """:func:`cube_edge_hole_case`, built once per test module."""
    return cube_edge_hole_case()
