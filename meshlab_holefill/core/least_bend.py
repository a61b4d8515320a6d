"""A fallback the filters share: the loop triangulated by least bend against the mesh beside it.

Where a hole's border is jagged (cut through triangles, or a noisy scan), the mesh faces on the
loop edges tilt every way and a patch begun from the loop alone folds onto them; every filter
then refuses its patch for crossing the mesh. :func:`meshlab_holefill.geometry.dihedral_triangulation.dihedral_triangulation`
(Liepa's weight) starts from the triangulation that bends least against those faces, and where
some of its triangles still cross the surroundings it is made again without them.
"""
from __future__ import annotations

import numpy as np

from ..errors import HoleFillError
from ..geometry.dihedral_triangulation import dihedral_triangulation
from .crossings import context_crossings

__all__ = ["MAX_EDGES", "ROUNDS", "least_bend_triangulations"]

#: Triangulations tried at most: each round bans the triangles of the one before that crossed.
ROUNDS = 3
#: Longest loop triangulated: the programme's time grows as k^3 (0.014-0.043 s a round at 300-500 edges,
#: 0.28 s at 1000) and its tables as k^2.
MAX_EDGES = 500


def least_bend_triangulations(ctx, rounds=ROUNDS):
    """Triangulations of the hole's loop by least bend, each without the crossing triangles of those before.

    Parameters
    ----------
    ctx : HoleContext
    rounds : int

    Yields
    ------
    F : (k - 2, 3) int64
        Triangles of loop indices, oriented as the loop (patch orientation). The next one comes
        only while the last crossed the surroundings or itself, and some triangulation avoids
        the triangles banned so far. Nothing for loops longer than :data:`MAX_EDGES`.
    """
    if ctx.size > MAX_EDGES:
        return
    banned = np.zeros((0, 3), np.int64)
    for _ in range(rounds):
        try:
            F = dihedral_triangulation(ctx.points, ctx.border_normals, ctx.forbidden_edges, banned)
        except HoleFillError:
            return
        yield F
        crossing = context_crossings(ctx, ctx.points, F)
        if not len(crossing):
            return
        banned = np.concatenate([banned, F[crossing]])
