"""Charts of a comparison (matplotlib, offscreen): metrics per hole size, quality histograms, trends.

Each function writes one PNG into the report directory and returns ``(relative path, caption)``.
"""
from __future__ import annotations

import os

import numpy as np

from ..metrics import QUALITY_BINS
from .labels import CHART_METRICS, HEADINGS, SIZE_ORDER, aggregate, filler_colors, hole_seconds, short_label

__all__ = ["chart_pictures", "metric_bars", "quality_histograms", "size_trends"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def metric_bars(comparison, directory, name="metrics.png"):
    """Grid of bar charts: one panel per metric, bars = fillers grouped by hole size class."""
    plt = _pyplot()
    labels = [f.label for f in comparison.fillers]
    colors = filler_colors(labels)
    rows = comparison.holes
    for r in rows:
        r["seconds_hole"] = hole_seconds(r)
    keys = [k for k in CHART_METRICS if any(r.get(k if k != "seconds" else "seconds_hole") is not None for r in rows)]
    ncol = 4
    nrow = int(np.ceil(len(keys) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.6 * ncol, 3.6 * nrow + 0.8), squeeze=False)
    width = 0.8 / max(len(labels), 1)
    for ax, key in zip(axes.ravel(), keys):
        field = "seconds_hole" if key == "seconds" else key
        # classes where the metric exists (natural holes have no ground-truth metrics)
        sizes = [s for s in SIZE_ORDER if any(r["size_class"] == s and r.get(field) is not None for r in rows)]
        for i, lab in enumerate(labels):
            vals, closed = [], []
            for s in sizes:
                rs = [r for r in rows if r["filler"] == lab and r["size_class"] == s]
                v = aggregate(rs, field, "min" if key == "quality_min" else "mean")
                vals.append(np.nan if v is None else v)
                closed.append(sum(1 for r in rs if r.get("closed")) < len(rs))
            x = np.arange(len(sizes)) + (i - (len(labels) - 1) / 2) * width
            bars = ax.bar(x, vals, width, color=colors[lab], label=short_label(lab))
            for b, v, partial in zip(bars, vals, closed):
                if np.isnan(v):
                    ax.text(b.get_x() + b.get_width() / 2, 0, "×", ha="center", va="bottom", color=colors[lab],
                            fontsize=11, fontweight="bold")
                elif partial:  # some holes of this class stayed open: the mean covers fewer holes
                    b.set_hatch("//")
        ax.set_xticks(np.arange(len(sizes)), sizes)
        ax.set_title(HEADINGS.get(key, key), fontsize=11)
        if key in ("seconds",):
            ax.set_yscale("log")
        if key == "edge_ratio":
            ax.axhline(1.0, color="k", lw=0.8, ls="--")
        if key.startswith("quality"):
            ax.set_ylim(0, 1.05)
            ax.axhline(0.7, color="k", lw=0.6, ls=":")
        ax.grid(axis="y", alpha=0.3)
    for ax in axes.ravel()[len(keys):]:
        ax.axis("off")
    from matplotlib.patches import Patch

    handles = [Patch(color=colors[lab], label=short_label(lab)) for lab in labels]
    fig.legend(handles, [short_label(lab) for lab in labels], loc="upper center", ncol=min(len(labels), 5), fontsize=10, frameon=False)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.55 / fig.get_size_inches()[1]))
    fig.savefig(os.path.join(directory, name), dpi=90)
    plt.close(fig)
    return name, ("Metrics per hole size class (mean over the holes closed; hatched: some holes of the class stayed "
                  "open, × none closed). Lower is better except quality (higher) and edge ratio (1 = density of "
                  "the surrounding mesh).")


def quality_histograms(comparison, directory, name="quality_histograms.png"):
    """Hu et al. Fig. 10: number of new triangles per quality bin, one panel per filler."""
    plt = _pyplot()
    labels = [f.label for f in comparison.fillers]
    colors = filler_colors(labels)
    n = len(labels)
    ncol = min(n, 3)
    nrow = int(np.ceil(n / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(5.0 * ncol, 3.3 * nrow), squeeze=False)
    for ax, lab in zip(axes.ravel(), labels):
        counts = np.zeros(len(QUALITY_BINS) - 1)
        for r in comparison.holes:
            if r["filler"] == lab and r.get("quality_hist"):
                counts += np.asarray(r["quality_hist"])
        ax.bar(QUALITY_BINS[:-1], counts, width=np.diff(QUALITY_BINS), align="edge", color=colors[lab],
               edgecolor="white")
        ax.axvline(0.7, color="k", ls="--", lw=0.8)
        total = counts.sum()
        share = counts[QUALITY_BINS[:-1] >= 0.7 - 1e-9].sum() / total if total else float("nan")
        ax.set_title(f"{short_label(lab)}\n{int(total)} triangles, {100 * share:.0f}% with q ≥ 0.7", fontsize=10)
        ax.set_xlim(0, 1)
        ax.set_xlabel("quality 2r/R")
        ax.set_ylabel("triangles")
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(os.path.join(directory, name), dpi=90)
    plt.close(fig)
    return name, "Quality of the new triangles per filter, all holes pooled (as in Hu et al. Fig. 10)."


def size_trends(comparison, directory, name="error_time_vs_size.png"):
    """Patch→GT distance and seconds per hole against the hole's boundary edges."""
    plt = _pyplot()
    labels = [f.label for f in comparison.fillers]
    colors = filler_colors(labels)
    markers = "osD^v<>ph*"
    has_gt = any(r.get("dist_patch_to_gt_mean_permille") is not None for r in comparison.holes)
    panels = (["dist_patch_to_gt_mean_permille"] if has_gt else ["quality_mean"]) + ["seconds"]
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.6))
    for ax, key in zip(axes, panels):
        for i, lab in enumerate(labels):
            rs = [r for r in comparison.holes if r["filler"] == lab and r.get("closed")]
            x = [r["boundary_edges"] for r in rs]
            y = [hole_seconds(r) if key == "seconds" else r.get(key) for r in rs]
            pts = sorted((a, b) for a, b in zip(x, y) if b is not None and b > 0)
            if not pts:
                continue
            ax.plot(*zip(*pts), marker=markers[i % len(markers)], ls="none", ms=6, alpha=0.8,
                    color=colors[lab], label=short_label(lab))
        ax.set_xscale("log")
        if key != "quality_mean":
            ax.set_yscale("log")
        ax.set_xlabel("hole boundary edges")
        ax.set_ylabel(HEADINGS.get(key, key))
        ax.grid(alpha=0.3, which="both")
    axes[0].legend(fontsize=9)
    axes[0].set_title("error against hole size" if has_gt else "quality against hole size")
    axes[1].set_title("time per hole against hole size")
    fig.tight_layout()
    fig.savefig(os.path.join(directory, name), dpi=90)
    plt.close(fig)
    return name, ("Left: mean patch→ground-truth distance per hole; right: seconds per hole (the filter's own "
                  "per-hole time where it reports one, else its run time divided by the holes).")


def chart_pictures(comparison, directory):
    """All charts of a comparison written into ``directory``: [(relative path, caption)]."""
    return [metric_bars(comparison, directory), quality_histograms(comparison, directory),
            size_trends(comparison, directory)]
