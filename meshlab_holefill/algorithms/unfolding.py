"""Unfolding a boundary loop into a simple planar polygon (Brunton et al. 2009, Sec. 3.1).

The loop is moved vertex by vertex by simulated annealing (Press et al., Numerical Recipes
Sec. 10.9) to lower the planarity energy E_PE (the angles between the normals of consecutive
vertex triples), never letting two non-adjacent segments come closer than epsilon, then
projected to its best-fitting plane; the projection is accepted when the loop reaches it by a
linear motion without self-intersection, otherwise annealing restarts.

Readings of what Sec. 3.1 leaves open (each used by :func:`anneal_loop`):

* **Move.** One annealing step moves one vertex p_j by ``u * max(eps, c_j)`` along a unit
  direction (u uniform in [0, 1)). ``c_j`` is the paper's d_MD restricted to the pairs the
  move can change (the segments (p_{j-1}, p_j) and (p_j, p_{j+1}) against every segment not
  adjacent to them); it is >= the global d_MD and gives the paper's guarantee for a one-vertex
  move: the two moving segments travel less than their distance to every other segment, so
  the loop cannot pass through itself. ``step_bound='global'`` uses the global d_MD instead.
  A move that would leave d_MD <= eps is rejected (the constraint d_MD > eps).
* **Direction.** "After an accepted step the next random direction stays within 10 degrees
  of the previous one": every vertex remembers the direction of its last move; when that move
  was accepted and lowered E_PE, the vertex's next direction is drawn within a 10 degree cone
  around it, otherwise uniformly on the sphere.
* **Schedule.** Acceptance ``exp(-dE / (k T))`` (Metropolis). The paper calls k (< 1) the rate
  of cooling and T the start temperature; as in Press et al.'s example schedule the
  temperature is lowered by the factor k after each stage, ``T <- k T``, a stage being one
  sweep (m moves, every vertex once, in random order).
* **Stopping rule.** A run ends when k T has fallen below ``1e-3`` times the start temperature
  (66 stages for k = 0.9) or after ``sa_steps`` moves, whichever comes first.
* **Restart.** A failed projection restarts the annealing from the original loop with the
  next random numbers of the same generator (so a seed fixes the whole sequence).
* **Units.** epsilon is relative to the loop's mean edge length (the paper's 1e-5 is in
  model units), which makes the method scale invariant.
"""
from __future__ import annotations

import math

import numpy as np

from ..geometry.pca import fit_plane, plane_frame
from ..patch import HoleFillError

TEMPERATURE_FLOOR = 1e-3  # a run ends when k T < TEMPERATURE_FLOOR * T_start
CONE_DEGREES = 10.0  # Sec. 3.1: next direction within 10 degrees of the previous one


def segment_distances(A0, A1, B0, B1):
    """Exact distance between segments [A0, A1] and [B0, B1], elementwise with broadcasting.

    Closest points by the dot-product formulation (Ladd and Kavraki, cited in Sec. 3.1;
    Ericson, Real-Time Collision Detection 5.1.9): the unconstrained parameters of the
    closest points of the two carrier lines are clamped to the segments in the right order.
    Degenerate (point) segments are handled.

    Parameters
    ----------
    A0, A1, B0, B1 : (..., d) float64
        Segment end points, d = 2 or 3, broadcast against each other.

    Returns
    -------
    dist : (...) float64
    """
    d1 = A1 - A0
    d2 = B1 - B0
    r = A0 - B0
    a = np.einsum("...i,...i->...", d1, d1)
    e = np.einsum("...i,...i->...", d2, d2)
    f = np.einsum("...i,...i->...", d2, r)
    c = np.einsum("...i,...i->...", d1, r)
    b = np.einsum("...i,...i->...", d1, d2)
    denom = a * e - b * b
    tiny = 1e-300
    with np.errstate(divide="ignore", invalid="ignore"):
        # Parallel (denom 0) or point segments: any s works, take 0.
        s = np.where(denom > 1e-14 * a * e + tiny, np.clip((b * f - c * e) / np.where(denom > 0, denom, 1.0), 0.0, 1.0), 0.0)
        t = np.where(e > tiny, (b * s + f) / np.where(e > tiny, e, 1.0), 0.0)
        s_lo = np.where(a > tiny, np.clip(-c / np.where(a > tiny, a, 1.0), 0.0, 1.0), 0.0)
        s_hi = np.where(a > tiny, np.clip((b - c) / np.where(a > tiny, a, 1.0), 0.0, 1.0), 0.0)
    s = np.where(t < 0.0, s_lo, np.where(t > 1.0, s_hi, s))
    t = np.clip(t, 0.0, 1.0)
    diff = r + d1 * s[..., None] - d2 * t[..., None]
    return np.sqrt(np.einsum("...i,...i->...", diff, diff))


