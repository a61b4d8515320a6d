"""The report's tables and text: summary, per size class, per hole, failures, as Markdown and HTML.

A report is a list of blocks (headings, paragraphs, lists, tables, images) that
:func:`to_markdown` and :func:`to_html` render; :func:`report_blocks` builds the whole
report, :func:`summary_blocks` the summary that the benchmark also writes into the README.
:mod:`.write` writes the files.
"""
from __future__ import annotations

import html
import json
import time

import numpy as np

from ..anchors import is_anchor
from ..reference_targets import reference_table
from .labels import METRICS, SIZE_ORDER, aggregate, short_label

__all__ = ["failures", "hole_table", "introduction", "markdown_table", "report_blocks", "size_table",
           "summary_blocks",
           "summary_table", "to_html", "to_markdown", "wins"]

def _fmt(value, fmt):
    if value is None:
        return "–"
    if fmt.endswith("d}"):
        return fmt.format(int(round(value)))
    return fmt.format(value)


def _best(values, better):
    """Index set of the best values (ties kept)."""
    pairs = [(i, v) for i, v in enumerate(values) if v is not None]
    if not pairs or better is None:
        return set()
    score = {"low": lambda v: v, "high": lambda v: -v, "one": lambda v: abs(np.log(max(v, 1e-9)))}[better]
    top = min(score(v) for _, v in pairs)
    return {i for i, v in pairs if abs(score(v) - top) <= 1e-12 * max(1.0, abs(top))}


# -------------------------------------------------------------------------------- tables

def wins(comparison):
    """Per filler: holes where its patch→GT distance is the best (holes with ground truth).

    Returns
    -------
    dict  {filler label: number of holes}
    """
    out = {f.label: 0 for f in comparison.fillers}
    for rows in _by_hole(comparison).values():
        vals = [r.get("dist_patch_to_gt_mean_permille") if r.get("closed") else None for r in rows]
        for i in _best(vals, "low"):
            out[rows[i]["filler"]] += 1
    return out


def _by_hole(comparison):
    groups = {}
    for r in comparison.holes:
        groups.setdefault((r["case"], r["hole"]), []).append(r)
    return groups


def summary_table(comparison):
    """The per-filler summary over all holes: one row per filler, one column per metric.

    Parameters
    ----------
    comparison : comparison.Comparison

    Returns
    -------
    header : list of str
    rows : list of list of str
    bold : list of set of int  per row, the columns where the filler is best
    """
    labels = [f.label for f in comparison.fillers]
    rows_by = {lab: [r for r in comparison.holes if r["filler"] == lab] for lab in labels}
    runs_by = {lab: [r for r in comparison.runs if r["filler"] == lab] for lab in labels}
    win = wins(comparison)
    # "best distance on": holes with ground truth only (a scan's own holes have none)
    has_gt = any(r["ground_truth"] for r in comparison.holes)
    keys = [m for m in METRICS if any(r.get(m[0]) is not None for r in comparison.holes)]
    first = 3 if has_gt else 2
    header = (["filter", "holes closed"] + ["best distance on"] * has_gt + [m[1] for m in keys]
              + ["originals changed", "seconds (all runs)"])
    closed_counts = [sum(1 for r in rows_by[lab] if r.get("closed")) for lab in labels]
    # Only fillers that closed (nearly) the most holes compete for bold: a mean over fewer, easier holes
    # is no win; with a single contender nothing is bold.
    eligible = [c >= 0.9 * max(closed_counts) for c in closed_counts]
    if sum(eligible) < 2:
        eligible = [False] * len(labels)
    columns = []
    for key, _, better, how, fmt in keys:
        vals = [aggregate(rows_by[lab], key, how) for lab in labels]
        columns.append(([_fmt(v, fmt) for v in vals], _best([v if ok else None for v, ok in zip(vals, eligible)],
                                                            better)))
    table, bold = [], []
    for i, lab in enumerate(labels):
        hr = rows_by[lab]
        closed = sum(1 for r in hr if r.get("closed"))
        line = [f"`{lab}`", f"{closed}/{len(hr)}"] + [str(win[lab])] * has_gt + [c[0][i] for c in columns]
        line += [str(sum(r.get("originals_changed") or 0 for r in runs_by[lab])),
                 f"{sum(r.get('seconds') or 0 for r in runs_by[lab]):.2f}"]
        table.append(line)
        bold.append({first + j for j, c in enumerate(columns) if i in c[1]})
    return header, table, bold


