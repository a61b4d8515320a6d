"""Queries of the compiled quality pass's patch (numba): the faces at a vertex or an edge, per-face geometry, the keys.

The patch is that of :mod:`._quality_pass_ops`: vertices V (capacity, 3), faces F (capacity,
3), the faces at each vertex in the tables of :mod:`._incidence_kernels` (in the order of the
numpy pass's Python sets), and the pass's constants in one tuple (:func:`context`). Each
helper answers what the numpy pass's ``_Patch`` computes (``edge_faces``, ``neighbours``,
``face_normals`` of a face, ``vertex_normals`` at a vertex...) with the same operations.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ._incidence_kernels import set_add, set_discard, set_items
from ._quality_pass_kernels import _triangle_terms
from ...geometry._vector_kernels import cross3, norm3, sub3

__all__ = ["context", "link_vertices", "EDGE_BASE", "TRIPLE_BASE"]

EDGE_BASE = 1 << 31  # forbidden edge (a, b), a <= b: key a EDGE_BASE + b
TRIPLE_BASE = 1 << 21  # blocked triple (a, b, c) sorted: key (a TRIPLE_BASE + b) TRIPLE_BASE + c


def context(k, floor, gain, turn_cos, border_cos, border, forbidden_keys, blocked_keys, cos_d, sin_d):
    """The tuple of constants the kernels take.

    Returns
    -------
    tuple
        (0) k, (1) the floor, (2) the gain an operation must bring, (3) the cosine of the largest
        turn, (4) that of the largest bend across a loop edge, (5) border (k, 3) float64 the mesh
        normals across the loop edges (0 rows for None) and (6) whether there are, (7) the sorted
        keys of the forbidden edges and (8) of the blocked triples (int64), (9, 10) the cosines
        and sines of the compass's 8 directions (numpy's values), (8,) float64.
    """
    has_border = border is not None
    border = np.zeros((0, 3)) if border is None else np.ascontiguousarray(border, np.float64)
    return (int(k), float(floor), float(gain), float(turn_cos), float(border_cos), border, has_border,
            np.ascontiguousarray(forbidden_keys, np.int64), np.ascontiguousarray(blocked_keys, np.int64),
            np.ascontiguousarray(cos_d, np.float64), np.ascontiguousarray(sin_d, np.float64))


@njit(cache=True)
def _pymax(a, b):
    """Python's max(a, b): b only if b > a."""
    return b if b > a else a


@njit(cache=True)
def _copy_row(dst, i, src, j):
    """dst[i] = src[j] for rows of three (a loop: row assignment costs seconds of compile time)."""
    for d in range(3):
        dst[i, d] = src[j, d]


@njit(cache=True)
def _sorted_unique(values, count):
    """np.unique(values[:count]): the distinct values, ascending (insertion sort: a few dozen values)."""
    out = np.empty(count, values.dtype)
    n = 0
    for i in range(count):
        v = values[i]
        j = n
        while j > 0 and out[j - 1] > v:
            j -= 1
        if j > 0 and out[j - 1] == v:
            continue
        for t in range(n, j, -1):
            out[t] = out[t - 1]
        out[j] = v
        n += 1
    return out[:n]


@njit(cache=True)
def _faces_of(pool, tab, v):
    out = np.empty(tab[v, 3], np.int64)
    set_items(pool, tab, v, out)
    return out


@njit(cache=True)
def _holds(F, f, v):
    return F[f, 0] == v or F[f, 1] == v or F[f, 2] == v


@njit(cache=True)
def _edge_faces(pool, tab, F, a, b):
    """_Patch.edge_faces: the faces at a holding b, in set order."""
    faces = _faces_of(pool, tab, a)
    count = 0
    for f in faces:
        if _holds(F, f, b):
            faces[count] = f
            count += 1
    return faces[:count]


@njit(cache=True)
def _has_edge(pool, tab, F, a, b):
    for f in _faces_of(pool, tab, a):
        if _holds(F, f, b):
            return True
    return False


@njit(cache=True)
def _neighbours(pool, tab, F, v):
    """_Patch.neighbours as a sorted array."""
    return link_vertices(F, _faces_of(pool, tab, v), v)


@njit(cache=True)
def link_vertices(F, faces, v):
    """The corners of ``faces`` (rows of F) other than v, distinct and ascending: v's link when they are its faces."""
    out = np.empty(3 * faces.shape[0], np.int64)
    count = 0
    for f in faces:
        for c in range(3):
            if F[f, c] != v:
                out[count] = F[f, c]
                count += 1
    return _sorted_unique(out, count)


@njit(cache=True)
def _has_key(keys, key):
    """key is in the sorted array keys (binary search)."""
    lo, hi = 0, keys.shape[0]
    while lo < hi:
        mid = (lo + hi) // 2
        if keys[mid] < key:
            lo = mid + 1
        else:
            hi = mid
    return lo < keys.shape[0] and keys[lo] == key


