"""Simulated annealing of a boundary loop towards a plane (Brunton et al. 2009, Sec. 3.1).

The loop is moved vertex by vertex (Press et al., Numerical Recipes Sec. 10.9) to lower the
planarity energy E_PE (the angles between the normals n_i of consecutive vertex triples),
never letting two non-adjacent segments come closer than epsilon. :mod:`.unfolding` runs it,
projects the result and restarts it.

Readings of what Sec. 3.1 leaves open:

* **Move.** One annealing step moves one vertex p_j by ``u * max(eps, d_MD)`` along a unit
  direction (u uniform in [0, 1)), the paper's step bound. Vertices whose moves touch
  disjoint energy terms are moved as one vectorised batch (:func:`colour_classes`); because
  up to m / 4 vertices then move at once, each gets half that bound, which still keeps any
  two segments from passing through each other. ``step_bound='local'`` replaces the global
  d_MD by the clearance of the moved segments (>= d_MD, same guarantee). A move that would
  leave d_MD <= eps is rejected (the constraint d_MD > eps).
* **Energy.** d_PE(p_i) is the angle between the vectors n_i and n_{i+1}, in [0, pi], as
  written in the paper (a zero normal, three collinear vertices, gives angle 0).
* **Direction.** "Move each point along a direction within 10 degrees of the previous random
  direction" after an accepted improving step: every vertex remembers the direction of its
  last move; if that move was accepted and lowered E_PE, its next direction is drawn within a
  10 degree cone around it, otherwise uniformly on the sphere.
* **Schedule.** Metropolis rule: a move is kept with probability ``exp(-dE / (k T))``. The paper calls k < 1 the rate of
  cooling and T the start temperature; as in Press et al.'s schedule the temperature drops by
  the factor k after each stage, ``T <- k T``, a stage being one sweep (every vertex one move).
* **Stopping rule.** At the start of every stage the loop's projection is tested; a run ends
  as soon as it is simple (so a loop that already projects simply is accepted before any
  move: 0 steps), when k T < 1e-3 T_start (66 stages for k = 0.9) or after ``sa_steps`` moves.
  Running the schedule to the end regardless is worse: E_PE has no term keeping the loop's
  shape or edge lengths, and on the bunny scan's holes, whose projections are simple from the
  start, a full anneal diffused the loop into one whose projection self-intersects in most
  runs.

Why the annealing does not unfold a long wrapped loop (measured on the benchmark's torus hole,
m = 211, wrapped 255 degrees around the tube; its best-plane projection has 5 crossing
segment pairs): E_PE starts at 489 rad, almost all of it the zig-zag of the grid border (each
change of turning sign costs about pi), while the wrap itself costs about 2 pi whatever its
angle, so lowering E_PE first straightens the zig-zag and gives no pull towards unwrapping.
With the global step bound, d_MD random-walks down to ~1e-7 h within a few thousand moves
and every later move is that short (E_PE 489 -> 372 in 66 stages); with ``step_bound='local'``
E_PE falls to 72-85 after 655-1966 stages (cooling per sweep 0.9^(1/10) and 0.9^(1/30)),
but the loop stays non-planar (largest distance to the best plane 0.33-0.64 of its extent)
and its projection crosses itself more (190-300 segment pairs) than at the start. At a
temperature of 0.005 (no uphill moves) the outcome is the same, so it is not the schedule.
"""
from __future__ import annotations

import math

import numpy as np

from ...geometry.quality import cross_rows
from ...geometry.segments import nonadjacent_mask, segment_distance_matrix, segment_distance_rows
from ._anneal_kernels import apply_moves, propose_moves
from .linear_motion import linear_motion_is_simple, project_to_best_plane, projection_is_simple

__all__ = ["triple_normals", "planarity_terms", "planarity_energy", "colour_classes", "anneal_loop"]

TEMPERATURE_FLOOR = 1e-3  # a run ends when k T < TEMPERATURE_FLOOR * T_start
CONE_DEGREES = 10.0  # Sec. 3.1: next direction within 10 degrees of the previous one
TAN_CONE = float(np.tan(np.radians(CONE_DEGREES)))  # the cone's tilt factor, as _cone_directions computes it
NEAR_EDGES = 4.0  # exact segment distances within this many mean edge lengths, lower bounds beyond


