"""``compare()``: fill holes in meshes with every filler, measure each patch, optionally write the report.

The one call behind ``meshlab-holefill compare`` and ``meshlab_holefill.compare``: a closed
mesh gets holes cut with ground truth (:mod:`.cut_holes`), a mesh with holes is filled as it
is; every filler runs in an isolated worker (:mod:`.comparison`, :mod:`.isolation`);
:mod:`.metrics` measures each patch; :mod:`.report` writes tables, charts and pictures.
"""
from __future__ import annotations

from .comparison import run_comparison
from .report.write import write_report

__all__ = ["compare"]


def compare(meshes, report=None, **options):
    """Fill holes in meshes with every filler and measure them; optionally write a report.

    Parameters
    ----------
    meshes : sequence of str (mesh files), pymeshlab.Mesh, (V, F) tuples or comparison.MeshCase
        A (V, F) tuple is ((n, 3) float, (m, 3) int).
    report : str, optional
        Directory for report.md, report.html, results.json, results.csv and pictures.
    **options
        Passed on to :func:`.comparison.run_comparison`: ``holes`` (per closed mesh, default 4),
        ``sizes`` ("small", "medium", "large"), ``seed``, ``filters`` (names, optionally
        ``name:param=value``), ``refinehole``, ``timeout`` (seconds per run), ``maxholesize``
        (largest natural hole evaluated), ``progress``.

    Returns
    -------
    comparison.Comparison  (``runs``, ``holes`` rows, ``cases``, ``fillers``)
    """
    result = run_comparison(meshes, **options)
    if report is not None:
        write_report(result, report)
    return result
