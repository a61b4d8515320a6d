"""The last results of a costly pure function of arrays, kept by the content of its arguments.

A curve-unfolding fill solves the same sparse system more than once for one hole (see
:data:`.embedding.AREA_SOLVES`): the answer kept from the first time is the same array, bit for bit.
"""
from __future__ import annotations

from collections import OrderedDict

import numpy as np

from ...core.content_key import content_key

__all__ = ["RecentSolves"]


class RecentSolves:
    """Results (arrays) by the content of their inputs, the most recent ones within ``max_bytes``.

    Parameters
    ----------
    max_bytes : int
        Bytes of results kept; the least recently used go first.
    """

    def __init__(self, max_bytes):
        self.max_bytes = int(max_bytes)
        self._kept = OrderedDict()  # digest -> result
        self.nbytes = 0  # of the results kept

    def __len__(self):
        return len(self._kept)

    def clear(self):
        self._kept.clear()
        self.nbytes = 0

    key = staticmethod(content_key)

    def get(self, key):
        """The result kept for ``key`` (a copy), or None."""
        result = self._kept.get(key)
        if result is None:
            return None
        self._kept.move_to_end(key)
        return result.copy()

    def computed(self, key, compute):
        """The result kept for ``key``, else ``compute()``, kept; a copy either way."""
        result = self.get(key)
        if result is None:
            result = compute()
            self.put(key, result)
        return result

    def put(self, key, result):
        """Keep a copy of ``result`` for ``key``, then forget the oldest results beyond ``max_bytes``."""
        if key in self._kept:
            self.nbytes -= self._kept.pop(key).nbytes
        self._kept[key] = np.array(result)
        self.nbytes += self._kept[key].nbytes
        while self._kept and self.nbytes > self.max_bytes:
            self.nbytes -= self._kept.popitem(last=False)[1].nbytes
