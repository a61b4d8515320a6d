"""Writing a comparison's report: report.md, report.html, results.json, results.csv and the pictures.

``write_report(comparison, directory)`` writes the tables (:mod:`.tables`), the charts
(:mod:`.plots`: bar charts per metric, quality histograms per filter as in Hu et al. Fig. 10,
error and time against hole size) and one rendered view per hole (:mod:`.render`).
"""
from __future__ import annotations

import csv
import json
import os

from .plots import chart_pictures
from .render import hole_pictures
from .tables import report_blocks, to_html, to_markdown

__all__ = ["INSTALL_BENCH", "check_report_dependencies", "write_csv", "write_json", "write_report"]

INSTALL_BENCH = 'pip install "meshlab_holefill[bench]"'


def check_report_dependencies(pictures=True):
    """Raise ModuleNotFoundError, with the install command, when the report's pictures cannot be drawn.

    The charts and hole pictures need matplotlib, which is in the ``bench`` extra, not a core
    dependency; tables, results.json and results.csv need nothing more. Called by
    ``compare(report=...)`` before anything runs, so a missing matplotlib costs no runs.

    Parameters
    ----------
    pictures : bool  whether charts and pictures will be drawn (without them nothing is needed)
    """
    if not pictures:
        return
    try:
        import matplotlib  # noqa: F401
    except ImportError as exc:
        raise ModuleNotFoundError(
            f"the comparison report's charts and pictures need matplotlib, which is not installed ({exc}); "
            f"install it with: {INSTALL_BENCH}  (or write the report without pictures: "
            "pictures=False, meshlab-holefill compare --no-pictures)", name="matplotlib") from exc


def _scalar_rows(comparison):
    rows = []
    for r in comparison.holes:
        row = {k: v for k, v in r.items() if not isinstance(v, (list, dict))}
        rows.append(row)
    return rows


def write_json(comparison, path):
    """results.json: settings, wall time, cases, runs and hole rows of a comparison."""
    data = {"settings": comparison.settings, "wall_seconds": comparison.wall_seconds, "cases": comparison.cases,
            "runs": comparison.runs, "holes": comparison.holes}
    with open(path, "w") as fh:
        json.dump(data, fh, indent=1, default=lambda o: o.item() if hasattr(o, "item") else str(o))


def write_csv(comparison, path):
    """results.csv: one row per (case, hole, filler), scalar columns only."""
    rows = _scalar_rows(comparison)
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=keys)
        writer.writeheader()
        writer.writerows(rows)


def write_report(comparison, directory, pictures=True, command=None, max_pictures=None):
    """Write the whole report into ``directory`` (created).

    Parameters
    ----------
    comparison : comparison.Comparison
    directory : str
    pictures : bool  also the charts and one picture per hole
    command : str, optional  the command line, quoted in the report
    max_pictures : int, optional  picture at most this many holes per mesh (the largest); default all

    Returns
    -------
    str  the path of report.md
    """
    check_report_dependencies(pictures)
    os.makedirs(directory, exist_ok=True)
    for run in comparison.runs:  # per-hole time for filters that give none: the run split over its holes
        holes = [r for r in comparison.holes if r["case"] == run["case"] and r["filler"] == run["filler"]]
        for r in holes:
            r["_run_share"] = (run.get("seconds") or 0.0) / max(len(holes), 1)
    write_json(comparison, os.path.join(directory, "results.json"))
    write_csv(comparison, os.path.join(directory, "results.csv"))
    pics = []
    if pictures:
        pics += chart_pictures(comparison, directory)
        pics += hole_pictures(comparison, directory, max_pictures)
    blocks = report_blocks(comparison, pics, command)
    with open(os.path.join(directory, "report.md"), "w") as fh:
        fh.write(to_markdown(blocks))
    with open(os.path.join(directory, "report.html"), "w") as fh:
        fh.write(to_html(blocks, "Hole filler comparison"))
    return os.path.join(directory, "report.md")
