"""Range scans made from closed meshes: what a scanner looking from one direction sees, and the holes it leaves.

A range scanner sees the surface from one side. Faces turned away from it or seen at a grazing
angle return nothing, and so do faces hidden behind other parts (an ear before the head, a leg
before the body). Inside the seen sheet those unseen faces leave holes whose ground truth is the
closed mesh: occlusion shadows and strips along folds, many of them small, with pinched borders
(two holes sharing a vertex) and jagged outlines, as real scans have. The faces on the far side
are dropped: the sheet's outline is not a hole.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse.csgraph import connected_components

from ..geometry.quality import cross_rows
from ..geometry.topology import face_adjacency
from .mesh_cases import MeshCase
from .noisy import normal_noise

__all__ = ["GRAZING_DEGREES", "visible_faces", "virtual_scan_case"]

#: Faces whose normal turns further than this from the scanner return nothing.
GRAZING_DEGREES = 78.0
# Barycentric samples of each face for its depth image: the corners moved a tenth inwards, the
# edge midpoints and the centroid (faces span about one pixel).
_SAMPLES = np.array([[0.8, 0.1, 0.1], [0.1, 0.8, 0.1], [0.1, 0.1, 0.8], [0.5, 0.5, 0.0], [0.0, 0.5, 0.5],
                     [0.5, 0.0, 0.5], [1 / 3, 1 / 3, 1 / 3]])


def _image_frame(direction):
    """Unit view direction d and two unit vectors e1, e2 spanning the image plane."""
    d = np.asarray(direction, np.float64)
    if d.shape != (3,) or not np.all(np.isfinite(d)) or not np.linalg.norm(d) > 0.0:
        raise ValueError(f"the scanner's direction must be a finite, non-zero 3-vector, got {direction!r}")
    d = d / np.linalg.norm(d)
    helper = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(d, helper)
    e1 /= np.linalg.norm(e1)
    return d, e1, np.cross(d, e1)


def visible_faces(V, F, direction, pixel, grazing_degrees=GRAZING_DEGREES):
    """Faces an orthographic scanner looking along ``direction`` sees.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int
    direction : (3,) float  the viewing direction (from the scanner into the scene)
    pixel : float  side of the depth image's pixels, in mesh units (about a mean edge)
    grazing_degrees : float  faces turned further than this from the scanner are not seen

    Raises
    ------
    ValueError
        A zero or non-finite direction, a pixel that is not a positive length, a mesh without faces.

    Returns
    -------
    (m,) bool
        Faces facing the scanner whose centroid is no deeper than the depth image there (within
        0.75 pixel, plus the face's own depth change across a cell): nothing in front of them.
    """
    V = np.asarray(V, np.float64)
    F = np.asarray(F, np.int64)
    if not (np.isfinite(pixel) and pixel > 0.0):
        raise ValueError(f"the depth image's pixel must be a positive length, got {pixel!r}")
    if len(F) == 0:
        raise ValueError("the mesh has no faces to scan")
    d, e1, e2 = _image_frame(direction)
    image = V @ np.stack([e1, e2], axis=1)  # (n, 2)
    image = (image - image.min(axis=0)) / pixel
    depth = V @ d
    shape = np.floor(image.max(axis=0)).astype(np.int64) + 1
    samples = np.einsum("sk,fkc->fsc", _SAMPLES, image[F])  # (m, s, 2)
    sample_depth = depth[F] @ _SAMPLES.T  # (m, s)
    cells = np.floor(samples).astype(np.int64)
    flat = cells[..., 1] * shape[0] + cells[..., 0]
    nearest = np.full(int(shape[0] * shape[1]), np.inf)
    np.minimum.at(nearest, flat.ravel(), sample_depth.ravel())
    normals = cross_rows(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    cos_angle = -(normals @ d) / np.maximum(np.linalg.norm(normals, axis=1), 1e-300)
    facing = cos_angle > np.cos(np.radians(grazing_degrees))
    # Within one cell a face's own depth varies by up to about 1.5 pixels times the tangent of its
    # angle to the scanner (4.7 at 78 degrees): the nearest depth there may be its own, or a
    # neighbour's in the same plane.
    slope = np.sqrt(np.clip(1.0 - cos_angle ** 2, 0.0, 1.0)) / np.maximum(cos_angle, 1e-12)
    centre = _SAMPLES.shape[0] - 1
    return facing & (sample_depth[:, centre] <= nearest[flat[:, centre]] + pixel * (0.75 + 1.5 * slope))


def virtual_scan_case(name, V, F, direction, noise=0.0, seed=0, min_faces=6, max_share=0.03):
    """The scan of a closed mesh from ``direction`` as a case whose holes are the unseen faces inside the seen sheet.

    Parameters
    ----------
    name : str
    V : (n, 3) float64, F : (m, 3) int  a closed mesh
    direction : (3,) float  the scanner's viewing direction
    noise : float  scanner noise along the normals, in mean edge lengths (:func:`.noisy.normal_noise`),
        added before the scan
    seed : int  the noise's seed
    min_faces, max_share : a group of unseen faces is a hole when it has at least ``min_faces``
        faces and at most ``max_share`` of the mesh's; smaller groups stay (seen), larger ones
        (the far side) are dropped; seen groups of fewer than ``min_faces`` faces count as unseen
        (a speck inside a hole would make it a ring around an island)

    Returns
    -------
    MeshCase  the seen sheet with its holes as ``removed`` faces (``given_class`` "scan"),
        unreferenced vertices left out

    Examples
    --------
    A ball before a sphere casts a shadow on it, a hole in the seen cap of the sphere:

    >>> from meshlab_holefill.evaluation.analytic import analytic_mesh
    >>> V, F = analytic_mesh("sphere")
    >>> scene_V, scene_F = np.vstack([V, 0.4 * V + [0.2, 0.1, 2.0]]), np.vstack([F, F + len(V)])
    >>> case = virtual_scan_case("ball and sphere", scene_V, scene_F, direction=(0.0, 0.0, -1.0))
    >>> bool(case.removed.any()), len(case.F) < len(scene_F)
    (True, True)
    """
    V = np.asarray(V, np.float64)
    F = np.asarray(F, np.int64)
    if len(F) == 0:
        raise ValueError(f"mesh '{name}' has no faces to scan")
    if noise:
        V = normal_noise(V, F, noise, seed=seed)
    edge = float(np.linalg.norm(V[F[:, 1]] - V[F[:, 0]], axis=1).mean())
    seen = visible_faces(V, F, direction, pixel=0.7 * edge)
    seen[_in_small_groups(F, np.flatnonzero(seen), min_faces)] = False  # specks: islands, not surface
    unseen = np.flatnonzero(~seen)
    size = _group_sizes(F, unseen)
    hole = (size >= min_faces) & (size <= max_share * len(F))
    keep = seen.copy()
    keep[unseen[size < min_faces]] = True
    keep[unseen[hole]] = True
    kept = np.flatnonzero(keep)
    removed = np.isin(kept, unseen[hole])
    used = np.unique(F[kept])
    renumber = np.full(len(V), -1, np.int64)
    renumber[used] = np.arange(len(used))
    return MeshCase(name, V[used], renumber[F[kept]], removed=removed, given_class="scan")


def _group_sizes(F, faces):
    """(len(faces),) the size of the edge-connected group of ``faces`` each belongs to."""
    _, label = connected_components(face_adjacency(F[faces]), directed=False)
    return np.bincount(label)[label]


def _in_small_groups(F, faces, min_faces):
    """The ``faces`` whose edge-connected group among them has fewer than ``min_faces`` faces."""
    return faces[_group_sizes(F, faces) < min_faces]
