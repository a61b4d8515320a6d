"""HPDE steps 2-4 (Xie and Zou 2013, Sec. 4.2-4.4): base points, segmentation, correspondences, section planes.

Each function is one step of Algorithm 2 and works on plain arrays. Readings of passages the
paper leaves open are listed in the docstring of the function that makes them and collected
in the module docstring of :mod:`meshlab_holefill.algorithms.xie_zou2013.differential_evolution`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...geometry.quality import mean_edge_length

__all__ = ["BasePoints", "base_points", "ring_edge_length", "base_point_normals", "pca_segmentation",
           "dihedral_angle", "segment_boundary", "boundary_frames", "intersection_angle", "best_start",
           "pair_chain", "correspondences", "base_point_pairs", "pairing_coverage", "section_normals",
           "border_third_vertices", "ring_intersections"]

# Dihedral comparisons (Sec. 4.2) allow this slack (0.1 degree), so that the cube of Fig. 15(b), whose two
# faces meet at exactly A_c = pi/2, is segmented as the paper reports, and so is a right-angled edge whose
# fitted planes are tilted by the tessellation: on remeshed and decimated CAD-like parts the fits of two
# faces meeting at 90 degrees measured 90.007-90.021 degrees.
ANGLE_SLACK = float(np.radians(0.1))


@dataclass
class BasePoints:
    """Base points BP_1..BP_n at equal arc length on the boundary (Sec. 4.2).

    Attributes
    ----------
    points : (n, 3) float64
    edge : (n,) int64  loop edge (edge[j], edge[j] + 1) holding BP_j
    t : (n,) float64  position of BP_j on that edge, in [0, 1)
    perimeter : float  BudLen
    """

    points: np.ndarray
    edge: np.ndarray
    t: np.ndarray
    perimeter: float
    # pairings already found for these base points (:func:`base_point_pairs`)
    _pairings: dict = field(default_factory=dict, repr=False, compare=False)

    def __len__(self):
        return len(self.points)


def base_points(P, edge_length):
    """Sec. 4.2: n = floor(BudLen / (0.8 EdgeLen)) base points at equal arc length.

    BP_1 is the first loop vertex; the boundary is the closed polyline of the loop.

    Parameters
    ----------
    P : (k, 3) float64  loop points
    edge_length : float  EdgeLen, mean edge length of the surrounding triangles

    Returns
    -------
    BasePoints  (n >= 3)
    """
    P = np.asarray(P, np.float64)
    k = len(P)
    seg = np.roll(P, -1, axis=0) - P
    lengths = np.linalg.norm(seg, axis=1)
    cum = np.concatenate([[0.0], np.cumsum(lengths)])
    perimeter = float(cum[-1])
    n = max(int(np.floor(perimeter / (0.8 * edge_length))), 3)
    s = np.arange(n) * (perimeter / n)
    edge = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, k - 1)
    t = np.clip((s - cum[edge]) / np.maximum(lengths[edge], 1e-300), 0.0, 1.0)
    points = P[edge] + t[:, None] * seg[edge]
    return BasePoints(points=points, edge=edge.astype(np.int64), t=t, perimeter=perimeter)


def ring_edge_length(ctx):
    """EdgeLen (Sec. 4.2): mean length of the edges of the ring of triangles adjacent to the hole."""
    ring = ctx.faces[np.any(ctx.faces < ctx.size, axis=1)]
    return mean_edge_length(ctx.vertices, ring)


def base_point_normals(normals, base):
    """Surface normal at each base point, interpolated along its loop edge, (n, 3)."""
    k = len(normals)
    N = (1 - base.t)[:, None] * normals[base.edge] + base.t[:, None] * normals[(base.edge + 1) % k]
    return N / np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)


def _moment_covariances(count, sums, squares):
    """Covariance matrices (q, 3, 3) from moment sums: count (q,), sums (q, 3), squares (q, 3, 3)."""
    mean = sums / count[:, None]
    return squares / count[:, None, None] - mean[:, :, None] * mean[:, None, :]


def smallest_eigenvalue_estimate(C):
    """Smallest eigenvalue of symmetric 3x3 matrices (q, 3, 3) in closed form (the trigonometric solution).

    Within about sqrt(machine epsilon) times the matrix norm of LAPACK's value (the arccos
    loses half the digits next to a repeated eigenvalue); a screen for :func:`pca_segmentation`.
    """
    q = np.trace(C, axis1=1, axis2=2) / 3.0
    off = C[:, 0, 1] ** 2 + C[:, 0, 2] ** 2 + C[:, 1, 2] ** 2
    d = np.diagonal(C, axis1=1, axis2=2) - q[:, None]
    p = np.sqrt(((d ** 2).sum(axis=1) + 2.0 * off) / 6.0)
    scale = np.where(p > 0, p, 1.0)
    B = (C - q[:, None, None] * np.eye(3)) / scale[:, None, None]
    r = np.clip(np.linalg.det(B) / 2.0, -1.0, 1.0)
    phi = np.arccos(r) / 3.0
    return np.where(p > 0, q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0), q)


def _eq8_best_split(cov1, cov2):
    """Index of the first minimum of max(lambda_3(PS_1), lambda_3(PS_2)), lambda_3 = max(LAPACK's smallest, 0).

    The closed-form estimates screen the splits: only those within a margin (1e-6 times the
    largest trace, far above the estimates' error) of the estimated minimum get LAPACK's
    eigenvalues, so the index is the one all splits through LAPACK give, in a fraction of
    the time (O(n^2) splits of a large hole).
    """
    est = np.maximum(np.maximum(smallest_eigenvalue_estimate(cov1), 0.0),
                     np.maximum(smallest_eigenvalue_estimate(cov2), 0.0))
    margin = 1e-6 * max(float(np.abs(np.trace(cov1, axis1=1, axis2=2)).max()),
                        float(np.abs(np.trace(cov2, axis1=1, axis2=2)).max()))
    near = np.flatnonzero(est <= est.min() + 2.0 * margin)
    lam1 = np.maximum(np.linalg.eigh(cov1[near])[0][:, 0], 0.0)
    lam2 = np.maximum(np.linalg.eigh(cov2[near])[0][:, 0], 0.0)
    return int(near[np.argmin(np.maximum(lam1, lam2))])


def pca_segmentation(BP, min_size=None):
    """Optimal split of the base points into two runs by PCA (Sec. 4.2, Eq. 8).

    Minimises max(lambda_3(PS_1), lambda_3(PS_2)) over 1 <= i < j <= n with
    PS_1 = {BP_j..BP_n, BP_1..BP_{i-1}} and PS_2 = {BP_i..BP_{j-1}}; all O(n^2) splits are
    evaluated at once from prefix sums of the first and second moments (the minimum found by a
    closed-form screen and LAPACK's eigenvalues on the few splits near it, :func:`_eq8_best_split`).

    Reading: the paper bounds nothing, but a run of 3 points is always planar (lambda_3 = 0)
    and a short run is nearly collinear (its plane is undefined), so each run must hold at
    least ``min_size`` points, default max(4, ceil(n / 6)).

    Parameters
    ----------
    BP : (n, 3) float64
    min_size : int, optional

    Returns
    -------
    i0, j0 : int  0-based: PS_2 = BP[i0:j0], PS_1 = the rest (BP[j0:] then BP[:i0])
    lambdas : (2,) float64  smallest eigenvalues of PS_1 and PS_2
    normals : (2, 3) float64  unit normals of the planes fitted to PS_1 and PS_2 (unoriented)
    (None, None, None, None) when n < 2 min_size.
    """
    BP = np.asarray(BP, np.float64)
    n = len(BP)
    if min_size is None:
        min_size = max(4, int(np.ceil(n / 6)))
    if n < 2 * min_size:
        return None, None, None, None
    X = BP - BP.mean(axis=0)  # centred moments: no cancellation in the covariances
    S1 = np.concatenate([np.zeros((1, 3)), np.cumsum(X, axis=0)])
    S2 = np.concatenate([np.zeros((1, 3, 3)), np.cumsum(X[:, :, None] * X[:, None, :], axis=0)])
    i, j = np.triu_indices(n, k=1)
    c2 = (j - i).astype(np.float64)
    c1 = n - c2
    ok = (c2 >= min_size) & (c1 >= min_size)
    i, j, c1, c2 = i[ok], j[ok], c1[ok], c2[ok]
    s2, q2 = S1[j] - S1[i], S2[j] - S2[i]
    s1, q1 = S1[n] - s2, S2[n] - q2
    best = _eq8_best_split(_moment_covariances(c1, s1, q1), _moment_covariances(c2, s2, q2))
    i0, j0 = int(i[best]), int(j[best])
    ps1 = np.r_[np.arange(j0, n), np.arange(0, i0)]
    ps2 = np.arange(i0, j0)
    fits = []
    for idx in (ps1, ps2):
        C = X[idx] - X[idx].mean(axis=0)
        w, U = np.linalg.eigh(C.T @ C / len(idx))
        fits.append((max(w[0], 0.0), U[:, 0]))
    return i0, j0, np.array([fits[0][0], fits[1][0]]), np.array([fits[0][1], fits[1][1]])


def dihedral_angle(normal_1, normal_2, reference_1, reference_2):
    """Dihedral angle of two fitted planes (Sec. 4.2), pi for coplanar ones.

    Each normal is first oriented like the surface (positive dot with its reference, the mean
    surface normal at the points it was fitted to); the angle between the half-planes is then
    pi minus the angle between the normals (90 degrees for two faces of a cube).
    """
    n1 = normal_1 * (1.0 if np.dot(normal_1, reference_1) >= 0 else -1.0)
    n2 = normal_2 * (1.0 if np.dot(normal_2, reference_2) >= 0 else -1.0)
    return float(np.pi - np.arccos(np.clip(np.dot(n1, n2), -1.0, 1.0))), n1, n2


def segment_boundary(base, normals, critical_dihedral):
    """Step 2 decision: Eq. 8 split and whether to segment (Sec. 4.2).

    Returns
    -------
    dict with ``split`` (i0, j0) or None, ``dihedral`` (radians or None), ``segmented`` (bool),
    ``planes`` ((centroid, oriented normal) for PS_1 and PS_2, or None).
    """
    i0, j0, lams, plane_normals = pca_segmentation(base.points)
    if i0 is None:
        return {"split": None, "dihedral": None, "segmented": False, "planes": None}
    n = len(base)
    ps1 = np.r_[np.arange(j0, n), np.arange(0, i0)]
    ps2 = np.arange(i0, j0)
    angle, n1, n2 = dihedral_angle(plane_normals[0], plane_normals[1],
                                            normals[ps1].sum(axis=0), normals[ps2].sum(axis=0))
    planes = ((base.points[ps1].mean(axis=0), n1), (base.points[ps2].mean(axis=0), n2))
    return {"split": (i0, j0), "dihedral": angle, "segmented": angle <= critical_dihedral + ANGLE_SLACK,
            "planes": planes}


def boundary_frames(BP, normals, window=2):
    """Boundary direction and into-hole direction at each base point (for the I_c test, Sec. 4.3).

    Reading of Q_t Q_{t+1} in Fig. 2: the boundary direction at BP_j is BP_{j+w} - BP_{j-w}
    (w = ``window``), the direction of the curve the base points sample. The literal loop
    edge holding BP_j would make the test arbitrary on holes cut along triangle edges, whose
    zigzag loops have single edges up to 60 degrees off the curve.

    Parameters
    ----------
    BP : (n, 3) float64  base points in patch orientation
    normals : (n, 3) float64  surface normals at the base points
    window : int

    Returns
    -------
    tangent : (n, 3) float64  unit, along the loop
    inward : (n, 3) float64  unit, normal x tangent: in the tangent plane, into the hole
    """
    t = np.roll(BP, -window, axis=0) - np.roll(BP, window, axis=0)
    t -= np.einsum("ij,ij->i", t, normals)[:, None] * normals
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-300)
    return t, np.cross(normals, t)


def intersection_angle(line, tangent, inward):
    """Angle from the boundary direction to a linking line, positive when the line enters the hole.

    (q, 3) arrays -> (q,) radians in (-pi, pi]; in [I_c, pi - I_c] when the line crosses the
    boundary into the hole at an angle of at least I_c.
    """
    return np.arctan2(np.einsum("ij,ij->i", line, inward), np.einsum("ij,ij->i", line, tangent))


def best_start(BP, tangent=None, inward=None, I_c=np.pi / 15, min_usable=0.5):
    """Starting position sp* of the pairing with the least summed clamping distance (Sec. 4.3, Eq. 10).

    Pairs are (Seq(i), Seq(n-i+1)), i = 1..n/2, with Seq = (sp, ..., n, 1, ..., sp-1): in
    0-based indices (sp + i, sp - 1 - i). Every start 0 <= sp < n is tried: for even n, sp and
    sp + n/2 give the same pairs (the paper's range 1..n/2); for odd n the extra starts are
    further symmetric pairings, a harmless superset.

    Reading (with ``tangent``/``inward`` given): the minimum is taken over the starts whose
    pairs mostly pass the I_c test unmodified (at least ``min_usable`` of them), when there is
    one. On a long hole bent round a sphere the chords along its length can sum shorter than
    those across it, yet they run along the boundary and I_c would skip nearly all of them.

    Returns
    -------
    sp : int
    dist : (n,) float64  Dist of Eq. 10 for each start
    """
    n = len(BP)
    D = np.linalg.norm(BP[:, None, :] - BP[None, :, :], axis=2)
    sp = np.arange(n)[:, None]
    i = np.arange(n // 2)[None, :]
    a, b = (sp + i) % n, (sp - 1 - i) % n
    dist = D[a, b].sum(axis=1)
    if tangent is None or n < 4:
        return int(np.argmin(dist)), dist
    line = BP[b] - BP[a]
    line /= np.maximum(np.linalg.norm(line, axis=2, keepdims=True), 1e-300)
    ang_a = np.arctan2(np.einsum("spd,spd->sp", line, inward[a]), np.einsum("spd,spd->sp", line, tangent[a]))
    ang_b = np.arctan2(np.einsum("spd,spd->sp", -line, inward[b]), np.einsum("spd,spd->sp", -line, tangent[b]))
    ok = (ang_a >= I_c) & (ang_a <= np.pi - I_c) & (ang_b >= I_c) & (ang_b <= np.pi - I_c)
    usable = ok.mean(axis=1) >= min_usable
    if usable.any():
        return int(np.flatnonzero(usable)[np.argmin(dist[usable])]), dist
    return int(np.argmin(dist)), dist


def pair_chain(BP, tangent, inward, start_a, start_b, I_c=np.pi / 15):
    """Walk the correspondences from one end of the symmetry axis to the other (Sec. 4.3).

    Pointer a runs forward from ``start_a`` and b backward from ``start_b`` (Eq. 9 and Eq. 10
    both pair indices with a constant sum). The modification of Fig. 2: a base point whose
    linking line BP_a BP_b meets the boundary at an angle below I_c is skipped, its pointer
    advancing alone, so that "the point and the following points" shift. Readings: the angle
    is measured in the tangent plane from the boundary direction towards the hole, so a line
    that leaves the hole (possible near the ends of the axis on a jagged boundary) fails too
    (accepted: I_c <= angle <= pi - I_c); when both ends fail both are skipped; the walk stops
    when the pointers meet.

    Parameters
    ----------
    BP : (n, 3) float64
    tangent, inward : (n, 3) float64  from :func:`boundary_frames`
    start_a, start_b : int
    I_c : float  critical intersection angle (radians)

    Returns
    -------
    pairs : (p, 2) int64  accepted (a, b), in chain order
    skipped : int  number of base points skipped by the I_c rule
    """
    n = len(BP)
    da = db = 0
    pairs = []
    skipped = 0
    while da + db <= n - 2:
        a, b = (start_a + da) % n, (start_b - db) % n
        line = BP[b] - BP[a]
        length = float(np.linalg.norm(line))
        if length <= 0:
            da += 1
            db += 1
            continue
        line = line / length
        ang = intersection_angle(np.stack([line, -line]), tangent[[a, b]], inward[[a, b]])
        ok_a, ok_b = bool(I_c <= ang[0] <= np.pi - I_c), bool(I_c <= ang[1] <= np.pi - I_c)
        if ok_a and ok_b:
            pairs.append((a, b))
            da += 1
            db += 1
        elif not ok_a and not ok_b:
            skipped += 2
            da += 1
            db += 1
        elif not ok_a:
            skipped += 1
            da += 1
        else:
            skipped += 1
            db += 1
    return np.asarray(pairs, np.int64).reshape(-1, 2), skipped


def correspondences(BP, tangent, inward, segmentation=None, I_c=np.pi / 15):
    """Pairs of corresponding base points (Sec. 4.3).

    Segmented boundary (``segmentation = (i0, j0)``): the forced pairing of Eq. 9,
    (i0 - t, j0 + t) for all t, walked from the middle of PS_2 to the middle of PS_1.
    Otherwise the pairing of Eq. 10 from the best start sp*. Both are then modified by I_c.

    Returns
    -------
    pairs : (p, 2) int64
    info : dict  ``start`` (sp* or None), ``skipped``
    """
    n = len(BP)
    if segmentation is not None:
        i0, j0 = segmentation
        s = i0 + j0
        if s % 2:
            start_a, start_b = (s + 1) // 2, (s - 1) // 2
        else:
            start_a, start_b = s // 2 + 1, s // 2 - 1
        sp = None
    else:
        sp, _ = best_start(BP, tangent, inward, I_c)
        start_a, start_b = sp, sp - 1
    pairs, skipped = pair_chain(BP, tangent, inward, start_a % n, start_b % n, I_c)
    return pairs, {"start": sp, "skipped": skipped}


def base_point_pairs(base, normals, split, I_c):
    """(tangent, inward, pairs, info): :func:`boundary_frames` and :func:`correspondences` of the base points.

    Found once per (split, I_c) for the same ``normals`` and kept on ``base``: the layout
    order (:func:`pairing_coverage`, both pairings) and the prediction of each attempt ask
    for the same pairs. The arrays are shared: read them, do not write them.
    """
    key = (None if split is None else tuple(int(x) for x in split), float(I_c))
    hit = base._pairings.get(key)
    if hit is not None and hit[0] is normals:
        return hit[1]
    tangent, inward = boundary_frames(base.points, normals)
    pairs, info = correspondences(base.points, tangent, inward, split, I_c)
    base._pairings[key] = (normals, (tangent, inward, pairs, info))
    return tangent, inward, pairs, info


def pairing_coverage(base, normals, split, I_c):
    """Share of the base points that the correspondences of Sec. 4.3 keep in a pair."""
    pairs = base_point_pairs(base, normals, split, I_c)[2]
    return 2.0 * len(pairs) / max(len(base), 1)


def section_normals(BP, pairs, surface_normals, max_tilt=np.pi / 4):
    """Normal Nv of the section plane of each pair (Sec. 4.4, Eq. 11).

    Nv = lv x n, lv = BP_i - BP_{n-i+1}, n = lv x (mid_{i-1} - mid_{i+1}) with mid the
    midpoints of the previous and next pairs of the chain: n is the normal of the sheet of
    chords, so the section plane contains the chord and that normal. Readings: the first and
    last pairs use one-sided differences; where the chain turns so that the difference of
    midpoints runs nearly along lv (after I_c skips, near the ends of the axis), n is
    ill-conditioned, so when it leans more than ``max_tilt`` (45 degrees) from the surface
    normal at the pair the surface normal is used instead.

    Parameters
    ----------
    BP : (n, 3) float64
    pairs : (p, 2) int64
    surface_normals : (p, 3) float64  mean surface normal at each pair

    Returns
    -------
    Nv : (p, 3) float64 unit normals
    fallback : (p,) bool  pairs that used the surface normal
    """
    A, Bq = BP[pairs[:, 0]], BP[pairs[:, 1]]
    lv = A - Bq
    mid = 0.5 * (A + Bq)
    if len(pairs) >= 2:
        prev = np.concatenate([mid[:1], mid[:-1]])
        nxt = np.concatenate([mid[1:], mid[-1:]])
        diff = prev - nxt
    else:
        diff = np.zeros_like(mid)
    nbar = np.cross(lv, diff)
    nbar /= np.maximum(np.linalg.norm(nbar, axis=1, keepdims=True), 1e-300)
    sn = surface_normals / np.maximum(np.linalg.norm(surface_normals, axis=1, keepdims=True), 1e-300)
    fallback = np.abs(np.einsum("ij,ij->i", nbar, sn)) < np.cos(max_tilt)
    nbar[fallback] = sn[fallback]
    Nv = np.cross(lv, nbar)
    return Nv / np.maximum(np.linalg.norm(Nv, axis=1, keepdims=True), 1e-300), fallback


def border_third_vertices(ctx):
    """Third corner W of the border triangle of each loop edge, (k, 3)."""
    k = ctx.size
    tri = ctx.faces[ctx.border_faces]
    i = np.arange(k)[:, None]
    other = (tri != i) & (tri != (i + 1) % k)
    # A border face whose third corner is also a loop vertex still has one "other" corner.
    pick = np.argmax(other, axis=1)
    return ctx.vertices[tri[np.arange(k), pick]]


def ring_intersections(P, base_edge, BP, Nv, third_vertex):
    """Intersections AP of the section planes with the ring triangles (Sec. 4.4).

    The section plane through a base point (on loop edge Q_t Q_{t+1}) crosses the border
    triangle (Q_t, Q_{t+1}, W) of that edge along a segment from the base point to AP on edge
    Q_t W or Q_{t+1} W (the line face-plane x section-plane); the unit tangent
    TV = (BP - AP) / |BP - AP| points from the surface into the hole. Reading for the
    degenerate case (plane containing the boundary edge, which the I_c rule is meant to
    avoid): TV is the in-face direction perpendicular to the edge projected into the section
    plane and AP is the base point moved back by one edge length.

    Parameters
    ----------
    P : (k, 3) float64  loop points
    base_edge : (q,) int64  loop edge of each base point
    BP : (q, 3) float64  base points
    Nv : (q, 3) float64  unit section-plane normals
    third_vertex : (q, 3) float64  W, the third corner of each border triangle

    Returns
    -------
    AP : (q, 3) float64
    TV : (q, 3) float64  unit, into the hole
    """
    k = len(P)
    Q0, Q1, W = P[base_edge], P[(base_edge + 1) % k], third_vertex
    u = Q1 - Q0
    u /= np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-300)
    nf = np.cross(Q1 - Q0, W - Q0)
    nf /= np.maximum(np.linalg.norm(nf, axis=1, keepdims=True), 1e-300)
    wq = W - Q0
    inward = wq - np.einsum("ij,ij->i", wq, u)[:, None] * u  # towards W, inside the face
    inward /= np.maximum(np.linalg.norm(inward, axis=1, keepdims=True), 1e-300)
    hole = -inward
    TV = np.cross(Nv, nf)
    tv_len = np.linalg.norm(TV, axis=1)
    # Ray BP - s TV through the triangle: exit on edge Q0-W or Q1-W (plane side tests).
    d0 = np.einsum("ij,ij->i", Q0 - BP, Nv)
    d1 = np.einsum("ij,ij->i", Q1 - BP, Nv)
    dw = np.einsum("ij,ij->i", W - BP, Nv)
    AP = np.empty_like(BP)
    with np.errstate(divide="ignore", invalid="ignore"):
        s0 = d0 / (d0 - dw)  # crossing on Q0-W at Q0 + s0 (W - Q0)
        s1 = d1 / (d1 - dw)
    on0 = (d0 * dw <= 0) & np.isfinite(s0) & (np.abs(d0 - dw) > 0)
    on1 = (d1 * dw <= 0) & np.isfinite(s1) & (np.abs(d1 - dw) > 0)
    c0 = Q0 + np.clip(np.nan_to_num(s0), 0, 1)[:, None] * (W - Q0)
    c1 = Q1 + np.clip(np.nan_to_num(s1), 0, 1)[:, None] * (W - Q1)
    # Prefer the crossing that is not the base point itself (a base point on a vertex).
    far0 = np.linalg.norm(c0 - BP, axis=1)
    far1 = np.linalg.norm(c1 - BP, axis=1)
    use0 = on0 & (~on1 | (far0 >= far1))
    use1 = on1 & ~use0
    AP[use0] = c0[use0]
    AP[use1] = c1[use1]
    scale = np.linalg.norm(W - Q0, axis=1)
    reach = np.where(use0, far0, np.where(use1, far1, 0.0))
    degenerate = ~(use0 | use1) | (tv_len < 1e-9) | (reach < 1e-6 * scale)
    # BP - AP leaves the border triangle through the boundary edge: into the hole.
    TV = (BP - AP) / np.maximum(reach, 1e-300)[:, None]
    if degenerate.any():
        h = hole[degenerate] - np.einsum("ij,ij->i", hole[degenerate], Nv[degenerate])[:, None] * Nv[degenerate]
        h /= np.maximum(np.linalg.norm(h, axis=1, keepdims=True), 1e-300)
        TV[degenerate] = h
        AP[degenerate] = BP[degenerate] - scale[degenerate, None] * h
    return AP, TV

