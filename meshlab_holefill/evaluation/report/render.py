"""Offscreen pictures of each hole: the ground truth and every filter's patch, side by side.

A small software renderer on matplotlib: orthographic view along the hole's mean normal
(tilted 20 degrees for depth cues), faces drawn far to near (painter's algorithm) with
Lambert shading. The surrounding mesh is grey, back faces blue-grey; a patch is coloured by
the distance of each face to the ground truth or, without ground truth (a scan's own holes),
by triangle quality 2r/R. Every panel of a hole's picture shares one colour scale, shown by
the colour bar under the panels: distances on a logarithmic scale from the best filter's
small distances to the worst filter's large ones (so 1.6 and 3.5 per mille differ even when
another filter reaches 40), quality on 0..1.
"""
from __future__ import annotations

import os

import numpy as np

from ...geometry.pca import plane_frame
from ...geometry.quality import face_normals, triangle_quality
from .labels import short_label

__all__ = ["draw_mesh", "hole_figure", "hole_pictures", "view_frame"]

TILT_DEGREES = 20.0


def view_frame(V, F, loop, surface=None):
    """Orthonormal (right, up, toward-viewer) axes looking at the hole from outside.

    The view direction is the area-weighted mean normal of ``surface`` (the ground truth or a
    patch: it faces the viewer best even when a hole wraps around a tip), else the normal of
    the plane fitted to the boundary loop turned to the side the faces around the hole face;
    then it is tilted by TILT_DEGREES.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int  faces around the hole
    loop : (k,) int  the hole's boundary vertices
    surface : ((p, 3) float64, (q, 3) int), optional

    Returns
    -------
    (3, 3) float64, rows = right, up, toward the viewer
    """
    from ...geometry.pca import fit_plane

    n = None
    if surface is not None and len(surface[1]):
        n = face_normals(surface[0], surface[1], normalize=False).sum(axis=0)
        n = n / np.linalg.norm(n) if np.linalg.norm(n) > 1e-12 else None
    if n is None:
        around = face_normals(V, F, normalize=False).sum(axis=0)  # area-weighted
        n = fit_plane(V[loop])[1]
        if np.dot(n, around) < 0:
            n = -n
    u, v = plane_frame(n)
    t = np.radians(TILT_DEGREES)
    toward = np.cos(t) * n + np.sin(t) * v
    up = np.cross(toward, u)
    return np.stack([u, up / np.linalg.norm(up), toward])


def draw_mesh(ax, V, F, frame, colors=None, base=(0.78, 0.78, 0.78), zorder=1):
    """Draw shaded triangles on a 2D axis, far to near.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int
    frame : (3, 3) float64  from view_frame
    colors : (m, 4) float64 RGBA per face, optional (else ``base``)
    """
    from matplotlib.collections import PolyCollection

    if len(F) == 0:
        return
    P = V @ frame.T
    order = np.argsort(P[F][:, :, 2].mean(axis=1))  # far first
    F = np.asarray(F)[order]
    normals = face_normals(V, F) @ frame.T
    facing = normals[:, 2]
    light = np.array([-0.3, 0.4, 0.87])
    light /= np.linalg.norm(light)
    shade = 0.45 + 0.55 * np.clip(np.abs(normals @ light), 0, 1)
    rgb = np.tile(np.asarray(base, float)[:3], (len(F), 1)) if colors is None else np.asarray(colors)[order][:, :3]
    rgb = np.where(facing[:, None] < 0, 0.5 * rgb + 0.5 * np.array([0.35, 0.45, 0.75]), rgb)  # back faces bluish
    face_rgb = np.clip(rgb * shade[:, None], 0, 1)
    polys = P[F][:, :, :2]
    ax.add_collection(PolyCollection(polys, facecolors=face_rgb, edgecolors=(0, 0, 0, 0.18), linewidths=0.25,
                                     zorder=zorder))