def triple_normals(P):
    """n_i = (p_i - p_{i+1}) x (p_{i+2} - p_{i+1}) of Sec. 3.1, indices mod m, (m, 3)."""
    P = np.asarray(P, np.float64)
    P1, P2 = np.roll(P, -1, axis=0), np.roll(P, -2, axis=0)
    return cross_rows(P - P1, P2 - P1)


def planarity_terms(P):
    """d_PE(p_i) = angle(n_i, n_{i+1}) of Sec. 3.1, in radians, (m,).

    A zero normal (three collinear vertices) makes an angle of 0 (atan2(0, 0)).
    """
    N = triple_normals(P)
    N1 = np.roll(N, -1, axis=0)
    return np.arctan2(np.linalg.norm(cross_rows(N, N1), axis=1), np.einsum("ij,ij->i", N, N1))


def planarity_energy(P):
    """E_PE = sum_i d_PE(p_i) of Sec. 3.1 (O(m), vectorised)."""
    return float(planarity_terms(P).sum())


def colour_classes(m):
    """Vertex classes whose moves touch disjoint d_PE terms and non-adjacent segments.

    A move of p_j changes n_{j-2}, n_{j-1}, n_j and the terms d_PE(p_{j-3}) .. d_PE(p_j); two
    vertices at cyclic distance >= 4 share none of these, so their Metropolis decisions are
    independent and one class is processed as one vectorised batch, exactly as if its moves
    were made one after the other. Classes: j mod 4 over the first 4 floor(m / 4) vertices
    (the wrap-around gap is then >= 4 too), each remaining vertex alone.

    Returns
    -------
    list of (b,) int64
    """
    full = 4 * (m // 4)
    classes = [np.arange(c, full, 4) for c in range(4)] + [np.array([j]) for j in range(full, m)]
    return [c for c in classes if len(c)]


def _cross_normals(A, B, C):
    """n = (a - b) x (c - b) row-wise, (b, 3)."""
    return cross_rows(A - B, C - B)


def _angles(N1, N2):
    """Angle between row vectors (0 where one is zero), (b,).

    cross_rows and the row sum are np.cross and np.linalg.norm's arithmetic without their
    per-call overhead, which dominates on a colour class of a few dozen rows.
    """
    C = cross_rows(N1, N2)
    return np.arctan2(np.sqrt((C * C).sum(axis=1)), (N1 * N2).sum(axis=1))


def _cone_directions(prev, G, r):
    """Unit vectors within CONE_DEGREES of the unit rows of ``prev``: each tilted by
    atan(r tan(cone)) towards G's component orthogonal to it (G standard normal, r in [0, 1))."""
    w = G - (G * prev).sum(axis=1)[:, None] * prev
    wn = np.linalg.norm(w, axis=1)
    w = w / np.where(wn > 0, wn, 1.0)[:, None]
    d = prev + (r * np.tan(np.radians(CONE_DEGREES)))[:, None] * w
    return d / np.linalg.norm(d, axis=1)[:, None]


def anneal_loop(P, rng, k=0.9, temperature=0.5, eps=1e-5, sa_steps=5000, step_bound="global",
                stop_when_simple=True, on_move=None, compiled=True):
    """One simulated-annealing run lowering E_PE subject to d_MD > eps (Sec. 3.1).

    A move displaces one vertex; the moves of a colour class (:func:`colour_classes`) are
    proposed, tested (Metropolis) and applied together, which is equivalent to making them
    one after the other because they touch disjoint energy terms. The energy change of a
    move is computed from the four d_PE terms it touches (O(1) each); the constraint is
    checked with one numpy call for the distances of all moved segments to all segments.
    See the module docstring for the move length, the 10 degree direction rule, the
    schedule and the stopping rule.

    Parameters
    ----------
    P : (m, 3) float64
        Simple loop with d_MD > eps.
    rng : numpy.random.Generator
    k : float
        Boltzmann constant / cooling factor (paper: 0.9).
    temperature : float
        Start temperature (paper: 0.5), in radians of E_PE.
    eps : float
        Absolute distance threshold of the constraint d_MD > eps.
    sa_steps : int
        Maximum number of moves in the run.
    step_bound : {'global', 'local'}
        Bound of a move's length: the global d_MD or the clearance of the moved segments.
    stop_when_simple : bool
        End the run at the first temperature stage whose loop projects to a simple polygon.
    on_move : callable, optional
        Called as ``on_move(P)`` with the new loop after every accepted batch of moves (tests;
        runs the numpy steps).
    compiled : bool
        Make each colour class's moves by the compiled kernels (:mod:`._anneal_kernels`, the same
        loop to the last bit); False runs the numpy steps (the reference).

    Returns
    -------
    A : (m, 3) float64
        Annealed loop, still simple with d_MD > eps.
    stats : dict
        ``steps``, ``accepted``, ``stages``, ``energy_start``, ``energy_end``, ``d_md`` (the clearance
        at the end, exact where it is within the near distance the run measures exactly),
        ``simple`` (the run ended on a simple projection).
    """
    P = np.array(P, np.float64)
    m = len(P)
    if m < 4:
        return P, {"steps": 0, "accepted": 0, "stages": 0, "energy_start": 0.0, "energy_end": 0.0,
                   "d_md": math.inf, "simple": linear_motion_is_simple(project_to_best_plane(P)[0], eps)}
    mask = nonadjacent_mask(m)
    # Exact distances only below `near`: far pairs keep a lower bound, which is all a step
    # bound or the constraint needs.
    near = NEAR_EDGES * float(np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1).mean())
    N = triple_normals(P)
    T = _angles(N, np.roll(N, -1, axis=0))
    energy_start = float(T.sum())
    D = segment_distance_matrix(P, near)
    d_md = float(D.min())
    last_dir = np.zeros((m, 3))
    improving = np.zeros(m, bool)
    classes = colour_classes(m)
    kT = k * temperature
    kT_floor = TEMPERATURE_FLOOR * temperature
    steps = accepted = stages = 0
    simple = False
    while True:
        if stop_when_simple and projection_is_simple(P, mask, eps, near):
            simple = True
            break
        if steps >= sa_steps or kT < kT_floor:
            break
        for ci in rng.permutation(len(classes)).tolist():
            J = classes[ci][: max(sa_steps - steps, 0)]
            if len(J) == 0:
                break
            steps += len(J)
            if compiled and on_move is None:
                acc, d_md = _compiled_class(P, N, T, D, J, rng, improving, last_dir, d_md, mask, near, eps, kT,
                                            step_bound)
                accepted += int(acc.sum())
                continue
            q, U = _propose_moves(P, J, rng, improving, last_dir, D, d_md, eps, step_bound)
            jm = (J - 1) % m
            n_a, n_b, n_c, t0, t1, t2, t3, dE = _energy_change(P, N, T, J, q)
            with np.errstate(over="ignore"):
                acc = (dE <= 0.0) | (U[:, 2] < np.exp(-dE / kT))
            acc, trial, moved, rows = _keep_clearance(P, J, q, acc, mask, near, eps)
            improving[J] = acc & (dE < 0.0)
            if not acc.any():
                continue
            accepted += int(acc.sum())
            P = trial
            jm2, jm3 = (J - 2) % m, (J - 3) % m
            N[jm2[acc]], N[jm[acc]], N[J[acc]] = n_a[acc], n_b[acc], n_c[acc]
            T[jm3[acc]], T[jm2[acc]], T[jm[acc]], T[J[acc]] = t0[acc], t1[acc], t2[acc], t3[acc]
            D[moved, :] = rows
            D[:, moved] = rows.T
            d_md = float(D.min())
            if on_move is not None:
                on_move(P)
        stages += 1
        kT *= k
    return P, {"steps": steps, "accepted": accepted, "stages": stages, "energy_start": energy_start,
               "energy_end": planarity_energy(P), "d_md": d_md, "simple": simple}


