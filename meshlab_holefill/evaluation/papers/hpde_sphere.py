"""The sphere experiment of Xie and Zou (2013), Sec. 5.1 and Table 1, with the errors of Eq. 17.

The paper's unit sphere has 1600 points and 3040 triangles: a 40 x 40 longitude/latitude
grid whose first and last rows are the poles (38 rings of 40 points plus 2 poles = 1522
distinct points, 2 * 1522 - 4 = 3040 triangles). Two "large holes" abandon 1210 triangles
in all. The paper does not give their shape; its Table 1 (M = 10, 7 and n = 106, 124 base
points) points to long holes, so here each hole is the set of triangles whose centroid lies
in a geodesic ellipse elongated along a meridian, on opposite sides of the sphere, sized to
abandon about 605 triangles each: 608 and 598 triangles (1206 in all), whose loops have 106
and 124 edges.
"""
from __future__ import annotations

import time

import numpy as np

from ...algorithms.xie_zou2013.differential_evolution import RINGS, fill
from ...core.holes import boundary_loops, hole_context, vertex_face_incidence
from ...core.patch import validate_patch

__all__ = ["PAPER_TABLE1_SPHERE", "SPHERE_HOLES", "ellipse_hole", "point_triangle_distances", "prediction_errors",
           "sphere_experiment", "uv_sphere"]

PAPER_TABLE1_SPHERE = {"MPE": 1.77e-2, "APE": 7.35e-3, "NHT": 1210, "M": (10, 7), "n": (106, 124),
                       "RT_seconds": 9.3}

# (centre latitude, centre longitude, semi-axis along the meridian, across it), radians.
SPHERE_HOLES = ((0.0, 0.0, 1.25, 0.85), (0.0, np.pi, 1.45, 0.65))


def uv_sphere(n_lon=40, n_lat=40):
    """Unit longitude/latitude sphere with n_lat grid rows (the first and last are the poles).

    Returns
    -------
    V : ((n_lat - 2) * n_lon + 2, 3) float64
    F : (2 * n_lon * (n_lat - 2), 3) int64  outward oriented
    """
    theta = np.linspace(0.0, np.pi, n_lat)[1:-1]
    phi = np.linspace(0.0, 2 * np.pi, n_lon, endpoint=False)
    T, Ph = np.meshgrid(theta, phi, indexing="ij")
    V = np.stack([np.sin(T) * np.cos(Ph), np.sin(T) * np.sin(Ph), np.cos(T)], axis=-1).reshape(-1, 3)
    V = np.vstack([V, [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]])
    rings = n_lat - 2
    north, south = len(V) - 2, len(V) - 1
    j = np.arange(n_lon)
    faces = []
    for r in range(rings - 1):
        a = r * n_lon + j
        b = r * n_lon + (j + 1) % n_lon
        faces += [np.stack([a, a + n_lon, b], axis=1), np.stack([b, a + n_lon, b + n_lon], axis=1)]
    last = (rings - 1) * n_lon
    faces += [np.stack([np.full(n_lon, north), j, (j + 1) % n_lon], axis=1),
              np.stack([np.full(n_lon, south), last + (j + 1) % n_lon, last + j], axis=1)]
    return V, np.concatenate(faces).astype(np.int64)


def ellipse_hole(V, F, lat, lon, along, across):
    """Faces whose centroid lies in a geodesic ellipse on the unit sphere, (m,) bool.

    The ellipse is centred at (lat, lon), with semi-axes ``along`` (radians along the
    meridian) and ``across``; a centroid is inside when (a / along)^2 + (b / across)^2 < 1 for
    its azimuthal-equidistant coordinates (a, b) about the centre.

    Parameters
    ----------
    V : (n, 3) float64  vertices on the unit sphere
    F : (m, 3) int
    lat, lon, along, across : float  radians

    Returns
    -------
    (m,) bool
    """
    c = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    north = np.array([-np.sin(lat) * np.cos(lon), -np.sin(lat) * np.sin(lon), np.cos(lat)])
    east = np.cross(north, c)
    X = V[F].mean(axis=1)
    X /= np.linalg.norm(X, axis=1, keepdims=True)
    dist = np.arccos(np.clip(X @ c, -1.0, 1.0))
    direction = np.arctan2(X @ east, X @ north)
    a, b = dist * np.cos(direction), dist * np.sin(direction)
    return (a / along) ** 2 + (b / across) ** 2 < 1.0