def nonadjacent_mask(m):
    """Pairs of loop segments that share no vertex.

    Segment i joins p_i and p_{(i+1) mod m}.

    Returns
    -------
    mask : (m, m) bool, symmetric, False on the diagonal and for consecutive segments.
    """
    i = np.arange(m)
    gap = np.abs(i[:, None] - i[None, :])
    return (gap > 1) & (gap < m - 1)


def segment_distance_matrix(P):
    """Distances between all pairs of non-adjacent loop segments, in one numpy call.

    Parameters
    ----------
    P : (m, d) float64  loop vertices

    Returns
    -------
    D : (m, m) float64
        D[i, j] = distance between segments i and j; +inf for adjacent pairs and i == j.
    """
    P = np.asarray(P, np.float64)
    m = len(P)
    Q = np.roll(P, -1, axis=0)
    D = segment_distances(P[:, None, :], Q[:, None, :], P[None, :, :], Q[None, :, :])
    D[~nonadjacent_mask(m)] = np.inf
    return D


def min_segment_distance(P):
    """d_MD of Sec. 3.1: the smallest distance between two non-adjacent loop segments.

    Parameters
    ----------
    P : (m, d) float64

    Returns
    -------
    float  (+inf for m <= 3, where every pair of segments is adjacent)
    """
    if len(P) <= 3:
        return math.inf
    return float(segment_distance_matrix(P).min())


def triple_normals(P):
    """n_i = (p_i - p_{i+1}) x (p_{i+2} - p_{i+1}) of Sec. 3.1, indices mod m, (m, 3)."""
    P = np.asarray(P, np.float64)
    P1, P2 = np.roll(P, -1, axis=0), np.roll(P, -2, axis=0)
    return np.cross(P - P1, P2 - P1)


def planarity_terms(P):
    """d_PE(p_i) = angle(n_i, n_{i+1}) of Sec. 3.1, in radians, (m,).

    A zero normal (three collinear vertices) makes an angle of 0 (atan2(0, 0)).
    """
    N = triple_normals(P)
    N1 = np.roll(N, -1, axis=0)
    return np.arctan2(np.linalg.norm(np.cross(N, N1), axis=1), np.einsum("ij,ij->i", N, N1))


def planarity_energy(P):
    """E_PE = sum_i d_PE(p_i) of Sec. 3.1 (O(m), vectorised)."""
    return float(planarity_terms(P).sum())


# --- pure-Python kernels of one annealing step (a handful of 3-vectors: faster than numpy) ---

def _normal(a, b, c):
    ux, uy, uz = a[0] - b[0], a[1] - b[1], a[2] - b[2]
    vx, vy, vz = c[0] - b[0], c[1] - b[1], c[2] - b[2]
    return (uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx)


def _angle(n, q):
    cx = n[1] * q[2] - n[2] * q[1]
    cy = n[2] * q[0] - n[0] * q[2]
    cz = n[0] * q[1] - n[1] * q[0]
    return math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), n[0] * q[0] + n[1] * q[1] + n[2] * q[2])


def _cone_direction(prev, g, r):
    """Unit vector within CONE_DEGREES of unit ``prev``: tilt by atan(r tan(cone)) towards g's
    component orthogonal to prev (g a standard normal 3-vector, r in [0, 1))."""
    dot = g[0] * prev[0] + g[1] * prev[1] + g[2] * prev[2]
    wx, wy, wz = g[0] - dot * prev[0], g[1] - dot * prev[1], g[2] - dot * prev[2]
    wn = math.sqrt(wx * wx + wy * wy + wz * wz)
    if wn == 0.0:
        return prev
    scale = r * math.tan(math.radians(CONE_DEGREES)) / wn
    dx, dy, dz = prev[0] + scale * wx, prev[1] + scale * wy, prev[2] + scale * wz
    dn = math.sqrt(dx * dx + dy * dy + dz * dz)
    return (dx / dn, dy / dn, dz / dn)


