"""CAD-like test cases: meshes with sharp creases and holes a crease runs through, and interpenetrating parts.

Built with MeshLab's generators, booleans and isotropic remeshing (through
:mod:`meshlab_holefill.meshlab.mesh_files`), with creases kept by the remeshing; each is the same
mesh in every run (the booleans' faces put in a fixed order, the remeshing run in a new process):

- ``creased_box``: a unit cube; holes centred on edges and on a corner (90 degree creases);
- ``bevelled_box``: the cube intersected with a rotated, larger cube, which bevels its four vertical
  edges (45 degree creases beside 90 degree ones); holes on bevel creases and where they meet the top;
- ``cylinder_rims``: ``create_cone`` with equal radii, holes centred on the sharp rims;
- ``union``: the cube united with a cylinder through it (concave creases where they meet, the
  cylinder's rims above and below);
- ``interpenetrating``: a sphere, a cylinder and a cube overlapping, put into one mesh without a
  boolean, so faces of different components cross; holes are cut next to the crossing curves (the
  removed surface itself crosses nothing), where a patch that leaves the surface hits the other part.

:func:`cad_tessellation_case` gives three such parts tessellated as a CAD export is (large
triangles on the flat faces, small ones along creases: :func:`meshlab_holefill.meshlab.mesh_files.cad_tessellation`), their
holes' borders mixing short and long edges.

A hole is the connected face region inside a ball around its centre, the radius grown until the
boundary has about the target number of edges (0.8 to 1.5 times), its loop simple. Each case is a
:class:`.mesh_cases.MeshCase` with the holes as ``removed`` faces and ``given_class`` "crease" or
"crossing" (the size class the report shows). ``seed=0`` gives the holes placed by hand; another seed
places them at random points of the creases (:func:`random_crease_holes`), or next to random points of
the crossing curves, so that the same shapes give holes no filter was tuned on.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse.csgraph import connected_components

from ..core.holes import boundary_loops
from ..geometry.intersections import faces_intersecting
from ..geometry.quality import edge_lengths
from ..geometry.topology import face_adjacency
from ..meshlab.mesh_files import boolean_mesh, cad_tessellation, generated_mesh, remeshed
from .cut_holes import _region_boundary
from .dihedrals import CREASE_ANGLE, edge_dihedrals
from .mesh_cases import MeshCase

__all__ = ["CAD_TESSELLATED_PARTS", "CREASED_CASES", "ball_hole", "cad_tessellation_case", "creased_case",
           "crossing_centres", "random_crease_holes", "rotation"]

#: Random points tried per hole of :func:`random_crease_holes` before that hole is left out.
CENTRE_TRIES = 12


def rotation(axis, degrees):
    """(3, 3) rotation matrix about ``axis`` ("x", "y" or "z") by ``degrees`` (counter-clockwise)."""
    a = np.radians(degrees)
    c, s = np.cos(a), np.sin(a)
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def _moved(mesh, R=None, t=(0.0, 0.0, 0.0)):
    V, F = mesh
    V = V @ (np.eye(3) if R is None else R).T + np.asarray(t, np.float64)
    return V, F


def ball_hole(V, F, center, target, taken=None, tries=40):
    """Faces to remove for a hole around ``center`` with about ``target`` boundary edges.

    The region is the connected set of faces (through edges) whose three vertices lie within a
    ball around ``center``, containing the face nearest to it; the ball grows (or shrinks) by 6 %
    until the boundary has 0.8 to 1.5 times ``target`` edges in one simple loop and the rest of
    the mesh keeps simple, unpinched loops.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int
    center : (3,) float
    target : int  boundary edges wanted
    taken : (m,) bool, optional  faces already removed (holes stay apart from them by two rings)
    tries : int

    Returns
    -------
    (r,) int64  face indices, or None when no radius gives such a hole
    """
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    taken = np.zeros(len(F), bool) if taken is None else np.asarray(taken, bool)
    ell = float(edge_lengths(V, F).mean())
    radius = target * ell / (2 * np.pi * 1.15)
    d_vertex = np.linalg.norm(V - np.asarray(center, np.float64), axis=1)
    d_face = d_vertex[F].max(axis=1)
    seed = int(np.argmin(np.linalg.norm(V[F].mean(axis=1) - center, axis=1)))
    adjacency = face_adjacency(F)
    near = taken.copy()
    for _ in range(2):
        near = near | (adjacency @ near.astype(np.float64) > 0)
    for _ in range(tries):
        inside = np.flatnonzero(d_face <= radius)
        if seed in set(inside.tolist()):
            _, label = connected_components(adjacency[inside][:, inside], directed=False)
            region = inside[label == label[np.searchsorted(inside, seed)]]
            edges, simple = _region_boundary(F, region)
        else:
            region, edges, simple = np.zeros(0, np.int64), 0, False
        if edges < 0.8 * target or not len(region):
            radius *= 1.06
            continue
        if edges > 1.5 * target:
            radius /= 1.06 ** 0.5
            continue
        if not simple or near[region].any():
            return None
        trial = taken.copy()
        trial[region] = True
        loops = boundary_loops(F[~trial])
        if any(lp.pinched or not lp.closed for lp in loops):
            return None
        return np.sort(region)
    return None


def _case(name, V, F, holes, given_class="crease"):
    """MeshCase with the ball holes [(centre, target), ...] as removed faces (holes that cannot be cut left out)."""
    removed = np.zeros(len(F), bool)
    for center, target in holes:
        region = ball_hole(V, F, center, target, removed)
        if region is not None:
            removed[region] = True
    return MeshCase(name, V, F, removed=removed, given_class=given_class)


def random_crease_holes(V, F, targets, rng, angle=CREASE_ANGLE):
    """Holes at random points of the creases, one per target, the last one anywhere on the surface.

    A crease is an interior edge whose dihedral angle exceeds ``angle`` degrees
    (:func:`.dihedrals.edge_dihedrals`); each hole is centred at a uniform random point of a
    random crease edge, the last at the centroid of a random face (on a CAD export that is
    mostly a large flat triangle). A centre whose ball gives no hole (:func:`ball_hole`) is
    drawn again, up to :data:`CENTRE_TRIES` times.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int
    targets : sequence of int  boundary edges wanted, one hole each
    rng : numpy.random.Generator
    angle : float  degrees

    Returns
    -------
    (m,) bool  the removed faces
    """
    V, F = np.asarray(V, np.float64), np.asarray(F, np.int64)
    edges, dihedral = edge_dihedrals(V, F)
    creases = edges[np.abs(dihedral) > angle]
    removed = np.zeros(len(F), bool)
    for i, target in enumerate(targets):
        anywhere = i == len(targets) - 1 or not len(creases)
        for _ in range(CENTRE_TRIES):
            if anywhere:
                centre = V[F[rng.integers(len(F))]].mean(axis=0)
            else:
                a, b = creases[rng.integers(len(creases))]
                w = rng.uniform(0.1, 0.9)
                centre = w * V[a] + (1.0 - w) * V[b]
            region = ball_hole(V, F, centre, int(target), removed)
            if region is not None:
                removed[region] = True
                break
    return removed


def _box(size=1.0):
    return generated_mesh("create_cube", size=size)


def _cylinder(radius, height, subdiv=96):
    return generated_mesh("create_cone", r0=radius, r1=radius, h=height, subdiv=subdiv)


def crossing_centres(V, F, components, specs, edge, rng=None):
    """Hole centres next to where components cross: removed faces cross nothing, their loop is close.

    For each ``(component, target)`` the centre is a vertex of that component whose distance to
    the nearest face of it that crosses another component is about the ball radius of the hole
    plus two edge lengths (with ``rng``, a random one of the vertices within an edge length of
    the best); centres keep apart from the ones chosen before.

    Parameters
    ----------
    V : (n, 3) float64, F : (m, 3) int
    components : (m,) int  component of each face
    specs : list of (component, target boundary edges)
    edge : float  mean edge length

    Returns
    -------
    list of ((3,) float64 centre, target)
    """
    out = []
    for comp, target in specs:
        own = np.flatnonzero(components == comp)
        other = np.flatnonzero(components != comp)
        crossing = faces_intersecting(V, F, own, other)
        if not len(crossing):
            continue
        radius = target * edge / (2 * np.pi * 1.15)
        verts = np.unique(F[own].ravel())
        cross_pts = V[F[crossing]].reshape(-1, 3)
        d = np.min(np.linalg.norm(V[verts][:, None, :] - cross_pts[None, ::3, :], axis=2), axis=1)
        score = np.abs(d - (radius + 2.5 * edge))
        for c, _t in out:
            too_close = np.linalg.norm(V[verts] - c, axis=1) < radius + 2 * _t * edge / (2 * np.pi) + 4 * edge
            score[too_close] = np.inf
        best = int(np.argmin(score))
        if rng is not None and np.isfinite(score[best]):
            close = np.flatnonzero(score <= score[best] + edge)
            best = int(close[rng.integers(len(close))])
        if np.isfinite(score[best]):
            out.append((V[verts[best]].copy(), target))
    return out


def creased_case(name, edge=0.025, seed=0):
    """One of the creased or interpenetrating cases by name (:data:`CREASED_CASES`).

    Parameters
    ----------
    name : str  "creased_box", "bevelled_box", "cylinder_rims", "union" or "interpenetrating"
    edge : float  target edge length of the remeshing (the shapes are about 1 unit across);
        0.08 gives the small test fixtures
    seed : int  0: the holes placed by hand; otherwise holes of 20-100 edges at random crease
        points (:func:`random_crease_holes`), or next to random points of the crossing curves

    Returns
    -------
    mesh_cases.MeshCase  with ``removed`` holes and ``given_class``
    """
    if name not in CREASED_CASES:
        raise ValueError(f"unknown creased case '{name}' (known: {', '.join(CREASED_CASES)})")
    s = edge / 0.025  # hole targets shrink with a coarser mesh, so the holes keep their size
    t = lambda k: max(int(round(k / s)), 8)  # noqa: E731
    if name == "creased_box":
        V, F = remeshed(*_box(), edge)
        holes = [((0.5, 0.5, 0.0), t(60)), ((-0.5, 0.0, 0.5), t(20)), ((0.5, -0.5, -0.5), t(60)),
                 ((-0.5, -0.5, 0.0), t(100))]
        return _seeded_case(name, V, F, holes, seed, t)
    if name == "bevelled_box":
        cutter = _moved(_box(1.2), rotation("z", 45.0))
        V, F = remeshed(*boolean_mesh("intersection", _box(), cutter), edge)
        b = 0.6 * np.sqrt(2) - 0.5  # where a bevel meets a face
        holes = [((0.5, b, 0.0), t(60)), ((0.5, -0.1, 0.5), t(20)), ((0.5 * (b + 0.5), 0.5 * (b + 0.5), 0.5), t(60)),
                 ((-b, -0.5, 0.0), t(60))]
        return _seeded_case(name, V, F, holes, seed, t)
    if name == "cylinder_rims":
        V, F = remeshed(*_cylinder(0.5, 1.5), edge)
        holes = [((0.5, 0.75, 0.0), t(60)), ((-0.5, -0.75, 0.0), t(60)), ((0.0, 0.75, -0.5), t(20)),
                 ((0.0, -0.75, 0.5), t(20))]
        return _seeded_case(name, V, F, holes, seed, t)
    if name == "union":
        V, F = remeshed(*boolean_mesh("union", _box(), _cylinder(0.3, 1.3)), edge)
        holes = [((0.3, 0.5, 0.0), t(60)), ((-0.3, -0.5, 0.0), t(20)), ((0.0, -0.5, -0.3), t(20)),
                 ((-0.5, 0.5, 0.5), t(60))]
        return _seeded_case(name, V, F, holes, seed, t)
    # interpenetrating: three closed parts in one mesh, no boolean
    parts = [remeshed(*_moved(generated_mesh("create_sphere", subdiv=3), 0.6 * np.eye(3)), edge),
             remeshed(*_moved(_cylinder(0.25, 1.2), rotation("z", 90.0), (0.55, 0.0, 0.0)), edge),
             remeshed(*_moved(_box(0.7), rotation("z", 30.0), (-0.5, 0.35, 0.0)), edge)]
    V = np.concatenate([p[0] for p in parts])
    offsets = np.cumsum([0] + [len(p[0]) for p in parts[:-1]])
    F = np.concatenate([p[1] + o for p, o in zip(parts, offsets)])
    components = np.concatenate([np.full(len(p[1]), i) for i, p in enumerate(parts)])
    ell = float(edge_lengths(V, F).mean())
    specs = [(0, t(60)), (0, t(20)), (1, t(40)), (2, t(40))]
    rng = None
    if seed:
        rng = np.random.default_rng(seed)
        specs = [(int(rng.integers(len(parts))), t(int(rng.choice(SEEDED_TARGETS)))) for _ in specs]
    return _case(name, V, F, crossing_centres(V, F, components, specs, ell, rng), given_class="crossing")


#: Boundary edges of the seeded holes (:func:`creased_case` with a seed other than 0), at the default edge.
SEEDED_TARGETS = (20, 40, 60, 100)


def _seeded_case(name, V, F, holes, seed, target):
    """The case with the hand-placed ``holes`` (seed 0) or as many at random crease points (another seed).

    ``target(k)`` is the boundary edges of a k-edge hole at this case's edge length.
    """
    if not seed:
        return _case(name, V, F, holes)
    rng = np.random.default_rng(seed)
    targets = [target(int(rng.choice(SEEDED_TARGETS))) for _ in holes]
    return MeshCase(name, V, F, removed=random_crease_holes(V, F, targets, rng), given_class="crease")


CREASED_CASES = ("creased_box", "bevelled_box", "cylinder_rims", "union", "interpenetrating")


# name: (the shape, faces kept by the decimation, [(hole centre, target boundary edges), ...])
CAD_TESSELLATED_PARTS = {
    "union": (lambda: boolean_mesh("union", _box(), _cylinder(0.3, 1.3)), 4000,
              [((0.3, 0.5, 0.0), 20), ((-0.5, 0.5, 0.5), 30), ((0.0, -0.65, 0.3), 24), ((0.5, -0.5, 0.0), 40)]),
    "drilled_box": (lambda: boolean_mesh("difference", _box(), _moved(_cylinder(0.25, 1.4), rotation("x", 90.0))),
                    5000, [((0.25, 0.0, 0.5), 24), ((0.0, 0.25, 0.0), 24), ((0.5, 0.5, 0.0), 40),
                           ((-0.5, -0.3, -0.5), 60)]),
    "cylinder": (lambda: _cylinder(0.5, 1.5), 3000, [((0.5, 0.75, 0.0), 30), ((0.0, -0.75, 0.5), 20),
                                                      ((0.0, 0.0, 0.5), 30)]),
}


def cad_tessellation_case(name, edge=0.02, seed=0):
    """One of :data:`CAD_TESSELLATED_PARTS`: the shape remeshed at ``edge``, decimated as a CAD export, holes cut.

    Parameters
    ----------
    name : str  "union", "drilled_box" or "cylinder"
    edge : float  edge length of the remeshing before the decimation (the shapes are about 1 unit across)
    seed : int  0: the holes placed by hand; otherwise as many of 20-60 edges at random crease
        points (:func:`random_crease_holes`)

    Returns
    -------
    mesh_cases.MeshCase  with ``removed`` holes (those that cannot be cut left out), ``given_class`` "crease"
    """
    if name not in CAD_TESSELLATED_PARTS:
        raise ValueError(f"unknown CAD part '{name}' (known: {', '.join(CAD_TESSELLATED_PARTS)})")
    shape, faces, holes = CAD_TESSELLATED_PARTS[name]
    V, F = cad_tessellation(*remeshed(*shape(), edge), faces)
    if not seed:
        return _case(name, V, F, holes)
    rng = np.random.default_rng(seed)
    targets = [int(rng.choice(SEEDED_TARGETS[:3])) for _ in holes]
    return MeshCase(name, V, F, removed=random_crease_holes(V, F, targets, rng), given_class="crease")
