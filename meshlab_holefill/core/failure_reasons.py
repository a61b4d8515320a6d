"""What a failed hole's reason adds about its surroundings: an island's outline, a mesh that already crosses itself.

A hole fails when its patch would cross the mesh. Two causes lie in the mesh rather than in the
filter, and the reason names them, so the user knows what to repair or to leave.
"""
from __future__ import annotations

from .crossings import surroundings_crossing_themselves
from .outlines import outline_ratio

__all__ = ["RINGS_SEEN", "explain_folded_surroundings", "explain_outlines"]


def explain_outlines(V, F, crossing, report, incidence, pinch=None):
    """Say so when a rejected loop is the outline of a whole island rather than a hole.

    Range scans hold small fragments whose only border is their outline; capping it lays a
    second sheet over the fragment, which the intersection check rightly refuses. The
    reason then tells the user it is not a hole (outlines.outline_ratio: grown from the loop,
    where labelling the whole mesh took 0.06 s of serial time on face000.ply). ``pinch`` is
    :func:`.outlines.pinch_vertices` of the mesh's loops.
    """
    for i, loop in crossing:
        ratio = outline_ratio(V, F, loop, incidence, pinch)
        if ratio is not None:
            report[i]["reason"] += (f"; the loop outlines its whole component (encloses {ratio:.0%} of its area): "
                                    "an island of the mesh, not a hole")


#: Rings of faces around a failed hole searched for faces that already cross each other.
RINGS_SEEN = 2


def explain_folded_surroundings(V, F, loops, report, incidence):
    """Say so when the mesh beside a failed hole already crosses itself: no patch may cross those faces."""
    for entry in report:
        if entry.get("status") != "failed" or incidence is None:
            continue
        count = surroundings_crossing_themselves(V, F, loops[entry["hole"]], incidence, RINGS_SEEN)
        if count:
            entry["reason"] += (f"; the mesh beside this hole already crosses itself ({count} faces within "
                                f"{RINGS_SEEN} rings of its border cross other faces; Select Self Intersecting "
                                "Faces shows them)")