def point_triangle_distances(X, T):
    """Distance of each point to the nearest of a set of triangles (the piecewise surface).

    Parameters
    ----------
    X : (q, 3) float64
    T : (t, 3, 3) float64  triangle corners

    Returns
    -------
    (q,) float64
    """
    A, B, C = T[:, 0], T[:, 1], T[:, 2]
    N = np.cross(B - A, C - A)
    N /= np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    D = X[:, None, :] - A[None, :, :]
    h = np.einsum("qtd,td->qt", D, N)
    foot = X[:, None, :] - h[..., None] * N[None]
    inside = np.ones(h.shape, bool)
    for P0, P1 in ((A, B), (B, C), (C, A)):
        inside &= np.einsum("qtd,td->qt", np.cross(P1 - P0, foot - P0[None]), N) >= 0
    best = np.where(inside, np.abs(h), np.inf)
    for P0, P1 in ((A, B), (B, C), (C, A)):
        d = P1 - P0
        t = np.clip(np.einsum("qtd,td->qt", X[:, None, :] - P0[None], d)
                    / np.maximum(np.einsum("td,td->t", d, d), 1e-300),
                    0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(X[:, None, :] - (P0[None] + t[..., None] * d[None]), axis=2))
    return best.min(axis=1)


def prediction_errors(points, hole_triangles):
    """MPE and APE of Eq. 17 for the smoothed predicted points SP_i.

    MPE = max_i E_i / Mx, APE = sum_i E_i / (K Mx), Mx = max_{i,j} |SP_{i,j}|, where E_i is
    the distance of SP_i to the abandoned hole triangles.

    Parameters
    ----------
    points : (K, 3) float64  SP_i, the new (interior) patch vertices of all holes
    hole_triangles : (t, 3, 3) float64  corners of the abandoned triangles

    Returns
    -------
    dict with ``MPE``, ``APE``, ``Mx``, ``K``
    """
    E = point_triangle_distances(np.asarray(points, np.float64), np.asarray(hole_triangles, np.float64))
    Mx = float(np.abs(points).max())
    return {"MPE": float(E.max() / Mx), "APE": float(E.mean() / Mx), "Mx": Mx, "K": int(len(points))}


def sphere_experiment(seed=0, holes=SPHERE_HOLES, **params):
    """Patch two large holes on the paper's 1600-point unit sphere and measure Eq. 17.

    Parameters
    ----------
    seed : int
    holes : sequence of (lat, lon, along, across)
    **params : HPDE parameters passed to :func:`differential_evolution.fill`

    Returns
    -------
    dict with ``MPE``, ``APE`` (ours), ``paper`` (Table 1 row), ``NHT``, ``K``, per-hole
    ``holes`` (boundary edges, n, M, Rate, seconds, segmented) and ``seconds``.
    """
    V, F = uv_sphere()
    removed = np.zeros(len(F), bool)
    for lat, lon, along, across in holes:
        removed |= ellipse_hole(V, F, lat, lon, along, across)
    F_cut = F[~removed]
    loops = boundary_loops(F_cut)
    incidence = vertex_face_incidence(F_cut, len(V))
    new_points, smoothed_points, per_hole = [], [], []
    t_all = time.perf_counter()
    for i, loop in enumerate(loops):
        ctx = hole_context(V, F_cut, loop, incidence, rings=RINGS, index=i)
        t0 = time.perf_counter()
        record = {}
        patch = fill(ctx, seed=seed, record=record, **params)
        seconds = time.perf_counter() - t0
        validate_patch(patch, ctx.points, ctx.forbidden_edges)
        new_points.append(patch.vertices)
        smoothed_points.append(record.get("smoothed_points", np.zeros((0, 3))))
        per_hole.append({"boundary_edges": ctx.size, "n": patch.info["base_points"], "M": patch.info["M"],
                         "Rate": round(patch.info["rate"], 3), "segmented": patch.info["segmented"],
                         "new_vertices": len(patch.vertices), "seconds": round(seconds, 3)})
    hole_triangles = V[F[removed]]
    errors = prediction_errors(np.concatenate(smoothed_points), hole_triangles)
    final = prediction_errors(np.concatenate(new_points), hole_triangles)
    return {"MPE": errors["MPE"], "APE": errors["APE"], "Mx": errors["Mx"], "K": errors["K"],
            "final_vertices": {key: final[key] for key in ("MPE", "APE", "K")},
            "NP": int(len(V)), "NOT": int(len(F)), "NHT": int(removed.sum()), "holes": per_hole,
            "seconds": time.perf_counter() - t_all, "paper": PAPER_TABLE1_SPHERE}
