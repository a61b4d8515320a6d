"""The numpy triangle-triangle query that the compiled kernels replaced (geometry/_broad_phase_kernels.py,
geometry/_narrow_phase_kernels.py), kept as the reference.

intersections.intersecting_pairs before the compiled kernels, verbatim but for this docstring and the
import of cross_rows (see git history of meshlab_holefill/geometry/intersections.py for the module's
documentation of the predicates); tests/geometry/test_tri_kernels.py checks that the compiled query
gives exactly its answers.
"""
import numpy as np
from scipy.spatial import cKDTree

from meshlab_holefill.geometry.quality import cross_rows

FOLD_ANGLE = 1e-3  # radians of opening below which edge-adjacent faces overlap
CHUNK = 200_000  # candidate pairs processed at once, bounds temporary memory

__all__ = ["intersecting_pairs", "faces_intersecting"]


def intersecting_pairs(V, F, query, against, tol=None, *, fold_angle=FOLD_ANGLE, weld=True):
    """Pairs of intersecting faces, one from `query` and one from `against`.

    Parameters
    ----------
    V : (n, 3) float64
        Vertex positions.
    F : (m, 3) int
        Triangles as vertex indices into `V`.
    query, against : (q,) int, (a,) int
        Face indices into `F`.  The sets may overlap (e.g. a patch tested
        against itself); duplicates are ignored.
    tol : float, optional
        Contact distance, see module docstring.  Default: scale-aware.
    fold_angle : float
        Opening angle (radians) below which faces sharing an edge overlap.
    weld : bool
        Vertices with identical coordinates count as shared (default); False: only equal indices.

    Returns
    -------
    pairs : (p, 2) int64
        Face indices into `F`, column 0 from `query`, column 1 from `against`,
        sorted.  No face is paired with itself and each unordered pair appears
        once (when both faces are in both sets, the smaller index comes first).
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    q = np.unique(np.asarray(query, dtype=np.int64).ravel())
    a = np.unique(np.asarray(against, dtype=np.int64).ravel())
    out = [np.empty((0, 2), np.int64)]
    if len(q) == 0 or len(a) == 0:
        return out[0]

    if tol is None:
        P = V[np.unique(F[np.concatenate([q, a])])]
        diag = np.linalg.norm(P.max(0) - P.min(0))
        tol = 1e-9 * diag + 1e-13 * np.abs(P).max()
    # Faces of `against` outside the query faces' common box (grown by tol) meet none of them;
    # dropping them first spares the candidate search and the welding that work (a few new
    # triangles tested against a whole ring of faces).
    Tq, Ta = V[F[q]], V[F[a]]
    lo, hi = Tq.min(axis=(0, 1)) - tol, Tq.max(axis=(0, 1)) + tol
    a = a[np.all(Ta.max(axis=1) >= lo, axis=1) & np.all(Ta.min(axis=1) <= hi, axis=1)]
    if len(a) == 0:
        return out[0]
    used = np.unique(F[np.concatenate([q, a])])
    P = V[used] + 0.0  # +0.0 turns -0.0 into 0.0 so the welding below sees them equal
    if weld:
        canon = np.zeros(len(V), np.int64)
        canon[used] = np.unique(P, axis=0, return_inverse=True)[1].ravel()
    else:
        canon = np.arange(len(V), dtype=np.int64)
    in_q = np.zeros(len(F), bool)
    in_q[q] = True
    in_a = np.zeros(len(F), bool)
    in_a[a] = True

    # The candidate search yields one small block per pair of radius bins; the narrow phase's
    # cost is mostly per call, so the blocks are joined and tested CHUNK pairs at a time.
    blocks = list(_candidates(V[F[q]], V[F[a]], tol))
    iq_all = np.concatenate([b[0] for b in blocks]) if blocks else np.zeros(0, np.int64)
    ja_all = np.concatenate([b[1] for b in blocks]) if blocks else np.zeros(0, np.int64)
    for s in range(0, len(iq_all), CHUNK):
        i, j = q[iq_all[s:s + CHUNK]], a[ja_all[s:s + CHUNK]]
        # (i, j) and (j, i) are both generated when both faces are in both sets
        keep = (i != j) & ~((i > j) & in_q[j] & in_a[i])
        i, j = i[keep], j[keep]
        T1, T2 = V[F[i]], V[F[j]]
        maybe = ~(_beyond_plane(T1, T2, tol) | _beyond_plane(T2, T1, tol))
        i, j = i[maybe], j[maybe]
        hit = _narrow(T1[maybe], T2[maybe], canon[F[i]], canon[F[j]], tol, fold_angle)
        out.append(np.stack([i[hit], j[hit]], axis=1))
    pairs = np.concatenate(out)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def faces_intersecting(V, F, query, against, tol=None, *, fold_angle=FOLD_ANGLE, weld=True):
    """Faces of `query` that intersect at least one other face of `against`.

    Parameters are as for :func:`intersecting_pairs`.

    Returns
    -------
    faces : (k,) int64
        Sorted unique face indices into `F`.
    """
    pairs = intersecting_pairs(V, F, query, against, tol, fold_angle=fold_angle, weld=weld)
    # a pair of two faces that are both in both sets is listed once, either way round
    flipped = pairs[np.isin(pairs[:, 1], query) & np.isin(pairs[:, 0], against), 1]
    return np.unique(np.concatenate([pairs[:, 0], flipped]))


def _candidates(Tq, Ta, tol):
    """Yield chunks of local index pairs (iq, ja) whose bounding boxes overlap.

    Dual-tree search on face centroids within the sum of the bounding-sphere
    radii.  A single search radius would be set by the largest face, so faces
    are binned by radius (factors of 4) and each pair of bins gets its own.
    """
    cq, ca = Tq.mean(1), Ta.mean(1)
    rq = np.linalg.norm(Tq - cq[:, None], axis=2).max(1)
    ra = np.linalg.norm(Ta - ca[:, None], axis=2).max(1)
    top = max(rq.max(), ra.max(), np.finfo(float).tiny)
    bin_q, bin_a = (np.clip(np.floor(np.log(np.maximum(r, 1e-300) / top) / np.log(4)), -15, 0)
                    for r in (rq, ra))
    lo_q, hi_q = Tq.min(1) - tol, Tq.max(1) + tol
    lo_a, hi_a = Ta.min(1), Ta.max(1)
    groups_a = [np.flatnonzero(bin_a == b) for b in np.unique(bin_a)]
    trees_a = [(ia, cKDTree(ca[ia]), ra[ia].max()) for ia in groups_a]
    for b in np.unique(bin_q):
        iq = np.flatnonzero(bin_q == b)
        tree_q = cKDTree(cq[iq])
        for ia, tree_a, ra_max in trees_a:
            near = tree_q.sparse_distance_matrix(
                tree_a, rq[iq].max() + ra_max + tol, output_type="ndarray")
            for s in range(0, len(near), CHUNK):
                i, j = iq[near["i"][s:s + CHUNK]], ia[near["j"][s:s + CHUNK]]
                keep = np.all((lo_q[i] <= hi_a[j]) & (lo_a[j] <= hi_q[i]), axis=1)
                yield i[keep], j[keep]


def _beyond_plane(T1, T2, tol):
    """T2 lies wholly more than `tol` to one side of T1's plane (so the two cannot meet).

    Moeller's early rejection: every contact the narrow test reports lies within `tol` of
    both faces, so a pair separated by one face's slab is settled without it. Degenerate
    T1 (no plane) never rejects.
    """
    n, deg = _unit_normal(T1, tol)
    d = np.einsum("kij,kj->ki", T2 - T1[:, :1], n)
    return ~deg & ((d > tol).all(axis=1) | (d < -tol).all(axis=1))


def _narrow(T1, T2, C1, C2, tol, fold_angle):
    """Exact test for (k, 3, 3) triangle pairs with (k, 3) canonical vertex ids."""
    eq = C1[:, :, None] == C2[:, None, :]
    sh1, sh2 = eq.any(2), eq.any(1)  # which corners of T1 / T2 are shared
    nsh = np.minimum(sh1.sum(1), sh2.sum(1))  # min() keeps repeated ids from double counting
    n1, deg1 = _unit_normal(T1, tol)
    n2, deg2 = _unit_normal(T2, tol)
    good = ~deg1 & ~deg2
    hit = (nsh >= 3) & good
    e = (nsh == 2) & good
    if e.any():
        hit[e] = _folded(T1[e], T2[e], sh1[e], sh2[e], fold_angle)
    g = nsh <= 1
    if g.any():
        one = nsh[g] == 1
        S = T1[g][np.arange(one.size), np.argmax(sh1[g], axis=1)]  # only used where `one`
        hit[g] = _edges_meet(T1[g], T2[g], n2[g], sh1[g], deg1[g], deg2[g], one, S, tol) | (
            _edges_meet(T2[g], T1[g], n1[g], sh2[g], deg2[g], deg1[g], one, S, tol))
    return hit


def _folded(T1, T2, sh1, sh2, fold_angle):
    """Opening angle around the shared edge is below `fold_angle`."""
    r = np.arange(len(T1))
    o1, o2 = np.argmin(sh1, axis=1), np.argmin(sh2, axis=1)  # unshared corners
    P, Q = T1[r, (o1 + 1) % 3], T1[r, (o1 + 2) % 3]
    e = _unit(Q - P)
    ua, ub = T1[r, o1] - P, T2[r, o2] - P
    ua -= e * _dot(ua, e)[:, None]
    ub -= e * _dot(ub, e)[:, None]
    # atan2 stays accurate near 0, where arccos of the cosine would not
    return np.arctan2(np.linalg.norm(cross_rows(ua, ub), axis=1), _dot(ua, ub)) < fold_angle


def _edges_meet(Ts, Tt, nt, shs, degs, degt, one, S, tol):
    """Some edge of `Ts` meets `Tt` (away from the shared vertex `S` where `one`)."""
    hit = np.zeros(len(Ts), bool)
    for k in range(3):
        incident = shs[:, k] | shs[:, (k + 1) % 3]
        # a degenerate face has no opposite edge worth the name: test all its edges
        use = ~degt & (~one | ~incident | degs)
        if not use.any():
            continue
        P0, P1 = Ts[use, k], Ts[use, (k + 1) % 3]
        o = one[use]
        # edges through S of a needle would graze the other face's inflated rim
        # near S for longer than tol, so test them against the exact triangle
        grow = np.where(o & degs[use], 0.0, tol)
        ok, t0, t1 = _clip(P0, P1, Tt[use], nt[use], tol, grow)
        far = np.maximum(np.linalg.norm(P0 + t0[:, None] * (P1 - P0) - S[use], axis=1),
                         np.linalg.norm(P0 + t1[:, None] * (P1 - P0) - S[use], axis=1)) > tol
        hit[use] |= ok & (far | ~o)
    return hit


def _clip(P0, P1, T, nh, slab, grow):
    """Clip segments P0-P1 to triangles T grown by `grow` and thickened by `slab`.

    Every constraint is linear along the segment, so Liang-Barsky clipping
    treats the crossing and the coplanar case alike.  Returns (ok, t0, t1),
    the parameter interval of the part inside.
    """
    d0, d1 = _dot(P0 - T[:, 0], nh), _dot(P1 - T[:, 0], nh)
    cons = [(slab - d0, slab - d1), (slab + d0, slab + d1)]
    for k in range(3):
        a, b, c = T[:, k], T[:, (k + 1) % 3], T[:, (k + 2) % 3]
        m = _unit(cross_rows(nh, b - a))  # in-plane inward normal of edge ab
        cons.append((_dot(P0 - a, m) + grow, _dot(P1 - a, m) + grow))
        # cap the corner at a; grown edge lines alone reach far out of sharp corners
        u = _unit(_unit(b - a) + _unit(c - a))
        cons.append((_dot(P0 - a, u) + grow, _dot(P1 - a, u) + grow))
    ok = np.ones(len(P0), bool)
    t0, t1 = np.zeros(len(P0)), np.ones(len(P0))
    for c0, c1 in cons:  # inside where c0 + t (c1 - c0) >= 0
        ok &= (c0 >= 0) | (c1 >= 0)
        den = c0 - c1
        t = c0 / np.where(den == 0, 1.0, den)
        t0 = np.where((c0 < 0) & (c1 >= 0), np.maximum(t0, t), t0)
        t1 = np.where((c0 >= 0) & (c1 < 0), np.minimum(t1, t), t1)
    return ok & (t0 <= t1), t0, t1


def _unit_normal(T, tol):
    """Unit normals (k, 3) and degeneracy flags (k,) of triangles (k, 3, 3)."""
    n = cross_rows(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    ln = np.linalg.norm(n, axis=1)
    longest = np.linalg.norm(T - T[:, [1, 2, 0]], axis=2).max(1)
    deg = ln <= tol * longest  # |n| = longest edge * smallest height
    return n / np.where(deg, 1.0, ln)[:, None], deg


def _unit(x):
    ln = np.linalg.norm(x, axis=1)
    return x / np.where(ln > 0, ln, 1.0)[:, None]


def _dot(x, y):
    return np.einsum("ij,ij->i", x, y)
