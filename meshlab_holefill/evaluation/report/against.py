"""A comparison against an earlier run of the same holes: what changed, filler by filler and class by class.

An earlier run's ``results.csv`` (:func:`.write.write_csv`) is read back (:func:`read_results_csv`)
and set beside this run's hole rows (:func:`against_table`): per filler and hole class, the holes
closed then and now, and the mean patch→ground-truth distance and removed crease error on the
holes both runs closed. A hole is the same hole when its case, number and boundary edges agree.
"""
from __future__ import annotations

import csv

import numpy as np

from .labels import SIZE_ORDER, short_label

__all__ = ["read_results_csv", "against_table", "AGAINST_METRICS"]

#: The metrics compared (hole-row key, heading, format): distance to the removed surface, and the
#: error of the removed creases (holes a crease runs through).
AGAINST_METRICS = (("dist_patch_to_gt_mean_permille", "patch→GT mean ‰", "{:.3f}"),
                   ("crease_error_mean_deg", "removed crease error °", "{:.1f}"))

_REQUIRED = ("case", "filler", "hole", "size_class", "boundary_edges", "closed", "ground_truth")


def read_results_csv(path):
    """The hole rows of a ``results.csv`` written by :func:`.write.write_csv`, with the columns compared here.

    Parameters
    ----------
    path : str

    Returns
    -------
    list of dict
        ``case``, ``filler``, ``size_class`` (str), ``hole``, ``boundary_edges`` (int), ``closed``,
        ``ground_truth`` (bool) and the :data:`AGAINST_METRICS` (float, None where empty).

    Raises
    ------
    ValueError
        When the file lacks a column every results.csv has (not a results.csv of this package).
    """
    with open(path, newline="") as fh:
        reader = csv.DictReader(fh)
        missing = [key for key in _REQUIRED if key not in (reader.fieldnames or ())]
        if missing:
            raise ValueError(f"'{path}' is not a results.csv of a comparison: no column {', '.join(missing)}")
        rows = []
        for raw in reader:
            row = {"case": raw["case"], "filler": raw["filler"], "size_class": raw["size_class"],
                   "hole": int(raw["hole"]), "boundary_edges": int(raw["boundary_edges"]),
                   "closed": raw["closed"] == "True", "ground_truth": raw["ground_truth"] == "True"}
            for key, _, _ in AGAINST_METRICS:
                row[key] = _number(raw.get(key))
            rows.append(row)
    return rows


def _number(text):
    """A csv cell as a finite float, None for an empty, "None" or non-finite cell."""
    try:
        value = float(text)
    except (TypeError, ValueError):
        return None
    return value if np.isfinite(value) else None


def _hole(row):
    return row["case"], int(row["hole"]), int(row["boundary_edges"])


def _value(row, key):
    """The row's finite number for ``key``, or None."""
    value = row.get(key)
    return float(value) if isinstance(value, (int, float)) and np.isfinite(value) else None


def _mean(values):
    return float(np.mean(values)) if values else None


def _pair(before, now, fmt):
    def text(value):
        return "–" if value is None else fmt.format(value)

    return "–" if before is None and now is None else f"{text(before)} → {text(now)}"


def against_table(previous, current):
    """Rows = (filler, hole class), for the fillers and holes both runs have: closed then → now, metrics then → now.

    Parameters
    ----------
    previous : list of dict  an earlier run's hole rows (:func:`read_results_csv`)
    current : list of dict  this run's (``Comparison.holes``)

    Returns
    -------
    header : list of str
    rows : list of list of str  each metric's mean over the holes of the class both runs closed
        (for the crease error, those of them with a removed crease), "before → now"
    """
    before = {(r["filler"], _hole(r)): r for r in previous}
    pairs = {}  # (filler, class) -> [(row before, row now)]
    for r in current:
        old = before.get((r["filler"], _hole(r)))
        if old is not None:
            pairs.setdefault((r["filler"], r["size_class"]), []).append((old, r))
    fillers = list(dict.fromkeys(r["filler"] for r in current))
    order = {s: i for i, s in enumerate(SIZE_ORDER)}
    header = ["filler", "holes", "closed before → now"] + [heading for _, heading, _ in AGAINST_METRICS]
    rows = []
    for filler in fillers:
        classes = sorted({c for f, c in pairs if f == filler}, key=lambda c: (order.get(c, len(order)), c))
        for size_class in classes:
            both = pairs[(filler, size_class)]
            closed_both = [(a, b) for a, b in both if a["closed"] and b["closed"]]
            cells = [f"`{short_label(filler)}`", f"{size_class} ({len(both)})",
                     f"{sum(a['closed'] for a, _ in both)} → {sum(b['closed'] for _, b in both)}"]
            for key, _, fmt in AGAINST_METRICS:
                values = [(_value(a, key), _value(b, key)) for a, b in closed_both]
                measured = [(x, y) for x, y in values if x is not None and y is not None]
                cells.append(_pair(_mean([a for a, _ in measured]), _mean([b for _, b in measured]), fmt))
            rows.append(cells)
    return header, rows
