"""core.border_bend: the mean angle between the mesh and the patch across a hole's border."""
import doctest

import numpy as np
import pytest

from meshlab_holefill.core import border_bend as border_bend_module
from meshlab_holefill.core.border_bend import border_bend
from meshlab_holefill.core.holes import boundary_loops, hole_context

from conftest import cut_disks, grid


def test_examples_run():
    result = doctest.testmod(border_bend_module)
    assert result.attempted > 0 and result.failed == 0


def test_border_bend_is_zero_on_a_plane_and_the_crease_angle_on_a_folded_cap():
    V, F = grid(9, 9)
    _, F, _ = cut_disks(V, F, [(0.5, 0.5, 0.0)], 0.25)
    ctx = hole_context(V, F, min(boundary_loops(F), key=len), rings=2)
    k = ctx.size
    fan = np.array([[k, i, (i + 1) % k] for i in range(k)])
    centre = ctx.points.mean(axis=0, keepdims=True)
    assert border_bend(ctx, centre, fan) == pytest.approx(0.0, abs=1e-6)
    # the same fan lifted: every border face meets a face tilted by the cone's slope
    lift = 0.2
    slopes = np.degrees(np.arctan2(lift, np.linalg.norm(ctx.points[:, :2] - centre[:, :2], axis=1)))
    bend = border_bend(ctx, centre + [0, 0, lift], fan)
    assert slopes.min() - 1e-6 < bend < slopes.max() + 1e-6
    # reversed faces turn against the surface: the supplement
    assert border_bend(ctx, centre, fan[:, ::-1]) == pytest.approx(180.0, abs=1e-6)
