"""The comparison report: tables and text (:mod:`.tables`), charts (:mod:`.plots`), per-hole pictures (:mod:`.render`), files (:mod:`.write`).

``report.write.write_report(comparison, directory)`` writes everything; :mod:`.labels` holds
the headings, size-class order, short labels, colours and aggregates the others share;
:mod:`.against` sets a run beside an earlier run's results.csv.
"""

__all__ = ["against", "labels", "plots", "render", "tables", "write"]
