"""Curve unfolding: the edge swaps that improve the embedded patch's triangles."""

import numpy as np

from meshlab_holefill import HoleFillError
from meshlab_holefill.algorithms.brunton2009 import crossing_repair
from meshlab_holefill.algorithms.brunton2009 import quality_swaps
from meshlab_holefill.algorithms.brunton2009 import unfolded_triangulation as tri
from meshlab_holefill.algorithms.brunton2009.embedding import embed_patch
from meshlab_holefill.geometry.quality import triangle_quality
from meshlab_holefill.core import examples
from meshlab_holefill.core.holes import hole_context
from meshlab_holefill.core.patch import Patch, validate_patch

from brunton_cases import flat_disk_hole


def test_improve_by_swaps_undoes_a_bad_swap_and_keeps_the_energy_solved():
    from meshlab_holefill.geometry.quality import face_normals
    from meshlab_holefill.geometry.topology import interior_edges
    from meshlab_holefill.core.patch import Patch

    ctx = flat_disk_hole()
    k = ctx.size
    vertices, faces = tri.triangulate_and_embed(ctx, ctx.points[:, :2], np.arange(k), [], "area", True)
    s, X = len(vertices), np.concatenate([ctx.points, vertices])
    # Degrade the refined patch by its worst legal swap, then solve E_AREA on that connectivity.
    E, f1, c1, f2, c2 = interior_edges(faces, len(X))
    worst = None
    for i in range(len(E)):
        u, v, c = faces[f1[i], c1[i]], faces[f1[i], (c1[i] + 1) % 3], faces[f1[i], (c1[i] + 2) % 3]
        d = faces[f2[i], (c2[i] + 2) % 3]
        G = faces.copy()
        G[f1[i]], G[f2[i]] = (u, d, c), (d, v, c)
        try:
            validate_patch(Patch(vertices, G), ctx.points, ctx.forbidden_edges)
        except HoleFillError:
            continue
        if np.all(face_normals(X, G)[:, 2] > 0):
            q = triangle_quality(X, G).min()
            worst = (q, G) if worst is None or q < worst[0] else worst
    bad_faces = worst[1]
    bad_vertices = embed_patch(ctx, s, bad_faces, energy="area")
    q0 = triangle_quality(np.concatenate([ctx.points, bad_vertices]), bad_faces)
    out_vertices, out_faces, swaps = quality_swaps.improve_by_swaps(ctx, bad_vertices, bad_faces, "area")
    q1 = triangle_quality(np.concatenate([ctx.points, out_vertices]), out_faces)
    assert swaps > 0 and q1.min() > q0.min() + 0.1  # measured: 0.49 -> 0.82
    assert len(out_faces) == len(bad_faces) and len(out_vertices) == s
    validate_patch(Patch(out_vertices, out_faces), ctx.points, ctx.forbidden_edges)
    assert len(crossing_repair.crossing_faces(ctx, out_vertices, out_faces)) == 0
    assert np.abs(out_vertices[:, 2]).max() < 1e-12  # flat context, flat patch
    # The kept vertices minimise E_AREA on the kept connectivity, not on the one they came from.
    assert np.allclose(out_vertices, embed_patch(ctx, s, out_faces, energy="area"), atol=1e-12)


def test_a_patch_of_loop_vertices_only_is_swapped_too():
    """A small hole's patch may have no new vertex (a range scan's 8-edge hole: a fan of slivers from the
    domain's triangulation); the swaps alone lift it, and no energy is solved."""
    V, F, loop = examples.bowl_with_hole(n=21)  # a round hole of 36 edges in a bowl
    ctx = hole_context(V, F, loop, rings=2)
    k = ctx.size
    apex = min(set(range(k)) - set(ctx.forbidden_edges.ravel().tolist()))  # joined to no vertex by a mesh edge
    order = np.roll(np.arange(k), -apex)
    fan = np.stack([np.full(k - 2, apex), order[1:-1], order[2:]], axis=1)  # every triangle from the apex
    validate_patch(Patch(np.zeros((0, 3)), fan), ctx.points, ctx.forbidden_edges)
    q0 = triangle_quality(ctx.points, fan)
    vertices, faces, swaps = quality_swaps.improve_by_swaps(ctx, np.zeros((0, 3)), fan, "area")
    q1 = triangle_quality(ctx.points, faces)
    assert len(vertices) == 0 and swaps > 0 and q1.min() > q0.min() + 0.1
    validate_patch(Patch(vertices, faces), ctx.points, ctx.forbidden_edges)
    assert len(crossing_repair.crossing_faces(ctx, vertices, faces)) == 0
