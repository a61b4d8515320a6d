"""Per-hole progress from MeshSet filter calls, whose signature holds filter parameters only.

>>> from meshlab_holefill.meshlab.progress import reporting
>>> with reporting(lambda hole, total: print(hole, total)):
...     ms.meshing_close_holes_min_angle_bilateral()

Inside the ``with`` block every filter of this package calls ``callback(hole_id, total)``
after each hole it fills (``hole_id`` is the hole's number in the result dict, ``total``
the number of holes being filled), as :func:`meshlab_holefill.core.pipeline.fill_mesh_holes`
does with its ``progress`` argument. The callback is held in a context variable, so threads
and asyncio tasks each see their own.
"""
from __future__ import annotations

import contextlib
import contextvars

__all__ = ["current_callback", "reporting"]

_CALLBACK: contextvars.ContextVar = contextvars.ContextVar("meshlab_holefill_progress", default=None)


@contextlib.contextmanager
def reporting(callback):
    """Within the block, filters of this package report each filled hole to ``callback(hole_id, total)``."""
    token = _CALLBACK.set(callback)
    try:
        yield callback
    finally:
        _CALLBACK.reset(token)


def current_callback():
    """The callback set by the innermost :func:`reporting` block, or None."""
    return _CALLBACK.get()
