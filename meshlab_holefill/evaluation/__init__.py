"""Comparing the hole fillers: holes with ground truth, isolated runs, metrics, reference figures, the report.

The evaluation layer sits above ``meshlab`` (it runs the registered filters and MeshLab's own
through :mod:`meshlab_holefill.meshlab`, the only package that imports pymeshlab) and below
the command line (``cli``); nothing below it imports it. Modules:

- :mod:`.compare`: ``compare()``, the one call (cases -> runs -> metrics -> report);
- :mod:`.cut_holes`: holes with known ground truth cut into closed meshes;
- :mod:`.analytic`: the sphere and torus meshed, their exact distance and area;
- :mod:`.creased`: CAD-like meshes with holes a crease runs through, and interpenetrating parts;
- :mod:`.noisy`: scan-like noise along the normals, for cases with jagged hole borders;
- :mod:`.virtual_scan`: range scans of closed meshes, their unseen surface as holes;
- :mod:`.anchors`: third-party fillers (CGAL's Liepa fill, MeshFix), optional, run like ours;
- :mod:`.mesh_cases`: the cases (meshes and their holes with ground truth, prepared once);
- :mod:`.fillers`: the contestants (our filters, the anchors, MeshLab's Close Holes) and their parsing;
- :mod:`.comparison`: running each filler on each case, the hole rows (offers the two above's names too);
- :mod:`.isolation`: the worker processes with timeouts;
- :mod:`.metrics`: distances, quality, normals, creases, the corner quality bound;
- :mod:`.reference_targets`: reference figures and where each filter stands against them;
- :mod:`.report`: tables, charts, per-hole pictures and the report files;
- :mod:`.papers`: the papers' own experiments (Xie and Zou's sphere).
"""

__all__ = ["analytic", "anchors", "compare", "comparison", "creased", "cut_holes", "fillers", "isolation", "mesh_cases", "metrics", "noisy", "papers", "reference_targets", "report",
           "virtual_scan"]