def _compiled_class(P, N, T, D, J, rng, improving, last_dir, d_md, mask, near, eps, kT, step_bound):
    """One colour class's moves by the compiled kernels, the loop state (P, N, T, D) updated in place.

    The same random numbers in the same order as :func:`_propose_moves`, the same arithmetic
    (:mod:`._anneal_kernels`); arctan2 and exp stay numpy's, whose vectorised implementations
    differ from the C library's in the last bit.

    Returns
    -------
    acc : (b,) bool  the moves kept
    d_md : float  the clearance afterwards
    """
    m = len(P)
    G = rng.standard_normal((len(J), 3))
    U = rng.random((len(J), 3))
    q, normals, y, x = propose_moves(P, N, D, J, G, U, last_dir, improving, d_md, eps, step_bound == "local",
                                     TAN_CONE)
    angles = np.arctan2(y, x)
    dE = (angles[0] + angles[1] + angles[2] + angles[3]) - (T[(J - 3) % m] + T[(J - 2) % m] + T[(J - 1) % m] + T[J])
    with np.errstate(over="ignore"):
        acc = (dE <= 0.0) | (U[:, 2] < np.exp(-dE / kT))
    acc, new_d_md = apply_moves(P, N, T, D, J, q, normals, angles, acc, mask, near, eps)
    improving[J] = acc & (dE < 0.0)
    return acc, (d_md if new_d_md < 0.0 else float(new_d_md))


