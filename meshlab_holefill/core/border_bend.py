"""How a patch meets the surface around its hole: the mean bend across the hole's border.

A patch that continues the surrounding surface without a kink at the border bends like the
missing surface there, which needs no ground truth to measure: curve unfolding chooses its
planar domain by it (:mod:`meshlab_holefill.algorithms.brunton2009.domain_choice`), HPDE its
fallback layout (:mod:`meshlab_holefill.algorithms.xie_zou2013._algorithm2`).
"""
from __future__ import annotations

import numpy as np

from ..geometry.quality import face_normals

__all__ = ["border_bend"]


def border_bend(ctx, vertices, faces):
    """Mean angle, in degrees, between the mesh face and the patch face on each border edge.

    Parameters
    ----------
    ctx : HoleContext
    vertices : (s, 3) float64  new vertices of the patch
    faces : (t, 3) int64  patch faces in Patch numbering (loop index i < k, new vertex k + j)

    Returns
    -------
    float  0 where the patch continues the surface's tangent planes across the whole border;
    NaN when no border edge is in the patch

    Examples
    --------
    The hole at the bottom of a bowl closed by a flat fan from the loop's centroid bends against
    the bowl's slope; the fan from a point sunk towards the bowl's bottom bends less:

    >>> import numpy as np
    >>> from meshlab_holefill.core import examples, hole_context
    >>> V, F, loop = examples.bowl_with_hole()
    >>> ctx = hole_context(V, F, loop, rings=2)
    >>> k = ctx.size
    >>> fan = np.array([[k, i, (i + 1) % k] for i in range(k)])
    >>> centre = ctx.points.mean(axis=0, keepdims=True)
    >>> bool(border_bend(ctx, centre - [0, 0, 0.05], fan) < border_bend(ctx, centre, fan))
    True
    """
    k = ctx.size
    faces = np.asarray(faces, np.int64)
    n = k + len(vertices)
    tails, heads = faces.ravel(), np.roll(faces, -1, axis=1).ravel()  # (3 t,) directed patch edges
    patch_keys = np.minimum(tails, heads) * n + np.maximum(tails, heads)
    order = np.argsort(patch_keys, kind="stable")
    i = np.arange(k)
    j = (i + 1) % k
    wanted = np.minimum(i, j) * n + np.maximum(i, j)  # (k,) loop edge (i, i + 1)
    position = np.clip(np.searchsorted(patch_keys[order], wanted), 0, len(order) - 1)
    found = patch_keys[order][position] == wanted
    if not found.any():
        return float("nan")
    patch_face = order[position[found]] // 3
    X = np.concatenate([ctx.points, np.asarray(vertices, np.float64).reshape(-1, 3)])
    n_patch = face_normals(X, faces[patch_face])
    n_mesh = face_normals(ctx.vertices, ctx.faces[ctx.border_faces[found]])
    cosine = np.clip(np.einsum("ij,ij->i", n_patch, n_mesh), -1.0, 1.0)
    return float(np.degrees(np.arccos(cosine)).mean())
