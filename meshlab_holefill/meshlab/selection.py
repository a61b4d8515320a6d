"""Selections written into a MeshSet layer (pymeshlab's selection arrays are read-only)."""
from __future__ import annotations

import numpy as np

__all__ = ["MAX_SELECTION_RANGES", "index_ranges", "set_selection"]


MAX_SELECTION_RANGES = 256  # index ranges written into one selection condition (about 30 characters each)


def index_ranges(mask):
    """Runs of True in a boolean mask as half-open (start, stop) index pairs, in order."""
    mask = np.asarray(mask, bool).ravel()
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.view(np.int8), [0]])))
    return list(zip(edges[0::2].tolist(), edges[1::2].tolist()))


def set_selection(ms, selected, element="face"):
    """Select exactly the faces (or vertices, ``element="vertex"``) where ``selected`` is True.

    pymeshlab's selections are read-only arrays, so a conditional selection writes them. The
    condition names index ranges (``fi`` / ``vi``, the element's index), which covers the usual
    masks (new faces at the end, a few selected blocks) and leaves nothing behind on the layer.
    A mask of more than MAX_SELECTION_RANGES runs goes in as a custom scalar attribute
    ``holefill_select`` instead, which then stays on the layer (pymeshlab cannot remove one).
    """
    m = ms.current_mesh()
    ranges = index_ranges(selected)
    if len(ranges) <= MAX_SELECTION_RANGES:
        index = "fi" if element == "face" else "vi"
        condition = " || ".join(f"({index} >= {a} && {index} < {b})" for a, b in ranges) or "0"
    else:
        getattr(m, f"add_{element}_custom_scalar_attribute")(np.asarray(selected, np.float64), "holefill_select")
        condition = "holefill_select > 0"
    getattr(ms, f"compute_selection_by_condition_per_{element}")(condselect=condition)
