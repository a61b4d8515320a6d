"""evaluation.cut_holes: holes of the requested sizes and shapes, simple, apart, with their removed faces."""
from __future__ import annotations

import numpy as np

from meshlab_holefill.core.holes import boundary_loops
from meshlab_holefill.evaluation.cut_holes import SIZE_CLASSES, cut_holes, hole_plan

from evaluation_meshes import sphere


def test_cut_holes_simple_apart_with_ground_truth():
    V, F = sphere(4)
    plan = hole_plan(4, ("small", "medium"))
    F_cut, holes = cut_holes(V, F, sizes=[p[0] for p in plan], shapes=[p[1] for p in plan], seed=3)
    assert [h.shape for h in holes] == ["compact", "irregular", "compact", "irregular"]
    loops = boundary_loops(F_cut)
    assert len(loops) == 4 and not any(lp.pinched for lp in loops)
    for h in holes:
        target = SIZE_CLASSES[h.size_class]
        assert 0.8 * target <= h.boundary_edges <= 1.5 * target
    # holes are apart: no two holes share a vertex
    sets = [set(np.unique(h.removed_faces)) for h in holes]
    assert all(not (a & b) for i, a in enumerate(sets) for b in sets[i + 1:])
    # removed + remaining faces are the original mesh
    assert sum(len(h.removed_faces) for h in holes) + len(F_cut) == len(F)

