"""HPDE Algorithm 2, steps 2-6 as the filter calls them (Xie and Zou 2013, Sec. 4.2-4.6).

EdgeLen and the base points' normals (Sec. 4.2), the segmentation test of Eq. 8 with A_c,
the correspondences, section planes and DE prediction of the points (Sec. 4.3-4.5,
:mod:`.hpde_sections`, :mod:`.hpde_prediction`), and the projection and constrained
triangulation of Sec. 4.6 (:mod:`.hpde_mesh`). :func:`.differential_evolution.fill` chains
them with the smoothing and optimisation of Sec. 4.7 and the fallbacks (readings in its
module docstring).
"""
from __future__ import annotations

import numpy as np

from ...errors import HoleFillError
from . import folds
from . import triangulation as mesh_steps
from . import prediction
from . import sections

EDGE_CLEARANCE = 0.35  # beyond the paper: a sliver apex nearer than this * L to a loop edge of length L ...
LONG_EDGE = 2.0  # ... longer than this * EdgeLen is left out (mesh_steps.triangulate_planar)
CLEARANCE = 0.25  # prediction points nearer than this * EdgeLen to the projected boundary are left out
STANDING_PLANE_COS = 0.5  # a PCA plane whose normal is further than 60 deg from the surface's stands across it


def ring_edge_length(ctx):
    """EdgeLen (Sec. 4.2): mean length of the edges of the ring of triangles adjacent to the hole."""
    from ...geometry.quality import mean_edge_length

    ring = ctx.faces[np.any(ctx.faces < ctx.size, axis=1)]
    return mean_edge_length(ctx.vertices, ring)


def base_point_normals(normals, base):
    """Surface normal at each base point, interpolated along its loop edge, (n, 3)."""
    k = len(normals)
    N = (1 - base.t)[:, None] * normals[base.edge] + base.t[:, None] * normals[(base.edge + 1) % k]
    return N / np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)


def border_third_vertices(ctx):
    """Third corner W of the border triangle of each loop edge, (k, 3)."""
    k = ctx.size
    tri = ctx.faces[ctx.border_faces]
    i = np.arange(k)[:, None]
    other = (tri != i) & (tri != (i + 1) % k)
    # A border face whose third corner is also a loop vertex still has one "other" corner.
    pick = np.argmax(other, axis=1)
    return ctx.vertices[tri[np.arange(k), pick]]


def segment_boundary(base, normals, critical_dihedral):
    """Step 2 decision: Eq. 8 split and whether to segment (Sec. 4.2).

    Returns
    -------
    dict with ``split`` (i0, j0) or None, ``dihedral`` (radians or None), ``segmented`` (bool),
    ``planes`` ((centroid, oriented normal) for PS_1 and PS_2, or None).
    """
    i0, j0, lams, plane_normals = sections.pca_segmentation(base.points)
    if i0 is None:
        return {"split": None, "dihedral": None, "segmented": False, "planes": None}
    n = len(base)
    ps1 = np.r_[np.arange(j0, n), np.arange(0, i0)]
    ps2 = np.arange(i0, j0)
    angle, n1, n2 = sections.dihedral_angle(plane_normals[0], plane_normals[1],
                                            normals[ps1].sum(axis=0), normals[ps2].sum(axis=0))
    planes = ((base.points[ps1].mean(axis=0), n1), (base.points[ps2].mean(axis=0), n2))
    return {"split": (i0, j0), "dihedral": angle, "segmented": angle <= critical_dihedral + sections.ANGLE_SLACK,
            "planes": planes}


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
    tangent, inward = sections.boundary_frames(base.points, normals)
    pairs, cinfo = sections.correspondences(base.points, tangent, inward, split, I_c)
    info = {"pairs": int(len(pairs)), "skipped_base_points": cinfo["skipped"], "M": 0, "predicted": 0,
            "de_generations": 0, "dropped_pairs": 0}
    empty = (np.zeros((0, 3)), np.zeros((0, 2), np.int64), np.zeros(0), info)
    if len(pairs) == 0:
        return empty
    a, b = pairs[:, 0], pairs[:, 1]
    Nv, flat = sections.section_normals(base.points, pairs, normals[a] + normals[b])
    W = border_third_vertices(ctx)
    AP_a, TV_a = sections.ring_intersections(P, base.edge[a], base.points[a], Nv, W[base.edge[a]])
    AP_b, TV_b = sections.ring_intersections(P, base.edge[b], base.points[b], Nv, W[base.edge[b]])
    P1, P2, TV1, TV2 = base.points[a], base.points[b], TV_a, -TV_b
    ok = prediction.forward_tangents(P1, P2, TV1, TV2)
    info.update(section_normal_fallbacks=int(flat.sum()), dropped_pairs=int((~ok).sum()))
    if not ok.any():
        return empty
    pairs, P1, P2, TV1, TV2, Nv = pairs[ok], P1[ok], P2[ok], TV1[ok], TV2[ok], Nv[ok]
    m, M = prediction.prediction_counts(np.linalg.norm(P2 - P1, axis=1), edge_len)
    if arc_tangent == "circle":
        # The circle through AP, BP and the other base point needs the lengths |BP - AP|.
        TV1, TV2 = P1 - AP_a[ok], AP_b[ok] - P2
    problem, frames = prediction.section_problems(P1, P2, TV1, TV2, Nv, m, tangent=arc_tangent)
    Y, f, g = prediction.predict_y(problem, **de_options)
    points, plane, fraction = prediction.predicted_points(P1, frames, problem, Y)
    info.update(M=M, predicted=int(len(points)), de_generations=int(g), de_objective_mean=float(np.mean(f)))
    return points, pairs[plane], fraction, info