def size_table(comparison, key="dist_patch_to_gt_mean_permille", fmt="{:.3f}", better="low"):
    """Rows = size classes, columns = fillers: mean of ``key`` over closed holes (closed/total).

    Parameters
    ----------
    comparison : comparison.Comparison
    key : str  a hole-row metric
    fmt : str  format of a value
    better : "low" | "high" | "one"  which values are set in bold

    Returns
    -------
    (header, rows, bold) as :func:`summary_table`
    """
    labels = [f.label for f in comparison.fillers]
    sizes = [s for s in SIZE_ORDER if any(r["size_class"] == s and (r["ground_truth"] or not key.startswith("dist"))
                                          and (not key.startswith("crease") or r.get(key) is not None)
                                          for r in comparison.holes)]
    header = ["holes"] + [f"`{short_label(lab)}`" for lab in labels]
    table, bold = [], []
    for s in sizes:
        cells, vals = [], []
        for lab in labels:
            rs = [r for r in comparison.holes if r["filler"] == lab and r["size_class"] == s]
            v = aggregate(rs, key, "mean")
            vals.append(v)
            cells.append(f"{_fmt(v, fmt)} ({sum(1 for r in rs if r.get('closed'))}/{len(rs)})")
        n = len({(r["case"], r["hole"]) for r in comparison.holes if r["size_class"] == s})
        table.append([f"{s} ({n})"] + cells)
        bold.append({1 + i for i in _best(vals, better)})
    return header, table, bold


def hole_table(comparison):
    """Rows = holes, columns = fillers: patch→GT mean ‰ (or quality mean without ground truth).

    Returns
    -------
    (header, rows, bold) as :func:`summary_table`
    """
    labels = [f.label for f in comparison.fillers]
    header = (["mesh", "hole", "size", "shape", "edges", "corner q bound", "measure"]
              + [f"`{short_label(lab)}`" for lab in labels])
    table, bold = [], []
    for (case, hole), rows in _by_hole(comparison).items():
        by = {r["filler"]: r for r in rows}
        gt = rows[0]["ground_truth"]
        key, fmt, better = (("dist_patch_to_gt_mean_permille", "{:.3f}", "low") if gt
                            else ("quality_mean", "{:.3f}", "high"))
        vals, cells = [], []
        for lab in labels:
            r = by.get(lab, {})
            v = r.get(key) if r.get("closed") else None
            vals.append(v)
            cells.append(_fmt(v, fmt) if r.get("closed") else "open: " + _short_reason(r.get("reason", "")))
        r0 = rows[0]
        table.append([case, str(hole), r0["size_class"], r0["shape"], str(r0["boundary_edges"]),
                      f"{r0.get('quality_bound', 1.0):.2f}", "patch→GT ‰" if gt else "quality"] + cells)
        bold.append({7 + i for i in _best(vals, better)})
    return header, table, bold


def _short_reason(reason):
    reason = reason or "?"
    return reason if len(reason) <= 48 else reason[:45] + "..."


def failures(comparison):
    """One Markdown line per failed run and per hole left open (other than by a failed run)."""
    lines = []
    for r in comparison.runs:
        if r["status"] != "ok":
            lines.append(f"{r['case']} / `{r['filler']}`: **{r['status']}**: {r.get('error')}")
    failed_runs = {(r["case"], r["filler"]) for r in comparison.runs if r["status"] != "ok"}
    for r in comparison.holes:
        if not r.get("closed") and (r["case"], r["filler"]) not in failed_runs:
            lines.append(f"{r['case']} hole {r['hole']} ({r['boundary_edges']} edges) / `{r['filler']}`: {r['reason']}")
    return lines


# ------------------------------------------------------------------------------- document

def markdown_table(header, rows, bold=None):
    """A Markdown table; ``bold[i]`` holds the column indices of row i set in bold.

    Parameters
    ----------
    header : list of str
    rows : list of list of str
    bold : list of set of int, optional
    """
    bold = bold or [set()] * len(rows)
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for row, b in zip(rows, bold):
        out.append("| " + " | ".join(f"**{c}**" if j in b else c for j, c in enumerate(row)) + " |")
    return "\n".join(out)


def _inline_html(text):
    text = html.escape(text)
    parts = text.split("`")
    text = "".join(f"<code>{p}</code>" if i % 2 else p for i, p in enumerate(parts))
    parts = text.split("**")
    return "".join(f"<b>{p}</b>" if i % 2 else p for i, p in enumerate(parts))


def _html_table(header, rows, bold=None):
    bold = bold or [set()] * len(rows)
    out = ["<table>", "<tr>" + "".join(f"<th>{_inline_html(h)}</th>" for h in header) + "</tr>"]
    for row, b in zip(rows, bold):
        out.append("<tr>" + "".join(f"<td class='best'>{_inline_html(c)}</td>" if j in b else f"<td>{_inline_html(c)}</td>"
                                    for j, c in enumerate(row)) + "</tr>")
    return "\n".join(out + ["</table>"])