def anneal_loop(P, rng, k=0.9, temperature=0.5, eps=1e-5, sa_steps=20000, step_bound="local"):
    """One simulated-annealing run lowering E_PE subject to d_MD > eps (Sec. 3.1).

    See the module docstring for the move, the 10 degree direction rule, the schedule and
    the stopping rule. The energy change of a move is computed from the four d_PE terms it
    touches (O(1)); the new distances of the two moved segments to all others are one numpy
    call (O(m)), evaluated only for moves the Metropolis test accepts; the distance matrix
    is updated in those two rows and columns.

    Parameters
    ----------
    P : (m, 3) float64
        Simple loop with d_MD > eps, m >= 4.
    rng : numpy.random.Generator
    k : float
        Boltzmann constant / cooling factor (paper: 0.9).
    temperature : float
        Start temperature (paper: 0.5), in radians of E_PE.
    eps : float
        Absolute distance threshold of the constraint d_MD > eps.
    sa_steps : int
        Maximum number of moves in the run.
    step_bound : {'local', 'global'}
        Bound of a move's length: the moved segments' clearance or the global d_MD.

    Returns
    -------
    Q : (m, 3) float64
        Annealed loop, still simple with d_MD > eps.
    stats : dict
        ``steps``, ``accepted``, ``stages``, ``energy_start``, ``energy_end``, ``d_md``.
    """
    P = np.array(P, np.float64)
    m = len(P)
    if m < 4:
        return P, {"steps": 0, "accepted": 0, "stages": 0, "energy_start": 0.0, "energy_end": 0.0,
                   "d_md": math.inf}
    pts = [tuple(p) for p in P.tolist()]
    normals = [_normal(pts[i], pts[(i + 1) % m], pts[(i + 2) % m]) for i in range(m)]
    terms = [_angle(normals[i], normals[(i + 1) % m]) for i in range(m)]
    energy = energy_start = math.fsum(terms)
    D = segment_distance_matrix(P)
    d_md = float(D.min())
    mask = nonadjacent_mask(m)
    Q = np.roll(P, -1, axis=0)  # Q[i] = end point of segment i (kept in sync with P)
    last_dir = [None] * m
    improving = [False] * m
    kT = k * temperature
    kT_floor = TEMPERATURE_FLOOR * temperature
    steps = accepted = stages = 0
    batch = max(m, 1)
    while steps < sa_steps and kT >= kT_floor:
        order = rng.permutation(m).tolist()
        G = rng.standard_normal((batch, 3)).tolist()
        U = rng.random((batch, 3)).tolist()
        for s, j in enumerate(order):
            if steps >= sa_steps:
                break
            steps += 1
            g, (u_len, u_cone, u_acc) = G[s], U[s]
            prev = last_dir[j]
            if prev is not None and improving[j]:
                d = _cone_direction(prev, g, u_cone)
            else:
                gn = math.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) or 1.0
                d = (g[0] / gn, g[1] / gn, g[2] / gn)
            last_dir[j] = d
            jm, jp = (j - 1) % m, (j + 1) % m
            clearance = d_md if step_bound == "global" else min(D[jm].min(), D[j].min())
            length = u_len * max(eps, clearance)
            p = pts[j]
            q = (p[0] + length * d[0], p[1] + length * d[1], p[2] + length * d[2])
            jm2, jm3, jp2 = (j - 2) % m, (j - 3) % m, (j + 2) % m
            n_a = _normal(pts[jm2], pts[jm], q)   # n_{j-2}
            n_b = _normal(pts[jm], q, pts[jp])    # n_{j-1}
            n_c = _normal(q, pts[jp], pts[jp2])   # n_j
            t0 = _angle(normals[jm3], n_a)
            t1 = _angle(n_a, n_b)
            t2 = _angle(n_b, n_c)
            t3 = _angle(n_c, normals[jp])
            dE = (t0 + t1 + t2 + t3) - (terms[jm3] + terms[jm2] + terms[jm] + terms[j])
            if dE > 0.0 and u_acc >= math.exp(-dE / kT):
                improving[j] = False
                continue
            # Constraint d_MD > eps: distances of the two moved segments to all segments.
            qa = np.array(q)
            A0 = np.array([pts[jm], q])
            A1 = np.array([q, pts[jp]])
            rows = segment_distances(A0[:, None, :], A1[:, None, :], P[None, :, :], Q[None, :, :])
            rows[0, ~mask[jm]] = np.inf
            rows[1, ~mask[j]] = np.inf
            if rows.min() <= eps:
                improving[j] = False
                continue
            improving[j] = dE < 0.0
            accepted += 1
            pts[j] = q
            P[j] = qa
            Q[jm] = qa
            normals[jm2], normals[jm], normals[j] = n_a, n_b, n_c
            terms[jm3], terms[jm2], terms[jm], terms[j] = t0, t1, t2, t3
            energy += dE
            D[jm, :] = rows[0]
            D[:, jm] = rows[0]
            D[j, :] = rows[1]
            D[:, j] = rows[1]
            if step_bound == "global":
                d_md = float(D.min())
        stages += 1
        kT *= k
    energy_end = float(planarity_energy(P))
    return P, {"steps": steps, "accepted": accepted, "stages": stages, "energy_start": energy_start,
               "energy_end": energy_end, "d_md": float(min_segment_distance(P))}