def pairing_coverage(base, normals, split, I_c):
    """Share of the base points that the correspondences of Sec. 4.3 keep in a pair."""
    tangent, inward = sections.boundary_frames(base.points, normals)
    pairs, _ = sections.correspondences(base.points, tangent, inward, split, I_c)
    return 2.0 * len(pairs) / max(len(base), 1)


def plane_map_for(base, normals, seg, segmented):
    """The triangulation plane(s) of Sec. 4.6: the two fitted planes unfolded, or the PCA plane."""
    if segmented:
        (c1, n1), (c2, n2) = seg["planes"]
        if np.linalg.norm(np.cross(n1, n2)) > 1e-6:
            return mesh_steps.PlaneMap(c1, n1, (c2, n2))
    return mesh_steps.PlaneMap(*fitting_plane(base.points, normals))


def fitting_plane(points, normals):
    """The PCA fitting plane of Sec. 4.6 whose normal faces the surface: (centroid, unit normal).

    Reading: the paper takes the plane of the two largest principal directions. A narrow hole
    bent along its length (a strip around a sphere) has its smallest spread across the strip,
    so that plane stands across the surface and the projected loop folds onto itself. Of the
    three principal axes the one nearest to the mean surface normal is used as the normal
    when the paper's normal is more than 60 degrees (``STANDING_PLANE_COS``) from it; for a
    hole that is not bent more than its width the paper's plane is kept.

    Parameters
    ----------
    points : (n, 3) float64  base points
    normals : (n, 3) float64  surface normals at the base points

    Returns
    -------
    centroid : (3,) float64
    normal : (3,) float64  unit, on the side of the surface normals
    """
    from ...geometry.pca import fit_plane

    c, n, _, axes = fit_plane(points)
    mean = normals.sum(axis=0)
    if np.linalg.norm(mean) > 0:
        mean = mean / np.linalg.norm(mean)
        dots = axes @ mean
        if abs(n @ mean) < STANDING_PLANE_COS and np.abs(dots).max() > abs(n @ mean):
            n = axes[int(np.argmax(np.abs(dots)))]
    if n @ normals.sum(axis=0) < 0:
        n = -n
    return c, n


def triangulate(ctx, base, normals, seg, layout, prediction_result, edge_len, excluded, stats=None):
    """Step 6 for one layout: 'plane', 'two planes' (Sec. 4.6) or the 'disc' fallback.

    Parameters
    ----------
    excluded : (q,) bool  prediction points left out (outliers of earlier rounds)
    stats : dict, optional  receives ``edge_cleared`` (points left out by EDGE_CLEARANCE alone)

    Returns
    -------
    V : (k + q', 3) float64,  F : (t, 3) int64,  ids : (q',) int64 prediction point of each V[k:]

    Raises
    ------
    HoleFillError  non-simple layout, or a fold-over after mapping the triangulation back.
    """
    points, owner, fraction, _ = prediction_result
    P = ctx.points
    clearance = CLEARANCE * edge_len
    use = np.flatnonzero(~excluded)
    if layout == "disc":
        # The disc keeps every chord inside; drop points whose chord left the hole in 3D
        # (the 2D inside test of the plane layouts).
        _, inward = sections.boundary_frames(base.points, normals)
        use = use[mesh_steps.inside_boundary(points[use], base.points, inward, clearance)]
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])
        offsets = mesh_steps.lateral_offsets(P, ctx.loop_normals)
        Q, X = mesh_steps.disc_coordinates(arc, base.perimeter, len(base), owner[use, 0], owner[use, 1],
                                           fraction[use], offsets)
        V, F, _, kept = mesh_steps.triangulate_planar(P, points[use], Q, X, clearance, EDGE_CLEARANCE, stats,
                                                      LONG_EDGE * edge_len)
    else:
        pmap = plane_map_for(base, normals, seg, layout == "two planes")
        V, F, orientation, kept = mesh_steps.triangulate_projection(P, points[use], pmap, clearance, EDGE_CLEARANCE,
                                                                    stats, LONG_EDGE * edge_len)
        if folds.fold_overs(V, F, pmap.reference_normals(V, F, orientation)).any():
            raise HoleFillError(f"fold-over after mapping the {layout} triangulation back to 3D")
    return V, F, use[kept]
