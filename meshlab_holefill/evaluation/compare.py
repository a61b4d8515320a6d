"""``compare()``: fill holes in meshes with every filler, measure each patch, optionally write the report.

The one call behind ``meshlab-holefill compare`` and ``meshlab_holefill.compare``: a closed
mesh gets holes cut with ground truth (:mod:`.cut_holes`), a mesh with holes is filled as it
is; every filler runs in an isolated worker (:mod:`.comparison`, :mod:`.isolation`);
:mod:`.metrics` measures each patch; :mod:`.report` writes tables, charts and pictures.

It needs no ``if __name__ == "__main__":`` guard: the workers are fresh interpreters that do
not import the caller's script. A report with pictures needs matplotlib (the ``bench``
extra); that is checked before anything runs.
"""
from __future__ import annotations

from .comparison import run_comparison
from .isolation import check_not_bootstrapping
from .report.write import check_report_dependencies, write_report

__all__ = ["compare"]


def compare(meshes, report=None, pictures=True, max_pictures=None, command=None, **options):
    """Fill holes in meshes with every filler and measure them; optionally write a report.

    Parameters
    ----------
    meshes : sequence of str (mesh files), pymeshlab.Mesh, (V, F) tuples or mesh_cases.MeshCase
        A (V, F) tuple is ((n, 3) float, (m, 3) int).
    report : str, optional
        Directory for report.md, report.html, results.json, results.csv and pictures.
    pictures : bool
        With ``report``: also the charts and a picture per hole (these need matplotlib, the
        ``bench`` extra: ``pip install "meshlab_holefill[bench]"``; checked before anything runs).
    max_pictures : int, optional
        Picture at most this many holes per mesh (the ones with most boundary edges); default all.
    command : str, optional
        The command line quoted in the report.
    **options
        Passed on to :func:`.comparison.run_comparison`: ``holes`` (per closed mesh, default 4),
        ``sizes`` ("small", "medium", "large"), ``seed``, ``filters`` (names, optionally
        ``name:param=value``), ``refinehole``, ``timeout`` (seconds per run), ``maxholesize``
        (largest natural hole evaluated), ``progress`` (a bar per run on stderr; default: when
        stderr is a terminal). Each run is also logged (logger ``meshlab_holefill``, level INFO).

    Returns
    -------
    comparison.Comparison  (``runs``, ``holes`` rows, ``cases``, ``fillers``)

    Raises
    ------
    ModuleNotFoundError
        ``report`` with ``pictures`` and matplotlib not installed (before any run).
    RuntimeError
        Called while ``multiprocessing`` re-imports an unguarded script in a child process.
    """
    check_not_bootstrapping()
    if report is not None:
        check_report_dependencies(pictures)
    if max_pictures is not None and (isinstance(max_pictures, bool) or int(max_pictures) != max_pictures
                                     or max_pictures < 0):
        raise ValueError(f"max_pictures must be a whole number >= 0 (or None: every hole), not {max_pictures!r}")
    result = run_comparison(meshes, **options)
    if report is not None:
        write_report(result, report, pictures=pictures, command=command, max_pictures=max_pictures)
    return result