def hole_figure(key, data, rows, labels, diag, path):
    """One picture: ground truth + one panel per filler for one hole."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import colormaps
    from matplotlib.colors import Normalize

    V0, context, loop, gt = data["V0"], data["context"], data["loop"], data["ground_truth"]
    has_gt = gt is not None
    surface = gt if has_gt else next(((p["V"], p["F"]) for p in data["patches"].values()), None)
    frame = view_frame(V0, context, loop, surface)
    if has_gt:
        norm = distance_norm([1000.0 * p["face_distance"] / diag for p in data["patches"].values()
                              if "face_distance" in p])
        cmap = colormaps["inferno_r"]
        bar_label = "distance to ground truth (‰ of bbox diagonal, log scale), one scale for all panels"
    else:
        norm, cmap = Normalize(0, 1), colormaps["RdYlGn"]
        bar_label = "triangle quality 2r/R (1 = equilateral), one scale for all panels"
    panels = (["ground truth"] if has_gt else []) + labels
    fig, axes = plt.subplots(1, len(panels), figsize=(2.9 * len(panels), 3.9), squeeze=False)
    axes = axes.ravel()
    P = np.vstack([V0[loop]] + ([gt[0][np.unique(gt[1])]] if has_gt else [])) @ frame.T  # zoom on the hole
    lo, hi = P.min(axis=0), P.max(axis=0)
    pad = 0.3 * (hi - lo)[:2].max()
    by_label = {r["filler"]: r for r in rows}
    for ax, panel in zip(axes, panels):
        draw_mesh(ax, V0, context, frame)
        if panel == "ground truth":
            draw_mesh(ax, gt[0], gt[1], frame, base=(0.55, 0.75, 0.95), zorder=2)
            title = "ground truth"
        else:
            row = by_label.get(panel, {})
            patch = data["patches"].get(panel)
            if patch is not None and row.get("closed"):
                values = (1000.0 * patch["face_distance"] / diag if has_gt
                          else patch.get("quality", triangle_quality(patch["V"], patch["F"])))
                draw_mesh(ax, patch["V"], patch["F"], frame, colors=cmap(norm(values)), zorder=2)
                if has_gt:
                    title = f"{short_label(panel)}\nmean {row.get('dist_patch_to_gt_mean_permille', float('nan')):.3f}‰"
                else:
                    title = f"{short_label(panel)}\nquality {row.get('quality_mean', float('nan')):.2f}"
            else:
                reason = (row.get("reason") or "not closed")
                title = f"{short_label(panel)}\nNOT CLOSED"
                ax.text(0.5, 0.04, reason[:60], transform=ax.transAxes, ha="center", va="bottom", fontsize=7,
                        color="darkred", wrap=True, zorder=5)
        L = V0[np.r_[loop, loop[:1]]] @ frame.T
        ax.plot(L[:, 0], L[:, 1], color="k", lw=0.9, zorder=3)
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(title, fontsize=9)
    r0 = rows[0]
    kind = r0["size_class"] if r0["shape"] in (r0["size_class"], "given") else f"{r0['size_class']} {r0['shape']}"
    kind = {"natural": "natural hole", "outline": "island outline"}.get(kind, kind)
    fig.suptitle(f"{key[0]} hole {key[1]}: {kind}, {r0['boundary_edges']} edges", fontsize=11, y=0.99)
    sm = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    fig.tight_layout(rect=(0, 0.2, 1, 0.93))
    cax = fig.add_axes([0.3, 0.15, 0.4, 0.035])
    fig.colorbar(sm, cax=cax, orientation="horizontal").set_label(bar_label, fontsize=8)
    fig.savefig(path, dpi=80)
    plt.close(fig)


def distance_norm(distances):
    """The colour scale shared by every panel of a hole: logarithmic over the panels' distances.

    From the smallest panel's 5th percentile to the largest panel's 98th (a face farther is
    drawn at the end colour), the range kept within four decades.

    Parameters
    ----------
    distances : list of (q_i,) float  per panel, the distance of each patch face (‰)

    Returns
    -------
    matplotlib.colors.LogNorm (clipping)
    """
    from matplotlib.colors import LogNorm

    values = [np.asarray(d, float)[np.isfinite(d)] for d in distances]
    values = [d for d in values if len(d)]
    vmax = max([float(np.percentile(d, 98)) for d in values] + [1e-6])
    vmin = min([float(np.percentile(d, 5)) for d in values] + [vmax])
    vmin = min(max(vmin, vmax * 1e-4, 1e-9), vmax / 10.0)
    return LogNorm(vmin, vmax, clip=True)


def hole_pictures(comparison, directory, max_pictures=None):
    """One PNG per hole in ``directory/holes``; returns [(relative path, caption)].

    Every hole gets a picture unless ``max_pictures`` caps them per mesh (then the holes with the
    most boundary edges); holes are named by their number, the boundary loop index that
    ``meshlab-holefill holes`` and the filters' results use.
    """
    os.makedirs(os.path.join(directory, "holes"), exist_ok=True)
    labels = [f.label for f in comparison.fillers]
    diags = {c["case"]: c["bbox_diagonal"] for c in comparison.cases}
    out = []
    for case in dict.fromkeys(k[0] for k in comparison.render):
        keys = [k for k in comparison.render if k[0] == case]
        sizes = {k: len(comparison.render[k]["loop"]) for k in keys}
        if max_pictures is not None:
            keys = sorted(keys, key=lambda k: -sizes[k])[:max_pictures]
        keys = sorted(keys, key=lambda k: k[1])
        for key in keys:
            rows = [r for r in comparison.holes if r["case"] == key[0] and r["hole"] == key[1]]
            if not rows:
                continue
            safe = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in key[0])
            rel = os.path.join("holes", f"{safe}_hole{key[1]}.png")
            hole_figure(key, comparison.render[key], rows, labels, diags[key[0]], os.path.join(directory, rel))
            if rows[0]["ground_truth"]:
                what = ("ground truth and each filter's patch, coloured by distance to the ground truth "
                        "(one log scale for all panels: the colour bar)")
            else:
                what = "each filter's patch, coloured by triangle quality 2r/R (one scale for all panels: the colour bar)"
            out.append((rel, f"{key[0]} hole {key[1]} ({rows[0]['boundary_edges']} edges, "
                             f"{'island outline' if rows[0]['size_class'] == 'outline' else rows[0]['size_class']}): "
                             f"{what}."))
    return out
