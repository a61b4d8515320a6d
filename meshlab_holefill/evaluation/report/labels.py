"""Names, headings, colours and aggregates shared by the report's tables, charts and pictures.

The metrics shown (``METRICS``: key, heading, which way is better, how holes are pooled, format),
the order of the hole size classes, the short filter labels and one colour per filler.
"""
from __future__ import annotations

import numpy as np

__all__ = ["CHART_METRICS", "HEADINGS", "METRICS", "SIZE_ORDER", "aggregate", "closed_values", "filler_colors",
           "hole_seconds", "short_label"]

# (key, heading, better: "low" | "high" | "one", aggregate: "mean" | "min" | "max" | "sum", format)
METRICS = [
    ("dist_patch_to_gt_mean_permille", "patch→GT mean ‰", "low", "mean", "{:.3f}"),
    ("dist_patch_to_gt_max_permille", "patch→GT max ‰", "low", "max", "{:.2f}"),
    ("dist_gt_to_patch_mean_permille", "GT→patch mean ‰", "low", "mean", "{:.3f}"),
    ("normal_dev_mean_deg", "normal dev. mean °", "low", "mean", "{:.1f}"),
    ("quality_mean", "quality mean", "high", "mean", "{:.3f}"),
    ("quality_min", "quality min", "high", "min", "{:.3f}"),
    ("quality_share07", "share q≥0.7", "high", "mean", "{:.2f}"),
    ("edge_ratio", "edge ratio", "one", "mean", "{:.2f}"),
    ("border_dihedral_mean_deg", "border crease °", "low", "mean", "{:.1f}"),
    ("border_dihedral_excess_deg", "crease − GT's °", "low", "mean", "{:.1f}"),
    ("crease_error_mean_deg", "removed crease error °", "low", "mean", "{:.1f}"),
    ("intersecting_new_faces", "intersecting faces", "low", "sum", "{:d}"),
    ("new_vertices", "new V", None, "sum", "{:d}"),
    ("faces", "new F", None, "sum", "{:d}"),
]
CHART_METRICS = ["dist_patch_to_gt_mean_permille", "dist_gt_to_patch_mean_permille", "normal_dev_mean_deg",
                 "quality_mean", "quality_min", "edge_ratio", "border_dihedral_excess_deg", "seconds"]
HEADINGS = {m[0]: m[1] for m in METRICS} | {"seconds": "seconds per hole"}
SIZE_ORDER = ["small", "medium", "large", "irregular", "real-size", "given", "crease", "crossing", "noisy", "natural", "outline"]


def short_label(label):
    """Filter labels without the common ``meshing_close_holes_`` prefix (for charts)."""
    return label.replace("meshing_close_holes_", "").replace("meshing_close_holes", "close_holes")


def filler_colors(labels):
    """One tab10 colour (RGBA tuple) per filler label, in order: {label: colour}."""
    import matplotlib

    cmap = matplotlib.colormaps["tab10"]
    return {label: cmap(i % 10) for i, label in enumerate(labels)}


def closed_values(rows, key):
    """The finite numeric values of ``key`` over the closed holes among ``rows`` (hole-row dicts)."""
    return [r[key] for r in rows if r.get("closed") and isinstance(r.get(key), (int, float))
            and r.get(key) is not None and np.isfinite(r[key])]


def aggregate(rows, key, how):
    """``how`` ("mean", "min", "max" or "sum") of ``key`` over the closed holes among ``rows``; None if none."""
    vals = closed_values(rows, key)
    if not vals:
        return None
    return {"mean": np.mean, "min": np.min, "max": np.max, "sum": np.sum}[how](vals).item()


def hole_seconds(row):
    """Seconds for one hole: the filter's own per-hole time, else the run time / holes in the run."""
    return row.get("seconds") if row.get("seconds") is not None else row.get("_run_share")
