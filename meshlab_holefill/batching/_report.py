"""The run report of a batch: ``batch.json``, ``batch.csv`` and ``summary.md``, and the BatchReport object."""
from __future__ import annotations

import csv
import json
import os
from dataclasses import dataclass, field

from ._task import _plain

STATUSES = ("ok", "failed", "skipped", "not run")
CSV_FIELDS = ("name", "status", "error", "starts", "closed_holes", "failed_holes", "skipped_holes", "new_vertices",
              "new_faces", "vertices", "faces", "load_s", "fill_s", "save_s", "total_s", "peak_rss_mb", "host", "pid",
              "input", "output", "input_sha256")
SLOWEST = 10


@dataclass
class BatchReport:
    """What a batch did.

    Attributes
    ----------
    files : list of dict
        One record per input file, in input order: ``status`` is ``"ok"`` (repaired now),
        ``"skipped"`` (output up to date), ``"failed"`` (with ``error``) or ``"not run"``
        (interrupted); the per-file result JSON's fields otherwise.
    counts : dict
        Number of files per status.
    seconds : float
        Wall-clock time of the batch.
    out : str
        The output folder (the report files are in it).
    interrupted : bool
        True when the batch was stopped before every file was done.
    settings : dict
        Filter, parameters, script, cluster and the other options of the run.
    paths : dict
        ``json``, ``csv`` and ``summary`` report paths.
    """

    files: list
    counts: dict
    seconds: float
    out: str
    interrupted: bool = False
    settings: dict = field(default_factory=dict)
    paths: dict = field(default_factory=dict)

    @property
    def failed(self):
        """Records of the files that failed."""
        return [r for r in self.files if r["status"] == "failed"]


def _hole_totals(result):
    """Per-hole counts summed over a filter's result or over a script's steps."""
    steps = result.get("steps", [result]) if isinstance(result, dict) else []
    keys = ("closed_holes", "failed_holes", "skipped_holes", "new_vertices", "new_faces")
    totals = {k: None for k in keys}
    for step in steps:
        for k in keys:
            if isinstance(step, dict) and isinstance(step.get(k), (int, float)):
                totals[k] = (totals[k] or 0) + step[k]
    return totals


def csv_row(record):
    """One record as a flat CSV row (see ``CSV_FIELDS``)."""
    seconds = record.get("seconds") or {}
    worker = record.get("worker") or {}
    row = {k: record.get(k) for k in CSV_FIELDS}
    row.update(_hole_totals(record.get("result") or {}))
    row.update({f"{k}_s": seconds.get(k) for k in ("load", "fill", "save", "total")}, host=worker.get("host"),
               pid=worker.get("pid"))
    return row


def make_report(files, seconds, out, interrupted, settings):
    """A BatchReport of per-file records."""
    counts = {s: sum(r["status"] == s for r in files) for s in STATUSES}
    return BatchReport(files, counts, seconds, out, interrupted, settings)


def write_report(report):
    """Write ``batch.json``, ``batch.csv`` and ``summary.md`` into the report's output folder.

    Returns
    -------
    BatchReport
        The same report with ``paths`` filled in.
    """
    os.makedirs(report.out, exist_ok=True)
    paths = {k: os.path.join(report.out, name) for k, name in
             (("json", "batch.json"), ("csv", "batch.csv"), ("summary", "summary.md"))}
    with open(paths["json"], "w") as fh:
        json.dump({"counts": report.counts, "seconds": report.seconds, "interrupted": report.interrupted,
                   "settings": report.settings, "files": report.files}, fh, indent=1, default=_plain)
    with open(paths["csv"], "w", newline="") as fh:
        writer = csv.DictWriter(fh, CSV_FIELDS)
        writer.writeheader()
        writer.writerows(csv_row(r) for r in report.files)
    with open(paths["summary"], "w") as fh:
        fh.write(summary_markdown(report))
    report.paths = paths
    return report


def _seconds(record):
    return (record.get("seconds") or {}).get("total") or 0.0


def summary_markdown(report):
    """The short human summary: counts, the slowest files, every failed file with its reason."""
    s = report.settings
    what = f"script `{s.get('mlx')}`" if s.get("mlx") else f"filter `{s.get('filter')}`"
    params = ", ".join(f"{k}={v}" for k, v in (s.get("params") or {}).items())
    lines = [f"# Batch: {len(report.files)} files, {what}" + (f" ({params})" if params else ""), ""]
    if report.interrupted:
        lines += ["**Interrupted**: files marked `not run` were not finished; run the same command again to "
                  "finish them (finished files are skipped).", ""]
    lines += ["| " + " | ".join(STATUSES) + " | seconds |", "|" + "---|" * (len(STATUSES) + 1),
              "| " + " | ".join(str(report.counts[k]) for k in STATUSES) + f" | {report.seconds:.1f} |", ""]
    ran = sorted((r for r in report.files if r["status"] == "ok"), key=_seconds, reverse=True)[:SLOWEST]
    if ran:
        lines += ["## Slowest files", "", "| file | seconds | holes closed | holes failed | peak MB |",
                  "|---|---|---|---|---|"]
        for r in ran:
            row = csv_row(r)
            peak = f"{row['peak_rss_mb']:.0f}" if row["peak_rss_mb"] is not None else ""
            lines.append(f"| {r['name']} | {_seconds(r):.2f} | {row['closed_holes']} | {row['failed_holes']} | {peak} |")
        lines.append("")
    failed = report.failed
    if failed:
        lines += ["## Failed files", "", "| file | reason |", "|---|---|"]
        lines += [f"| {r['name']} | {str(r.get('error')).splitlines()[0].replace('|', '/')} |" for r in failed]
        lines.append("")
    return "\n".join(lines)
