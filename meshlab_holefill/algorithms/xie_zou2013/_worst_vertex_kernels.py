"""Compiled kernel of the apex moves of the ``relax`` option (numba): one round of
:func:`.optimisation.improve_worst_vertices`.

The vertices are taken in the order the caller gives and each is moved, or not, exactly as the
numpy code (:func:`.optimisation.improve_worst_vertices_numpy`) moves it: the same candidate
targets, the same IEEE operations in the same order (numpy's 1-D dot and norm sum the three
products left to right, np.einsum's row dots as :func:`meshlab_holefill.geometry._vector_kernels.dot3`,
the mean of the link adds its rows in index order), so the same bits.
tests/algorithms/xie_zou2013/test_worst_vertex_kernels.py checks it against the numpy code.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...geometry._quality_kernels import face_quality
from ...geometry._vector_kernels import cross3, dot3, npmin
from ._fold_kernels import _unit_normal
from ._patch_kernels import link_vertices

__all__ = ["worst_vertex_moves"]

_HALF_SQRT3 = math.sqrt(3.0) / 2.0  # the height of an equilateral triangle over its edge


@njit(cache=True)
def _dot(a, b):
    """numpy's 1-D ``a @ b`` of two 3-vectors: the products added left to right."""
    return (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2]


@njit(cache=True)
def _unit_or_small(a):
    """``a / max(np.linalg.norm(a), 1e-300)`` for a 3-vector (Python's max: a NaN norm stays)."""
    length = math.sqrt(_dot(a, a))
    if 1e-300 > length:
        length = 1e-300
    return (a[0] / length, a[1] / length, a[2] / length)


@njit(cache=True)
def _row(V, v):
    return (V[v, 0], V[v, 1], V[v, 2])


@njit(cache=True)
def _worst_quality(V, F, faces):
    """``triangle_quality(V, F[faces]).min()`` (NaN propagating, as numpy's min)."""
    worst = face_quality(V, F[faces[0], 0], F[faces[0], 1], F[faces[0], 2])
    for r in range(1, faces.shape[0]):
        f = faces[r]
        worst = npmin(worst, face_quality(V, F[f, 0], F[f, 1], F[f, 2]))
    return worst


@njit(cache=True)
def _goals(V, F, faces, v, nv, target):
    """The candidate targets of vertex v, (g, 3): the centroid of its link, then for each incident face
    below ``target`` the apex of the equilateral triangle on its opposite edge, in the tangent plane."""
    link = link_vertices(F, faces, v)
    goals = np.empty((1 + faces.shape[0], 3))
    for c in range(3):
        s = V[link[0], c] if link.shape[0] else 0.0
        for r in range(1, link.shape[0]):
            s += V[link[r], c]
        goals[0, c] = s / link.shape[0] if link.shape[0] else np.nan
    g = 1
    for f in faces:
        if not face_quality(V, F[f, 0], F[f, 1], F[f, 2]) < target:
            continue
        c = 0
        while F[f, c] != v:
            c += 1
        a, b = _row(V, F[f, (c + 1) % 3]), _row(V, F[f, (c + 2) % 3])
        e = (b[0] - a[0], b[1] - a[1], b[2] - a[2])
        side = _unit_or_small(cross3(nv, e))
        reach = math.sqrt(_dot(e, e))
        for k in range(3):
            goals[g, k] = 0.5 * (a[k] + b[k]) + side[k] * _HALF_SQRT3 * reach
        g += 1
    return goals[:g]


@njit(cache=True)
def worst_vertex_moves(V, F, faces_at, start, order, N, target, steps, min_cos):
    """Move each vertex of ``order`` in turn, in place in V, where a candidate raises the worst quality of its faces.

    For vertex v with faces faces_at[start[v]:start[v + 1]] and unit normal N[v]: each target of
    :func:`_goals`, its displacement made tangential, is tried at each fraction of ``steps``; the position
    whose worst face quality beats the best so far by more than 1e-6, with no face turned to a cosine of
    ``min_cos`` or less from the vertex normal or from its own former normal, is kept.

    Parameters
    ----------
    V : (n, 3) float64, C-contiguous (moved in place)
    F : (m, 3) int64  valid indices
    faces_at, start : :func:`meshlab_holefill.geometry.topology.vertex_face_runs` of F
    order : (s,) int64  the vertices to try, in turn
    N : (n, 3) float64  vertex normals (as at the start of the round)
    target : float
    steps : (t,) float64
    min_cos : float

    Returns
    -------
    int  the vertices moved
    """
    changed = 0
    for v in order:
        faces = faces_at[start[v]:start[v + 1]]
        nv = _unit_or_small(_row(N, v))
        best_q = _worst_quality(V, F, faces)
        goals = _goals(V, F, faces, v, nv, target)
        old = np.empty((faces.shape[0], 3))
        for r in range(faces.shape[0]):
            old[r, 0], old[r, 1], old[r, 2] = _unit_normal(V, F[faces[r]])
        here = _row(V, v)
        best = here
        moved = False
        for g in range(goals.shape[0]):
            d = (goals[g, 0] - here[0], goals[g, 1] - here[1], goals[g, 2] - here[2])
            along = _dot(d, nv)
            d = (d[0] - along * nv[0], d[1] - along * nv[1], d[2] - along * nv[2])
            for s in steps:
                p = (here[0] + s * d[0], here[1] + s * d[1], here[2] + s * d[2])
                V[v, 0], V[v, 1], V[v, 2] = p
                qn = _worst_quality(V, F, faces)
                if qn <= best_q + 1e-6:
                    continue
                turned = False
                for r in range(faces.shape[0]):
                    fn = _unit_normal(V, F[faces[r]])
                    if dot3(fn, nv) <= min_cos or dot3(fn, (old[r, 0], old[r, 1], old[r, 2])) <= min_cos:
                        turned = True
                        break
                if turned:
                    continue
                best, best_q, moved = p, qn, True
        V[v, 0], V[v, 1], V[v, 2] = best
        changed += moved
    return changed
