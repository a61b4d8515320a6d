"""Hu et al. (beyond the paper): the crossing test of a patch, its projection embedding and remembered answers."""
import numpy as np

from meshlab_holefill.algorithms.hu2012.min_angle_bilateral import fill
from meshlab_holefill.core.holes import boundary_loops, hole_context

from conftest import grid


def _disk_patch(n=6):
    """A flat triangulated disk: loop of 4 n points on a square's border first, grid inside."""
    V, F = grid(n, n)
    loops = boundary_loops(F)
    loop = loops[0].vertices[::-1]  # as the boundary of the grid's own (counter-clockwise) faces
    order = np.concatenate([loop, np.setdiff1d(np.arange(len(V)), loop)])
    inv = np.empty(len(V), np.int64)
    inv[order] = np.arange(len(V))
    return V[order].astype(float), inv[F], len(loop)


def test_embeds_in_projection_accepts_a_flat_disk_and_rejects_a_folded_one():
    from meshlab_holefill.algorithms.hu2012.crossing_test import embeds_in_projection
    from meshlab_holefill.geometry.intersections import intersecting_pairs

    V, F, k = _disk_patch()
    # Orientation of the loop as the patch's boundary: faces are counter-clockwise from +z.
    assert embeds_in_projection(V, F, k)
    bumped = V.copy()
    bumped[k:, 2] = 0.3 * np.sin(7 * bumped[k:, 0])  # a height field still embeds
    assert embeds_in_projection(bumped, F, k)
    # Drag one interior vertex far across its neighbours: the patch folds over itself.
    folded = V.copy()
    centre = k + np.argmin(np.linalg.norm(V[k:, :2] - 0.5, axis=1))
    folded[centre, :2] += [0.45, 0.0]
    assert len(intersecting_pairs(folded, F, np.arange(len(F)), np.arange(len(F)))) > 0
    assert not embeds_in_projection(folded, F, k)


def test_embeds_in_projection_rejects_a_doubly_wound_fan():
    # A fan around a centre that winds twice (a helicoid step): every face keeps its
    # orientation over the plane, yet the surface overlaps itself in projection.
    from meshlab_holefill.algorithms.hu2012.crossing_test import embeds_in_projection

    m = 12
    t = np.linspace(0, 4 * np.pi, m, endpoint=False)
    ring = np.stack([np.cos(t), np.sin(t), 0.05 * t], axis=1)
    V = np.concatenate([ring, [[0.0, 0.0, 0.3]]])
    F = np.array([[i, (i + 1) % m, m] for i in range(m)])
    assert not embeds_in_projection(V, F, m)



def test_compiled_turn_test_answers_as_the_numpy_code():
    from meshlab_holefill.algorithms.hu2012._projection_kernels import projected_turns
    from meshlab_holefill.algorithms.hu2012.crossing_test import _turns_numpy

    rng = np.random.default_rng(12)
    V, F, k = _disk_patch()
    answers = set()
    for trial in range(60):
        Q = V[:, :2] + rng.normal(scale=10.0 ** rng.uniform(-4, -0.5), size=(len(V), 2))  # folds at large moves
        G = F if trial % 5 else F[1:]  # a face less: a vertex may lose its full turn or every face
        ok, sure = projected_turns(Q, np.ascontiguousarray(G, np.int64), k, 1e-6)
        assert sure and ok == _turns_numpy(Q, G, k)
        answers.add(bool(ok))
    assert answers == {True, False}


def test_remembered_crossing_answers_are_those_of_the_check():
    from meshlab_holefill.algorithms.hu2012.crossing_test import crosses, crosses_uncached
    from meshlab_holefill.core import examples

    V, F, loop = examples.bowl_with_hole()
    ctx = hole_context(V, F, loop, rings=2)
    patch = fill(ctx)
    X = np.concatenate([ctx.points, patch.vertices])
    pierced = X.copy()
    pierced[ctx.size:] = X[ctx.size:][::-1] + [0.05, 0.0, 0.0]  # new vertices shuffled: the patch folds through itself
    for _ in range(2):  # the second round answers from memory
        assert crosses(ctx, X, patch.faces) is False
        assert crosses(ctx, pierced, patch.faces) is True
    assert crosses_uncached(ctx, pierced, patch.faces) is True