@njit(cache=True)
def _forbidden(ctx, a, b):
    return _has_key(ctx[7], min(a, b) * EDGE_BASE + max(a, b))


@njit(cache=True)
def _blocked(ctx, a, b, c):
    x, y, z = min(a, b, c), max(min(a, b), min(max(a, b), c)), max(a, b, c)
    return z < TRIPLE_BASE and _has_key(ctx[8], (x * TRIPLE_BASE + y) * TRIPLE_BASE + z)


@njit(cache=True)
def _loop_edge(a, b, k):
    return a < k and b < k and (abs(a - b) == 1 or abs(a - b) == k - 1)


@njit(cache=True)
def _other(F, f, a, b):
    """The first corner of face f that is neither a nor b (-1 if none)."""
    for c in range(3):
        if F[f, c] != a and F[f, c] != b:
            return F[f, c]
    return -1


@njit(cache=True)
def _face_quality(V, F, f):
    cr = np.empty(3)
    return _triangle_terms(V[F[f, 0]], V[F[f, 1]], V[F[f, 2]], cr)


@njit(cache=True)
def _face_normal(V, t0, t1, t2, normalize):
    """geometry.quality.face_normals of one face (t0, t1, t2): the cross product, unit or 0 when normalised."""
    n = cross3(sub3(V[t1], V[t0]), sub3(V[t2], V[t0]))
    if not normalize:
        return n
    ln = norm3(n)
    if ln > 0:
        return (n[0] / ln, n[1] / ln, n[2] / ln)
    return (0.0, 0.0, 0.0)


@njit(cache=True)
def _corners(T, V, x, w):
    """V[T] (s, 3, 3), the corners at vertex w (its row of V is not read) at x."""
    s = T.shape[0]
    P = np.empty((s, 3, 3))
    for i in range(s):
        for c in range(3):
            for d in range(3):
                P[i, c, d] = x[d] if T[i, c] == w else V[T[i, c], d]
    return P


@njit(cache=True)
def _corner_of(T, v):
    """Per triangle, the first corner at v (-1: none): np.where(mask.any(1), np.argmax(mask, 1), -1)."""
    corner = np.full(T.shape[0], -1, np.int64)
    for i in range(T.shape[0]):
        for c in range(3):
            if T[i, c] == v:
                corner[i] = c
                break
    return corner


@njit(cache=True)
def _replace_face(pool, tab, sizes, F, f, a, b, c):
    """F[f] := (a, b, c), the incidence sets updated as the numpy pass does (discards, then adds)."""
    for j in range(3):
        set_discard(pool, tab, F[f, j], f)
    F[f, 0], F[f, 1], F[f, 2] = a, b, c
    for v in (a, b, c):
        pool = set_add(pool, tab, sizes, v, f)
    return pool


@njit(cache=True)
def _same_set(a, b):
    """Sorted unique arrays a and b hold the same values."""
    if a.shape[0] != b.shape[0]:
        return False
    for i in range(a.shape[0]):
        if a[i] != b[i]:
            return False
    return True


@njit(cache=True)
def _link_condition(pool, tab, F, x, y, fs, ctx):
    """The neighbours common to x and y are the two faces' opposite corners; a loop y joins no forbidden loop vertex."""
    nx, ny = _neighbours(pool, tab, F, x), _neighbours(pool, tab, F, y)
    common = np.empty(nx.shape[0], np.int64)
    count = 0
    for w in nx:
        if _has_key(ny, w):
            common[count] = w
            count += 1
    opposite = np.empty(2, np.int64)
    opposite[0], opposite[1] = _other(F, fs[0], x, y), _other(F, fs[1], x, y)
    if not _same_set(common[:count], _sorted_unique(opposite, 2)):
        return False
    k = ctx[0]
    if y < k:
        for w in nx:
            if w != y and w < k and _forbidden(ctx, y, w):
                return False
    return True


@njit(cache=True)
def _vertex_normal(V, old, y):
    """geometry.quality.vertex_normals(V, old)[y]: the cross products of old's faces at y, unit.

    Summed as its bincount does: the faces with y at corner 0 in order, then at corner 1, then 2.
    """
    acc = (0.0, 0.0, 0.0)
    for c in range(3):
        for r in range(old.shape[0]):
            if old[r, c] == y:
                n = _face_normal(V, old[r, 0], old[r, 1], old[r, 2], False)
                acc = (acc[0] + n[0], acc[1] + n[1], acc[2] + n[2])
    ln = norm3(acc)
    if ln > 0:
        acc = (acc[0] / ln, acc[1] / ln, acc[2] / ln)
    out = np.empty(3)
    out[0], out[1], out[2] = acc
    return out