def to_markdown(blocks):
    """Markdown of report blocks: ("h", level, text), ("p", text), ("list", items), ("table", header, rows,
    bold), ("img", path, caption)."""
    out = []
    for kind, *args in blocks:
        if kind == "h":
            out.append("#" * args[0] + " " + args[1])
        elif kind == "p":
            out.append(args[0])
        elif kind == "list":
            out.append("\n".join(f"- {x}" for x in args[0]))
        elif kind == "table":
            out.append(markdown_table(*args))
        elif kind == "img":
            out.append(f"![{args[1]}]({args[0]})")
    return "\n\n".join(out) + "\n"


def to_html(blocks, title):
    """A standalone HTML page of the same blocks as :func:`to_markdown`."""
    css = ("body{font-family:sans-serif;max-width:1400px;margin:auto;padding:1em}table{border-collapse:collapse;"
           "margin:1em 0;font-size:90%}td,th{border:1px solid #ccc;padding:3px 6px;text-align:right}"
           "td:first-child,th:first-child{text-align:left}td.best{background:#d8f5d0;font-weight:bold}"
           "img{max-width:100%;border:1px solid #eee}code{font-size:95%}")
    out = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
           f"<style>{css}</style></head><body>"]
    for kind, *args in blocks:
        if kind == "h":
            out.append(f"<h{args[0]}>{_inline_html(args[1])}</h{args[0]}>")
        elif kind == "p":
            out.append(f"<p>{_inline_html(args[0])}</p>")
        elif kind == "list":
            out.append("<ul>" + "".join(f"<li>{_inline_html(x)}</li>" for x in args[0]) + "</ul>")
        elif kind == "table":
            out.append(_html_table(*args))
        elif kind == "img":
            out.append(f"<figure><img src='{html.escape(args[0])}' alt='{html.escape(args[1])}'>"
                       f"<figcaption>{_inline_html(args[1])}</figcaption></figure>")
    return "\n".join(out + ["</body></html>"])


def summary_blocks(comparison):
    """The summary (also the README's Results section): settings line, summary and size tables."""
    blocks = [("table", *summary_table(comparison))]
    if any(r["ground_truth"] for r in comparison.holes):
        blocks += [("p", "Mean patch→ground-truth distance (‰ of the bounding-box diagonal) per hole size, over "
                         "the holes each filter closed (closed/total):"),
                   ("table", *size_table(comparison))]
    blocks += [("p", "Mean triangle quality 2r/R of the new faces per hole size:"),
               ("table", *size_table(comparison, "quality_mean", "{:.3f}", "high"))]
    if any(r.get("crease_error_mean_deg") is not None for r in comparison.holes):
        blocks += [("p", "Removed crease error (degrees; holes whose removed surface has edges sharper than 30°): "
                         "per crease edge, |its dihedral angle − the patch's best-matching dihedral within one edge "
                         "length| (0 when none: flat there), length-weighted mean; a flat cap scores the crease angle:"),
                   ("table", *size_table(comparison, "crease_error_mean_deg", "{:.1f}", "low"))]
    baseline = "meshing_close_holes (all holes)"
    if any(f.label == baseline for f in comparison.fillers):
        header, rows, bold = reference_table(comparison, baseline)
        if rows:
            blocks += [("p", f"Reference figures and where each filter stands against them (the baseline is `{baseline}`); "
                             "✓ met, ✗ not met. A hole's minimum quality is judged against min(0.3, the best a patch "
                             "can reach at its sharpest convex border corner); 'natural' excludes loops that outline "
                             "a whole island of the scan:"),
                       ("table", header, rows, bold)]
    return blocks


def introduction(comparison):
    """The paragraph saying what is measured, for the kinds of hole in the comparison.

    Distances to a ground truth are explained only where some hole has one (holes cut into a
    closed mesh, or given); a scan's own holes (no ground truth) are judged by the patch alone.
    """
    has_gt = any(r["ground_truth"] for r in comparison.holes)
    scans = [c["case"] for c in comparison.cases if c["kind"] == "natural holes"]
    text = []
    if has_gt:
        text.append("Distances are in per mille (‰) of the mesh's bounding-box diagonal, between the patch and the "
                    "removed ground-truth surface: 20,000 points spread by area over one surface (seeded, so a "
                    "figure depends only on the two surfaces), each at its exact distance from the other surface "
                    "(MeshLab's per-vertex distance filter).")
    if scans:
        text.append(f"{', '.join(scans)} {'is a mesh' if len(scans) == 1 else 'are meshes'} with holes of "
                    f"{'its' if len(scans) == 1 else 'their'} own (a scan): there is no true surface under "
                    "them, so each patch is judged by itself (triangle quality, edge ratio, border crease, "
                    "intersections, time). Holes are numbered by boundary loop, as `meshlab-holefill holes` and the "
                    "filters' results number them; loops that outline a whole island are listed as `outline`, apart "
                    "from the holes.")
    text.append("Quality is Field's 2r/R (1 = equilateral). Edge ratio = mean new edge length / mean edge length "
                "around the hole. Border crease = angle between the normals of the mesh face and the patch face at "
                "each hole border edge" + ("; 'crease − GT's' compares it with the ground truth's." if has_gt else ".")
                + (" 'Removed crease error' measures the creases inside the removed surface (edges sharper than 30°): "
                   "per crease edge the difference between its dihedral angle and the patch's best-matching one "
                   "within an edge length (0 where the patch is flat there), length-weighted "
                   "(`metrics.crease_metrics`)." if has_gt else "")
                + " Means are over the holes each filter closed; in the summary the best value per column is bold "
                "among the filters that closed at least 90 % as many holes as the best one.")
    return " ".join(text)