def _propose_moves(P, J, rng, improving, last_dir, D, d_md, eps, step_bound):
    """Moves of the vertices J of one colour class: new positions q and the uniforms U they used.

    Directions are uniform on the sphere, or within the 10 degree cone of the last direction
    for a vertex whose last move lowered the energy (``improving``); ``last_dir`` is updated.
    A move's length is uniform up to half the bound (global d_MD or the moved segments'
    clearance): moves of one class happen together, and half the bound keeps any two moving
    segments from meeting (their distance is >= d_MD and shrinks by less than two half steps).

    Returns
    -------
    q : (j, 3) float64
    U : (j, 3) float64  U[:, 0] the length, U[:, 1] the cone tilt, U[:, 2] the Metropolis draw
    """
    m = len(P)
    G = rng.standard_normal((len(J), 3))
    U = rng.random((len(J), 3))
    dirs = G / np.linalg.norm(G, axis=1)[:, None]
    cone = improving[J]
    if cone.any():
        dirs[cone] = _cone_directions(last_dir[J[cone]], G[cone], U[cone, 1])
    last_dir[J] = dirs
    jm = (J - 1) % m
    if step_bound == "global":
        clearance = np.full(len(J), d_md)
    else:
        clearance = np.minimum(D[jm].min(axis=1), D[J].min(axis=1))
    length = U[:, 0] * 0.5 * np.maximum(eps, clearance)
    return P[J] + length[:, None] * dirs, U


def _energy_change(P, N, T, J, q):
    """Change of E_PE when each vertex J[i] moves to q[i]: the four d_PE terms it touches (O(1) each).

    Returns the three new triple normals n_{j-2}, n_{j-1}, n_j, the four new angles t0..t3 and dE.
    """
    m = len(P)
    jm, jp = (J - 1) % m, (J + 1) % m
    jm2, jm3, jp2 = (J - 2) % m, (J - 3) % m, (J + 2) % m
    n_a = _cross_normals(P[jm2], P[jm], q)    # n_{j-2}
    n_b = _cross_normals(P[jm], q, P[jp])     # n_{j-1}
    n_c = _cross_normals(q, P[jp], P[jp2])    # n_j
    t0, t1 = _angles(N[jm3], n_a), _angles(n_a, n_b)
    t2, t3 = _angles(n_b, n_c), _angles(n_c, N[jp])
    dE = (t0 + t1 + t2 + t3) - (T[jm3] + T[jm2] + T[jm] + T[J])
    return n_a, n_b, n_c, t0, t1, t2, t3, dE


def _keep_clearance(P, J, q, acc, mask, near, eps):
    """The constraint d_MD > eps on the moved segments, all accepted moves of the class applied.

    Moves whose segments come too close are refused, up to three times; then every move of
    the class is refused.

    Returns
    -------
    acc : (j,) bool  the moves kept
    trial : (m, 3) float64 or None  the loop with them applied
    moved : (s,) int64  segments moved
    rows : (s, m) float64  their distances to every segment
    """
    m = len(P)
    jm = (J - 1) % m
    trial = moved = rows = None
    for _ in range(3):
        if not acc.any():
            break
        trial = P.copy()
        trial[J[acc]] = q[acc]
        ends = np.roll(trial, -1, axis=0)
        # Boolean marks over the loop: sorted unique segment indices without np.unique / np.isin.
        is_moved = np.zeros(m, bool)
        is_moved[jm[acc]] = is_moved[J[acc]] = True
        moved = np.flatnonzero(is_moved)
        rows = segment_distance_rows(trial[moved], ends[moved], trial, ends, mask[moved], near)
        bad = moved[rows.min(axis=1) <= eps]
        if len(bad) == 0:
            break
        is_bad = np.zeros(m, bool)
        is_bad[bad] = True
        acc &= ~(is_bad[J] | is_bad[jm])
    else:
        acc[:] = False
    return acc, trial, moved, rows