def project_to_best_plane(P):
    """Orthogonal projection of a loop onto its best-fitting (least-squares) plane (Sec. 3.1).

    Parameters
    ----------
    P : (m, 3) float64

    Returns
    -------
    Q : (m, 2) float64
        Coordinates in an orthonormal frame (u, v) of the plane, (u, v, normal) right-handed.
    projected : (m, 3) float64
        The projected points in space.
    normal : (3,) float64
    """
    P = np.asarray(P, np.float64)
    centroid, normal, _, _ = fit_plane(P)
    u, v = plane_frame(normal)
    rel = P - centroid
    Q = np.stack([rel @ u, rel @ v], axis=1)
    projected = P - np.outer(rel @ normal, normal)
    return Q, projected, normal


def linear_motion_is_simple(Q, eps):
    """Whether a simple loop reaches its projection by linear motion without self-intersection.

    Sec. 3.1 accepts the unfolding only if the annealed loop can be moved to its projection
    onto its best-fitting plane by linear motions of the vertices without self-intersection.
    This test is exact and reduces to the end point: under the motion p(t) = p + t (proj(p) -
    p) every point keeps its in-plane coordinates and its height above the plane is scaled by
    (1 - t). Two points of two segments coincide at time t < 1 only if they have the same
    in-plane position and equal heights, and heights scaled by the common factor (1 - t) are
    equal exactly when they were equal at t = 0, where the loop is simple (d_MD > eps). So the
    motion is free of self-intersection iff the projected polygon is simple; it is required to
    keep the clearance d_MD > eps, like the annealing.

    Parameters
    ----------
    Q : (m, 2) float64
        Projected polygon.
    eps : float
        Absolute clearance.

    Returns
    -------
    bool
    """
    Q = np.asarray(Q, np.float64)
    if len(Q) == 3:
        a, b, c = Q
        return abs(float((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))) > eps * eps
    return min_segment_distance(Q) > eps


def unfold_loop(P, rng, k=0.9, temperature=0.5, epsilon=1e-5, max_restarts=100, sa_steps=20000,
                step_bound="local"):
    """Unfold a boundary loop into a simple planar polygon (Sec. 3.1).

    Anneal (:func:`anneal_loop`), project to the best-fitting plane
    (:func:`project_to_best_plane`) and accept if the linear motion to the projection keeps
    the loop simple (:func:`linear_motion_is_simple`); otherwise restart from the original
    loop, at most ``max_restarts`` annealing runs in all.

    Parameters
    ----------
    P : (m, 3) float64
        Boundary loop in order, m >= 3.
    rng : numpy.random.Generator
    k, temperature, sa_steps, step_bound : see :func:`anneal_loop`
    epsilon : float
        Clearance threshold relative to the loop's mean edge length.
    max_restarts : int
        Maximum number of annealing runs (paper: 100).

    Returns
    -------
    Q : (m, 2) float64
        Simple planar polygon, vertex i the image of loop vertex i.
    annealed : (m, 3) float64
        The annealed loop whose projection Q is.
    info : dict
        ``restarts`` (runs - 1), ``sa_steps`` (moves over all runs), ``accepted_steps``,
        ``energy_start``, ``energy_end`` (E_PE of the accepted run), ``d_md_start``.

    Raises
    ------
    HoleFillError
        For a degenerate loop (non-finite, touching itself, zero area) or when no run
        gives a simple projection (e.g. a knotted loop).
    """
    P = np.asarray(P, np.float64)
    m = len(P)
    if m < 3:
        raise HoleFillError("a boundary loop needs at least 3 vertices")
    if not np.all(np.isfinite(P)):
        raise HoleFillError("boundary loop has non-finite coordinates")
    h = float(np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1).mean())
    if not h > 0:
        raise HoleFillError("boundary loop has zero length")
    eps = epsilon * h
    d_md = min_segment_distance(P)
    if d_md <= eps:
        raise HoleFillError(f"boundary loop touches itself (d_MD = {d_md:.3g} <= epsilon = {eps:.3g}); "
                            "curve unfolding needs a simple loop")
    total_steps = total_accepted = 0
    for run in range(max(int(max_restarts), 1)):
        annealed, stats = anneal_loop(P, rng, k=k, temperature=temperature, eps=eps,
                                      sa_steps=sa_steps, step_bound=step_bound)
        total_steps += stats["steps"]
        total_accepted += stats["accepted"]
        Q, _, _ = project_to_best_plane(annealed)
        if linear_motion_is_simple(Q, eps):
            return Q, annealed, {"restarts": run, "sa_steps": total_steps, "accepted_steps": total_accepted,
                                 "energy_start": stats["energy_start"], "energy_end": stats["energy_end"],
                                 "d_md_start": d_md}
    raise HoleFillError(f"curve unfolding failed: no annealing run out of {max(int(max_restarts), 1)} gave a "
                        "loop whose projection to its best-fitting plane is simple "
                        "(knotted or strongly twisted boundary)")