def _per_hole_text(comparison):
    has_gt = any(r["ground_truth"] for r in comparison.holes)
    has_scan = any(not r["ground_truth"] for r in comparison.holes)
    if has_gt and has_scan:
        return ("Patch→GT mean distance (‰) where the hole has ground truth, else the mean quality of the new "
                "triangles; the best filter per hole in bold.")
    if has_gt:
        return "Patch→GT mean distance (‰) per hole; the best filter per hole in bold."
    return "Mean quality 2r/R of the new triangles per hole; the best filter per hole in bold."


def _anchor_note(comparison):
    """A paragraph on the third-party fillers in the comparison (what their per-hole figures mean)."""
    names = {f.filter for f in comparison.fillers if is_anchor(f.filter)}
    if not names:
        return []
    text = "Third-party anchors: "
    parts = []
    if "cgal_liepa" in names:
        parts.append("`cgal_liepa` is CGAL's triangulate_refine_and_fair_hole (Liepa: triangulation, refinement, "
                     "fairing), called once per hole with its own time")
    if "pymeshfix" in names:
        parts.append("`pymeshfix` is MeshFix's fill_small_boundaries, called once for the whole mesh (it cannot "
                     "fill one chosen hole): its patches are still made hole by hole, so distances and qualities "
                     "are per hole as for the others, but its seconds per hole are the run time shared out")
    skipped = sorted({r["filler"] for r in comparison.runs if r["status"] == "skipped"})
    tail = f" Skipped (package not installed): {', '.join(f'`{s}`' for s in skipped)}." if skipped else ""
    return [("p", text + "; ".join(parts) + ". Their output is mapped back to the original numbering, so every "
                  "metric is computed the same way." + tail)]


def report_blocks(comparison, pictures, command=None):
    """Blocks of the whole report.

    Parameters
    ----------
    comparison : comparison.Comparison
    pictures : list of (relative path, caption)
    command : str, optional  the command line that made the comparison

    Returns
    -------
    list of blocks (see :func:`to_markdown`)
    """
    settings = comparison.settings
    cases = ", ".join(f"{c['case']} ({c['faces']} faces, {len(c['holes'])} {c['kind']})" for c in comparison.cases)
    blocks = [("h", 1, "Hole filler comparison"),
              ("p", f"{time.strftime('%Y-%m-%d %H:%M')}, {settings['cores']} cores, "
                    f"{comparison.wall_seconds:.1f} s wall time (runs and metrics). Meshes: {cases}. "
                    + (f"Command: `{command}`." if command else "")),
              ("p", introduction(comparison)),
              *_anchor_note(comparison),
              ("h", 2, "Summary"), *summary_blocks(comparison),
              ("h", 2, "Per hole"),
              ("p", _per_hole_text(comparison)),
              ("table", *hole_table(comparison))]
    fails = failures(comparison)
    blocks += [("h", 2, "Failures and open holes"), ("list", fails) if fails else ("p", "None.")]
    notes = [f"{c['case']}: {n}" for c in comparison.cases for n in c["notes"]]
    if notes:
        blocks += [("h", 2, "Notes"), ("list", notes)]
    blocks += [("h", 2, "Pictures")]
    for path, caption in pictures:
        blocks.append(("img", path, caption))
    cut = any(c["kind"] == "cut holes" for c in comparison.cases)
    blocks += [("h", 2, "Settings"),
               ("list", [f"`{f['label']}`: `{f['filter']}` {json.dumps(f['params'])}" for f in settings["fillers"]]
                + ([f"holes per closed mesh: {settings['holes']}, sizes {settings['sizes']}, seed {settings['seed']}"]
                   if cut else [])
                + ([f"natural holes evaluated up to {settings['maxholesize']} boundary edges"]
                   if any(c["kind"] == "natural holes" for c in comparison.cases) else [])
                + [f"timeout {settings['timeout']} s per run"]),
              ("p", "All numbers per hole and filter: `results.csv`, `results.json`.")]
    return blocks
