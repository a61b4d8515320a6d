"""The plain-Python dynamic programme HPDE's last resort used before it was compiled: the tests' oracle.

:func:`meshlab_holefill.algorithms.xie_zou2013.folds.loop_triangulation` now runs the compiled
programme of :mod:`meshlab_holefill.geometry.dihedral_triangulation`; tests/algorithms/xie_zou2013/test_folds.py
checks that it gives this function's triangles, in its order, and its largest angle.
"""
import numpy as np

from meshlab_holefill.geometry.quality import cross_rows
from meshlab_holefill.geometry.topology import edge_pair_set


def loop_triangulation_python(P, border_normals, forbidden_edges=(), blocked=frozenset()):
    """:func:`meshlab_holefill.algorithms.xie_zou2013.folds.loop_triangulation` as it was, in Python, without its size cap.

    Returns (F (k - 2, 3) int64 or None, the largest dihedral angle in radians or inf).
    """
    k = len(P)
    forbidden = edge_pair_set(forbidden_edges)
    normal = {}

    def tri_normal(i, m, j):
        key = (i, m, j)
        if key not in normal:
            n = cross_rows(P[m] - P[i], P[j] - P[i])  # np.cross's arithmetic, without its overhead
            length = np.linalg.norm(n)
            normal[key] = (n / length if length > 0 else n, 0.5 * length)
        return normal[key]

    def angle(n1, n2):
        if not np.any(n1) or not np.any(n2):
            return 0.0
        return float(np.arccos(np.clip(n1 @ n2, -1.0, 1.0)))

    inf = (np.inf, np.inf)
    W = {}
    apex = {}
    for i in range(k - 1):
        W[(i, i + 1)] = (0.0, 0.0)
    for span in range(2, k):
        for i in range(k - span):
            j = i + span
            if span < k - 1 and tuple(sorted((i, j))) in forbidden:
                W[(i, j)] = inf
                continue
            best, best_m = inf, -1
            for m in range(i + 1, j):
                a, b = W[(i, m)], W[(m, j)]
                if a[0] == np.inf or b[0] == np.inf:
                    continue
                n, area = tri_normal(i, m, j)
                if area <= 0 or (i, m, j) in blocked:
                    continue
                worst = max(a[0], b[0])
                for (u, v), sub in (((i, m), apex.get((i, m))), ((m, j), apex.get((m, j)))):
                    other = border_normals[u] if v == u + 1 else tri_normal(u, sub, v)[0]
                    worst = max(worst, angle(n, other))
                if span == k - 1:
                    worst = max(worst, angle(n, border_normals[k - 1]))
                cand = (worst, a[1] + b[1] + area)
                if cand < best:
                    best, best_m = cand, m
            W[(i, j)] = best
            apex[(i, j)] = best_m
    if W[(0, k - 1)][0] == np.inf:
        return None, np.inf
    faces, stack = [], [(0, k - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        m = apex[(i, j)]
        faces.append((i, m, j))
        stack += [(i, m), (m, j)]
    return np.asarray(faces, np.int64), W[(0, k - 1)][0]
