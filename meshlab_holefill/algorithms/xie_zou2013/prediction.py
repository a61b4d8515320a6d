"""HPDE step 5 (Xie and Zou 2013, Sec. 4.5 and 4.8): prediction points on each section plane.

Each section plane is rotated to the xy-plane (P_1 at the origin, P_2 on the x-axis); two
circular arcs from the end tangents bound the points; x-coordinates average equal-distance
points of the two arcs (Eq. 12-13); y-coordinates minimise the variation of the turning
angles (Eq. 14) by DE/rand/1/bin, planes of similar m in one batched run.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import sections
from ._de_kernels import PAIRWISE_BLOCK, changed_masked_row_sums, masked_row_sums, turning_terms
from .de_rand_1_bin import de_rand_1_bin, reflect_into_bounds

__all__ = ["arc_points", "arc_height", "circle_start_angle", "forward_tangents", "prediction_counts",
           "SectionProblem", "section_problems", "turning_angles", "angle_variation", "AngleVariation",
           "initial_population",
           "subset", "predict_y", "predicted_points", "predict_points", "NUM_ITER"]

# Generations of the DE (NumIter, Sec. 4.8): the paper gives no value; see predict_y.
NUM_ITER = 20


def arc_points(theta, length, s):
    """Points on the circular arc from (0, 0) to (length, 0) leaving (0, 0) at angle theta.

    The arc is symmetric about x = length / 2 (tangent angle theta at the start, -theta at
    the end); s in [0, 1] is the fraction of arc length, so equal steps in s give points at
    equal distances (Eq. 13). |theta| <= pi / 2 keeps x monotone in s.

    Parameters
    ----------
    theta : (...,) float64
    length : (...,) float64
    s : (..., m) float64

    Returns
    -------
    x, y : (..., m) float64
    """
    th = np.asarray(theta, np.float64)[..., None]
    L = np.asarray(length, np.float64)[..., None]
    a = th * (1.0 - 2.0 * s)
    small = np.abs(th) < 1e-6
    sin_th = np.where(small, 1.0, np.sin(th))
    x = np.where(small, L * s, 0.5 * L * (1.0 - np.sin(a) / sin_th))
    y = np.where(small, L * th * 2.0 * s * (1.0 - s), 0.5 * L * (np.cos(a) - np.cos(th)) / sin_th)
    return x, y


def arc_height(theta, length, x):
    """y of the arc of :func:`arc_points` above abscissa x in [0, length] (the points L_i, U_i)."""
    th = np.asarray(theta, np.float64)[..., None]
    L = np.asarray(length, np.float64)[..., None]
    small = np.abs(th) < 1e-6
    sin_th = np.where(small, 1.0, np.sin(th))
    r = np.clip(1.0 - 2.0 * np.asarray(x) / L, -1.0, 1.0)
    a = np.arcsin(np.clip(np.sin(th) * r, -1.0, 1.0))
    y = 0.5 * L * (np.cos(a) - np.cos(th)) / sin_th
    xs = np.clip(np.asarray(x) / L, 0.0, 1.0)
    return np.where(small, L * th * 2.0 * xs * (1.0 - xs), y)


def circle_start_angle(ap, length):
    """Start angle at P_1 = (0, 0) of the circle through AP = ``ap``, P_1 and P_2 = (length, 0).

    The circle's centre is (length / 2, c) with c = (|AP|^2 - AP_x length) / (2 AP_y); the arc
    from P_1 to P_2 leaves P_1 at angle theta with tan(theta) = -length / (2 c).

    Parameters
    ----------
    ap : (p, 2) float64  AP in the plane frame (behind P_1: AP_x < 0 for a forward tangent)
    length : (p,) float64

    Returns
    -------
    (p,) float64 in (-pi, pi]; 0 when AP, P_1, P_2 are collinear.
    """
    ap = np.asarray(ap, np.float64)
    D = np.einsum("ij,ij->i", ap, ap) - ap[:, 0] * length
    return np.arctan2(-length * ap[:, 1], D)


def forward_tangents(P1, P2, TV1, TV2):
    """Pairs whose end tangents both point along P_1 -> P_2, (p,) bool.

    Reading: the arcs of Fig. 3 exist only when TV_1 leaves P_1 towards P_2's side and TV_2
    arrives at P_2 from P_1's side (|angle| < 90 degrees in the plane frame). A pair failing
    this is dropped; on zigzag boundaries it happens to short chords near the ends of the
    symmetry axis, which pass the I_c test with the smoothed boundary direction but meet a
    border triangle edge almost along the chord.
    """
    chord = P2 - P1
    return (np.einsum("ij,ij->i", TV1, chord) > 0) & (np.einsum("ij,ij->i", TV2, chord) > 0)


def prediction_counts(lengths, edge_length):
    """Numbers of prediction points per pair (Sec. 4.5, Eq. 15).

    M = floor(MaxLen / EdgeLen) + 1 and m = floor(Len / MaxLen * M) + 1.

    Returns
    -------
    m : (p,) int64
    M : int
    """
    lengths = np.asarray(lengths, np.float64)
    max_len = float(lengths.max())
    M = int(np.floor(max_len / edge_length)) + 1
    return (np.floor(lengths / max_len * M) + 1).astype(np.int64), M


@dataclass
class SectionProblem:
    """The 2D data of Eq. 12-16 for a batch of section planes (padded to m_max points).

    Attributes
    ----------
    length : (p,) float64  |P_2 - P_1|, P_1 = (0, 0), P_2 = (length, 0)
    tv1, tv2 : (p, 2) float64  unit end tangents TV_1, TV_2 in the plane frame
    theta_lower, theta_upper : (p,) float64  start angles of L_arc and U_arc
    m : (p,) int64
    x : (p, m_max) float64  PP_{i,1} (Eq. 12), padding 0
    lower, upper : (p, m_max) float64  bounds of PP_{i,2} (Eq. 14), padding 0
    y_init : (p, m_max) float64  Eq. 16
    """

    length: np.ndarray
    tv1: np.ndarray
    tv2: np.ndarray
    theta_lower: np.ndarray
    theta_upper: np.ndarray
    m: np.ndarray
    x: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    y_init: np.ndarray


def section_problems(P1, P2, TV1, TV2, Nv, m, max_tangent_angle=np.pi / 2, tangent="secant"):
    """Rotate each section plane to the xy-plane and set up Eq. 12-16 (Sec. 4.5).

    Frame: origin P_1, x along P_2 - P_1, y = Nv x x. TV_1 = P_1 - AP_i (into the hole at
    P_1), TV_2 = AP_{n-i+1} - P_2 (out of the hole at P_2). L_arc is the arc through P_1, P_2
    tangent to TV_1 at P_1, U_arc the one tangent to TV_2 at P_2. Reading: their start angles
    are clipped to +-``max_tangent_angle`` (pi/2, a half circle) so that each vertical line
    x = PP_{i,1} meets each arc once, as Fig. 3 draws them.

    Parameters
    ----------
    P1, P2, TV1, TV2, Nv : (p, 3) float64
    m : (p,) int64  prediction points per plane (Eq. 15)

    Returns
    -------
    SectionProblem
    frames : (p, 3, 3) float64  rows: origin-free axes ex, ey, Nv (3D = P1 + x ex + y ey)
    """
    ex = P2 - P1
    length = np.linalg.norm(ex, axis=1)
    ex = ex / length[:, None]
    ey = np.cross(Nv, ex)
    ey /= np.maximum(np.linalg.norm(ey, axis=1, keepdims=True), 1e-300)
    tv1 = np.stack([np.einsum("ij,ij->i", TV1, ex), np.einsum("ij,ij->i", TV1, ey)], axis=1)
    tv2 = np.stack([np.einsum("ij,ij->i", TV2, ex), np.einsum("ij,ij->i", TV2, ey)], axis=1)
    if tangent == "circle":
        th_l = circle_start_angle(-tv1, length)
        # Mirror x -> length - x: AP_{n-i+1} = P_2 + TV_2 lies behind P_2 seen from P_1's side.
        th_u = circle_start_angle(np.stack([-tv2[:, 0], tv2[:, 1]], axis=1), length)
    tv1 /= np.maximum(np.linalg.norm(tv1, axis=1, keepdims=True), 1e-300)
    tv2 /= np.maximum(np.linalg.norm(tv2, axis=1, keepdims=True), 1e-300)
    if tangent != "circle":
        th_l = np.arctan2(tv1[:, 1], tv1[:, 0])
        # The arc tangent to TV_2 at P_2 leaves P_1 at minus the angle of TV_2 (symmetry).
        th_u = -np.arctan2(tv2[:, 1], tv2[:, 0])
    th_l = np.clip(th_l, -max_tangent_angle, max_tangent_angle)
    th_u = np.clip(th_u, -max_tangent_angle, max_tangent_angle)
    m = np.asarray(m, np.int64)
    m_max = int(m.max()) if len(m) else 0
    i = np.arange(1, m_max + 1)[None, :]
    valid = i <= m[:, None]
    s = np.where(valid, i / (m[:, None] + 1.0), 0.0)
    xl, _ = arc_points(th_l, length, s)
    xu, _ = arc_points(th_u, length, s)
    x = np.where(valid, 0.5 * (xl + xu), 0.0)  # Eq. 12
    yl = arc_height(th_l, length, x)
    yu = arc_height(th_u, length, x)
    y_init = np.where(valid, yl + (yu - yl) * s, 0.0)  # Eq. 16: i / (m + 1)
    lower = np.where(valid, np.minimum(yl, yu), 0.0)
    upper = np.where(valid, np.maximum(yl, yu), 0.0)
    frames = np.stack([ex, ey, Nv], axis=1)
    return SectionProblem(length, tv1, tv2, th_l, th_u, m, x, lower, upper, y_init), frames


def _chain_constants(problem):
    """Parts of the chain segments S_0..S_{m+2} that do not depend on y (cached on the problem).

    Returns
    -------
    seg_x : (p, m_max + 3) float64  x of TV_1, of the m + 1 chord segments, of TV_2, then 0
    seg_y_add : (p, m_max + 3) float64  y of TV_1 at 0 and of TV_2 at m + 2, else 0
    valid : (p, m_max + 2) float64  1 for the m + 2 real turning angles
    """
    cached = getattr(problem, "_chain", None)
    if cached is not None:
        return cached
    p, m_max = problem.x.shape
    m = problem.m[:, None]
    cols = np.arange(m_max + 3)[None, :]
    chain_x = np.concatenate([np.zeros((p, 1)), problem.x, np.zeros((p, 1))], axis=1)
    chain_x = np.where(np.arange(m_max + 2)[None, :] > m, problem.length[:, None], chain_x)
    seg_x = np.concatenate([problem.tv1[:, 0:1], np.diff(chain_x, axis=1), np.zeros((p, 1))], axis=1)
    seg_x = np.where(cols == m + 2, problem.tv2[:, 0:1], seg_x)
    seg_y_add = np.where(cols == 0, problem.tv1[:, 1:2], 0.0) + np.where(cols == m + 2, problem.tv2[:, 1:2], 0.0)
    valid = (np.arange(m_max + 2)[None, :] <= m + 1).astype(np.float64)
    problem._chain = (seg_x, seg_y_add, valid)
    return problem._chain


def turning_angles(problem, Y):
    """Turning angles along AP_i, P_1, PP_1..PP_m, P_2, AP_{n-i+1} (the quantities of Eq. 14).

    Reading of Eq. 14: the "connection lines" are the segments of that chain, the first and
    last being the end tangents TV_1, TV_2; its m + 2 signed turning angles are
    beta_0 = <TV_1, PP_1 - P_1>, beta_i = <PP_i - PP_{i-1}, PP_{i+1} - PP_i> and
    beta_{m+1} = <P_2 - PP_m, TV_2>. With the tangents included the problem is well posed
    even for m = 1 (one interior angle alone has no variation).

    Parameters
    ----------
    problem : SectionProblem  (p planes)
    Y : (p, N, m_max) float64  candidate y-coordinates

    Returns
    -------
    beta : (p, N, m_max + 2) float64
    valid : (p, 1, m_max + 2) float64  1 for the m + 2 real angles of each plane
    """
    p, N, m_max = Y.shape
    seg_x, seg_y_add, valid = _chain_constants(problem)
    # y of the chain segments (differences of (0, Y, 0); Y is 0 beyond m, fixed bounds) and the
    # cross and dot products of consecutive segments, compiled; arctan2 stays numpy's.
    cross, dot = turning_terms(np.ascontiguousarray(Y, np.float64), seg_x, seg_y_add)
    beta = np.arctan2(cross, dot)
    valid = valid[:, None, :]
    return beta, valid


def angle_variation(problem, Y):
    """Objective of Eq. 14: sum of squared deviations of the turning angles from their mean.

    Zero exactly when all intersection angles of consecutive connection lines are equal
    (the second condition of Sec. 4.5).

    Returns
    -------
    f : (p, N) float64
    """
    beta, valid = turning_angles(problem, Y)
    beta = beta * valid
    count = valid.sum(axis=2)
    total = beta.sum(axis=2)
    return np.maximum(np.einsum("pnk,pnk->pn", beta, beta) - total * total / count, 0.0)


class AngleVariation:
    """The objective of Eq. 14 on a SectionProblem, ``f = AngleVariation(problem)(Y)``.

    Also exposes its parts to the fused DE generation of :func:`.de_rand_1_bin.de_rand_1_bin`:
    ``turning_chain`` (the chain constants of :func:`turning_angles` and the number of angles
    per plane), :meth:`angle_sums` and :meth:`changed_angle_sums`;
    :func:`_de_kernels.select_reflect_terms` finishes ``np.maximum(square_sum - total * total / count, 0)``
    as :func:`angle_variation` does.
    """

    def __init__(self, problem):
        self.problem = problem
        seg_x, seg_y_add, valid = _chain_constants(problem)
        self.valid = np.ascontiguousarray(valid)[:, None, :]
        self.turning_chain = (seg_x, seg_y_add, np.ascontiguousarray(self.valid.sum(axis=2)[:, 0]))

    def __call__(self, Y):
        return angle_variation(self.problem, Y)

    def angle_sums(self, beta):
        """(sum of squared angles, sum of angles), (p, N) each, of turning angles beta (p, N, K).

        beta = arctan2 of the turning terms of :func:`turning_angles`, masked here in place to
        the valid ones. Masking is idempotent (a masked angle times its 0 or 1 is itself, bit for bit), so
        beta may hold angles masked before.
        """
        if beta.shape[2] <= PAIRWISE_BLOCK:
            total = masked_row_sums(beta, self.valid[:, 0, :])  # beta * valid, beta.sum(axis=2): numpy's order
        else:
            beta *= self.valid
            total = beta.sum(axis=2)
        return np.einsum("pnk,pnk->pn", beta, beta), total

    def changed_angle_sums(self, parent, changed, beta, out):
        """:meth:`angle_sums` of out = parent (masked angles) with out.flat[changed] = beta, written into out.

        The trial angles of a fused DE generation: its parents' but at the turning terms its
        crossover changed (ascending flat indices, their arctan2 in beta).
        """
        if out.shape[2] <= PAIRWISE_BLOCK:
            total = changed_masked_row_sums(parent, changed, beta, self.valid[:, 0, :], out)  # one pass, numpy's order
            return np.einsum("pnk,pnk->pn", out, out), total
        np.copyto(out, parent)
        out.ravel()[changed] = beta
        return self.angle_sums(out)


def initial_population(problem, pop_size, rng, spread=0.5):
    """Initial DE population around the vector of Eq. 16 (Sec. 4.8).

    Reading of "randomly initialized around": individual 0 is the Eq. 16 vector itself, the
    others add uniform noise of +-spread/2 times the bound width (U_i2 - L_i2), reflected into
    the bounds (Eq. 5).

    Returns
    -------
    (p, N_max, m_max) float64
    """
    p, m_max = problem.y_init.shape
    N_max = int(np.max(pop_size))
    width = (problem.upper - problem.lower)[:, None, :]
    noise = (rng.random((p, N_max, m_max)) - 0.5) * spread * width
    X = problem.y_init[:, None, :] + noise
    X[:, 0, :] = problem.y_init
    return reflect_into_bounds(X, problem.lower, problem.upper)


def subset(problem, idx):
    """The section problems ``idx``, padded only to their own largest m."""
    m_max = int(problem.m[idx].max())
    cut = lambda a: a[idx][:, :m_max]  # noqa: E731
    return SectionProblem(problem.length[idx], problem.tv1[idx], problem.tv2[idx], problem.theta_lower[idx],
                          problem.theta_upper[idx], problem.m[idx], cut(problem.x), cut(problem.lower),
                          cut(problem.upper), cut(problem.y_init))


def predict_y(problem, N_factor=3.0, F=0.8, CR=0.05, generations=NUM_ITER, seed=0, bounds="paper",
              group_ratio=1.5):
    """y-coordinates of the prediction points by DE/rand/1/bin on Eq. 14 (Sec. 4.5, 4.8).

    Every section plane is its own problem with N = N_factor * m individuals and m variables,
    bounds [min(L_i2, U_i2), max(L_i2, U_i2)]. Planes of similar m (within a factor
    ``group_ratio``) are solved together in one batched DE run, which keeps the padding of
    the batched arrays small. ``bounds`` is passed to :func:`de_rand_1_bin` ('paper':
    Algorithm 1 literally).

    Reading of NumIter (``generations``, default ``NUM_ITER`` = 20). The paper gives no value:
    Sec. 4.8 calls NumIter a small constant, reports that the DE "always obtains a convergence
    solution after only several iterations", and names fewer iterations as the way to cut
    HPDE's time. The DE's time is proportional to it, while the patch hardly depends on it:
    Eq. 14 rates how evenly the points turn, and the points stay close to the Eq. 16 start.
    Mean patch-to-ground-truth distance (per mille of the bounding-box diagonal) of the holes of
    ``scripts/unseen_holes.py --seeds 1,2,3`` with 5 / 10 / 20 / 30 / 50 / 100 generations:
    closed samples 1.384 / 1.381 / 1.385 / 1.387 / 1.382 / 1.390, creased 4.034 / 4.045 / 4.047 /
    4.053 / 4.061 / 4.069, CAD tessellations 9.786 / 9.781 / 9.817 / 9.843 / 9.866 / 9.941,
    real-size 2.065 for every count but 100 (2.064), noisy 3.334 / 3.340 / 3.330 / 3.332 /
    3.325 / 3.313. On the paper's sphere experiment
    (:func:`meshlab_holefill.evaluation.papers.hpde_sphere.sphere_experiment`, seeds 0-3) the APE
    is 0.1-1.0 % above 100 generations' for every count from 5 to 30 (20: 0.4-0.7 %). Eq. 14's
    value still falls between 20 and 100 generations; 20 keeps the DE an optimisation of it
    at a fifth of the cost of 100.

    Parameters
    ----------
    problem : SectionProblem
    N_factor, F, CR, generations, seed, bounds : DE settings (N = N_factor * m, at least 3)
    group_ratio : float

    Returns
    -------
    Y : (p, m_max) float64
    f : (p,) float64  final objective values
    generations_run : int  (largest over the groups)
    """
    p, m_max = problem.y_init.shape
    Y = np.zeros((p, m_max))
    f = np.zeros(p)
    if p == 0 or m_max == 0:
        return Y, f, 0
    rng = np.random.default_rng(seed)
    group = np.floor(np.log(problem.m) / np.log(group_ratio)).astype(np.int64)
    g_run = 0
    for gid in np.unique(group):
        idx = np.flatnonzero(group == gid)
        sub = subset(problem, idx)
        pop = np.maximum(np.ceil(N_factor * sub.m).astype(np.int64), 3)
        init = initial_population(sub, pop, rng)
        Yg, fg, g = de_rand_1_bin(AngleVariation(sub), sub.lower, sub.upper,
                                  pop_size=pop, dims=sub.m, F=F, CR=CR, generations=generations, seed=rng,
                                  init=init, bounds=bounds)
        Y[idx, :Yg.shape[1]] = Yg
        f[idx] = fg
        g_run = max(g_run, g)
    return Y, f, g_run


def predicted_points(P1, frames, problem, Y):
    """3D prediction points PP from the plane coordinates (x of Eq. 12, y of Eq. 14).

    Returns
    -------
    points : (sum m, 3) float64
    plane : (sum m,) int64  section-plane index of each point
    fraction : (sum m,) float64  x / |P_2 - P_1|, position along the chord in (0, 1)
    """
    valid = np.arange(problem.x.shape[1])[None, :] < problem.m[:, None]
    plane, col = np.nonzero(valid)
    ex, ey = frames[plane, 0], frames[plane, 1]
    pts = P1[plane] + problem.x[plane, col, None] * ex + Y[plane, col, None] * ey
    return pts, plane, problem.x[plane, col] / problem.length[plane]


def predict_points(ctx, base, normals, split, I_c, edge_len, de_options, arc_tangent="secant"):
    """Steps 3-5: correspondences, section planes and DE prediction (Sec. 4.3-4.5).

    Returns
    -------
    points : (q, 3) float64
    owner : (q, 2) int64  base points (a, b) of the pair each point was predicted for
    fraction : (q,) float64  position along the chord, in (0, 1)
    info : dict
    """
    P = ctx.points
    tangent, inward, pairs, cinfo = sections.base_point_pairs(base, normals, split, I_c)
    info = {"pairs": int(len(pairs)), "skipped_base_points": cinfo["skipped"], "M": 0, "predicted": 0,
            "de_generations": 0, "dropped_pairs": 0}
    empty = (np.zeros((0, 3)), np.zeros((0, 2), np.int64), np.zeros(0), info)
    if len(pairs) == 0:
        return empty
    a, b = pairs[:, 0], pairs[:, 1]
    Nv, flat = sections.section_normals(base.points, pairs, normals[a] + normals[b])
    W = sections.border_third_vertices(ctx)
    AP_a, TV_a = sections.ring_intersections(P, base.edge[a], base.points[a], Nv, W[base.edge[a]])
    AP_b, TV_b = sections.ring_intersections(P, base.edge[b], base.points[b], Nv, W[base.edge[b]])
    P1, P2, TV1, TV2 = base.points[a], base.points[b], TV_a, -TV_b
    ok = forward_tangents(P1, P2, TV1, TV2)
    info.update(section_normal_fallbacks=int(flat.sum()), dropped_pairs=int((~ok).sum()))
    if not ok.any():
        return empty
    pairs, P1, P2, TV1, TV2, Nv = pairs[ok], P1[ok], P2[ok], TV1[ok], TV2[ok], Nv[ok]
    m, M = prediction_counts(np.linalg.norm(P2 - P1, axis=1), edge_len)
    if arc_tangent == "circle":
        # The circle through AP, BP and the other base point needs the lengths |BP - AP|.
        TV1, TV2 = P1 - AP_a[ok], AP_b[ok] - P2
    problem, frames = section_problems(P1, P2, TV1, TV2, Nv, m, tangent=arc_tangent)
    Y, f, g = predict_y(problem, **de_options)
    points, plane, fraction = predicted_points(P1, frames, problem, Y)
    info.update(M=M, predicted=int(len(points)), de_generations=int(g), de_objective_mean=float(np.mean(f)))
    return points, pairs[plane], fraction, info
