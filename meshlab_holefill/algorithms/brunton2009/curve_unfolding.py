"""Hole filling by curve unfolding (Brunton, Wuhrer, Shu, Bose and Demaine 2009).

A. Brunton, S. Wuhrer, C. Shu, P. Bose, E. D. Demaine, "Filling Holes in Triangular Meshes by
Curve Unfolding", IEEE Shape Modeling International 2009. Each hole is filled in three steps:
the boundary loop is unfolded into a simple planar polygon by simulated annealing of a
planarity energy, never self-intersecting, then projected to its best-fitting plane
(Sec. 3.1, :mod:`.unfolding`); the polygon gets a constrained Delaunay triangulation without
Steiner points (Sec. 3.2); the triangulation is refined in the plane after Chew and embedded
in space with its boundary on the loop and its interior vertices minimising the least-squares
mesh energy E_AREA or the discrete fairing energy E_DF (Sec. 3.3, :mod:`.embedding`).

Reading: E_AREA (``energy='area'``, the default) is the least-squares mesh the paper names
it (Sorkine and Cohen-Or 2004), which keeps the Laplacian rows of the loop vertices as well
as those of P_Int; the sum over P_Int alone, as printed (``area_rows='interior'``), is a
membrane spanning the loop that cannot beat a flat ear-clipping fill on curved surfaces
(benchmark cut holes, mean patch-to-ground-truth distance per mille of the diagonal, small /
medium / large: least-squares mesh 0.174 / 1.688 / 1.883, interior rows 0.706 / 6.775 / 19.55,
E_DF 0.181 / 1.807 / 2.059, MeshLab 0.296 / 5.905 / 21.43; :mod:`.embedding`).

Reading: the unfolding keeps the loop's edge lengths (``lengths='loop'``, the default): the
projection to the best plane shortens edges by their tilt, most around a crease, and the planar
domain is the dominant source of the patch's error there. Measured stage by stage on the
benchmark's crease holes (mean patch-to-ground-truth distance per mille): other energies,
densities, no swaps or no tangential relaxation move it by 0.13 at most (4.79-5.01 against 4.92),
the domain by far more (loop lengths 4.00, the surface's development 2.55;
:func:`.unfolding.with_loop_lengths`, option ``domain``).

Beyond the paper (options, on by default because the benchmark targets need them):
``fallback`` unfolds loops that annealing does not (loops wrapped around a tube or a knob) by
developing them with the surface's own angles; ``tangential`` moves the embedded interior
vertices within their tangent planes until the umbrella has no tangential part, even spacing
on the solved shape (:func:`.embedding.tangential_relaxation`);
``repair`` replaces a patch that crosses the surrounding mesh (scan borders with folded sliver
faces) by the best patch of another planar domain that crosses nothing, else clips the ears of
the boundary vertices involved and fills the rest of the loop again (:func:`repair_crossings`);
``swaps`` improves the connectivity of the embedded patch by quality-improving edge swaps, the
energy solved again after each round (:func:`improve_by_swaps`);
``max_domain_area`` refuses planar domains many times larger than the missing surface, whose
patches bulge out of it (long strip-shaped holes, :func:`domains_within_area`);
``density='surrounding'`` (default) samples the energy's patch at the surrounding mesh's density
(mean new edge 0.8 of the surrounding one before, 0.99 now;
:func:`.unfolded_triangulation.resample_patch`; ``'twice'`` and ``'equilateral'`` keep the
refinement's own patch); ``slivers`` lifts the triangles still below quality 0.3 by local moves,
splits and collapses (:func:`.slivers.repair_slivers`). Off by default: ``domain='development'``
takes the surface's development of the loop as the planar domain whenever it is simple
(:func:`_development_domain`).
"""
from __future__ import annotations

import hashlib
import time

import numpy as np

from ...geometry.flips import relax_edges
from ...geometry.intersections import faces_intersecting
from ...geometry.quality import edge_lengths, triangle_quality
from ...geometry.topology import edge_pair_set
from ...core import examples
from ...core.holes import hole_context
from ...core.patch import Patch
from ...errors import HoleFillError
from ...core.parameters import ParamSpec
from .embedding import embed_patch, relax_patch
from .slivers import repair_slivers
from .unfolded_triangulation import DENSITIES, resample_patch, surrounding_edge_length, triangulate_and_embed
from ...geometry.development import boundary_gap_angles, develop_loop, developed_area, simple_development, simple_developments
from ...geometry.triangulate import polygon_perimeter, polygon_signed_area
from .unfolding import anneal_loop, linear_motion_is_simple, unfold_loop

__all__ = ["fill", "PARAMS", "RINGS", "WARM_UP", "warm_up", "crossing_faces", "clip_ears", "repair_crossings", "improve_by_swaps",
           "domains_within_area"]

RINGS = 2

MAX_REPAIR_ROUNDS = 4  # rounds of ear clipping when a patch crosses its surroundings
MAX_SWAP_ROUNDS = 4  # rounds of quality-improving edge swaps, each followed by a new energy solve
RESAMPLE_TOLERANCE = 0.1  # density 'surrounding': a patch whose mean edge is within 10 % of the surroundings' is kept
GOOD_QUALITY = 0.3  # repair stops trying domains at a clean patch of this minimum quality (poor triangles are below it)

PARAMS = [
    ParamSpec("k", "float", 0.9,
              "Simulated annealing constant k < 1 (Sec. 3.1, 4: 0.9): Boltzmann factor exp(-dE/(kT)) and "
              "cooling T <- kT after each temperature stage (one sweep over the loop).", minimum=0.01, maximum=0.999),
    ParamSpec("temperature", "float", 0.5,
              "Start temperature T of the annealing (Sec. 4: 0.5), in radians of the planarity energy E_PE.",
              minimum=1e-6, maximum=100.0),
    ParamSpec("epsilon", "float", 1e-5,
              "Clearance d_MD > epsilon kept between non-adjacent boundary segments while unfolding (Sec. 4: "
              "1e-5), relative to the hole's mean boundary edge length.", minimum=1e-12, maximum=0.1),
    ParamSpec("max_restarts", "int", 100,
              "Annealing runs tried before the unfolding is given up (Sec. 3.1: 100).", minimum=1, maximum=10000),
    ParamSpec("sa_steps", "int", 5000,
              "Maximum single-vertex moves per annealing run; a run also ends when k T falls below 1e-3 T or "
              "as soon as the loop projects to a simple polygon (checked at each temperature stage).",
              minimum=0, maximum=10_000_000),
    ParamSpec("step_bound", "enum", "global",
              "Length bound of a move: 'global' = max(epsilon, d_MD) as in Sec. 3.1 (halved, since up to m/4 "
              "independent vertices move together); 'local' = the clearance of the moved segments instead of "
              "d_MD (same no-crossing guarantee, larger steps).",
              choices=("global", "local")),
    ParamSpec("lengths", "enum", "loop",
              "Edge lengths of the unfolded polygon (Sec. 3.1 read as an unfolding that keeps the loop's edge "
              "lengths): 'loop' = the accepted projection's edge directions walked with the loop's own edge "
              "lengths, closed by the smallest relative change (the projection where that polygon is not "
              "simple); 'projection' = the projection as it is, its edges shortened by their tilt from the "
              "best plane (scaled to the loop's perimeter as a whole in Sec. 3.3).",
              choices=("loop", "projection")),
    ParamSpec("domain", "enum", "unfolding",
              "Beyond the paper: planar domain of the patch. 'unfolding' = Sec. 3.1's unfolded loop (the "
              "development only when annealing fails, option fallback); 'development' = the loop developed "
              "with the surrounding surface's angles whenever that polygon is simple, without annealing "
              "(closer on developable surfaces: creases, cylinders; farther on large holes of curved ones).",
              choices=("unfolding", "development")),
    ParamSpec("energy", "enum", "area",
              "Energy of the interior vertices (Sec. 3.3): 'area' = least-squares mesh E_AREA (the energy of the "
              "paper's Table 1 run), 'fairing' = discrete fairing E_DF.",
              choices=("area", "fairing")),
    ParamSpec("area_rows", "enum", "mesh",
              "Rows of E_AREA: 'mesh' = the least-squares mesh (Sorkine and Cohen-Or, the paper's ref. [24]): the "
              "umbrellas of the interior vertices and of the loop vertices, whose 1-rings reach the surrounding "
              "surface; 'interior' = the sum over the interior vertices only as printed, a membrane spanning "
              "the loop (flat, farther from curved surfaces).",
              choices=("mesh", "interior")),
    ParamSpec("refinement", "bool", True,
              "Refine the planar triangulation after Chew to angles in [30, 120] degrees and edges at most twice "
              "the surrounding edges (Sec. 3.3); off keeps the Steiner-free CDT of Sec. 3.2."),
    ParamSpec("density", "enum", "surrounding",
              "Density of the patch (Sec. 3.3), against the mean edge e of the faces around the hole: "
              "'twice' = refinement area bound e^2/sqrt(3), the paper's 'edges at most twice the surrounding "
              "ones' exactly (mean new edge 0.9 e); 'equilateral' = the equilateral area of e, the reading used "
              "before (0.8 e); 'surrounding' = the 'equilateral' patch as the shape, sampled again at e (the "
              "paper's aim, 'match the resolution of the surrounding mesh') when it is more than 10 % off: its "
              "planar domain refined with the bound e^2/sqrt(3) corrected by the measured ratio, the new vertices "
              "placed on the patch (the uniform-umbrella energy's shape depends on the resolution, so it is not "
              "solved again at e).",
              choices=DENSITIES),
    ParamSpec("fallback", "bool", True,
              "Beyond the paper: when the first annealing run gives no simple projection, unfold the loop by "
              "developing it with the surrounding surface's angles (loops wrapped around a tube or knob)."),
    ParamSpec("repair", "bool", True,
              "Beyond the paper: when the patch crosses the surrounding mesh, take the best patch of the loop's "
              "simple developments that crosses nothing; if none does, clip the ears of the boundary vertices "
              "involved and fill the remaining loop again (up to 4 rounds)."),
    ParamSpec("swaps", "bool", True,
              "Beyond the paper: after the embedding, swap patch edges whose swap raises the lower quality of "
              "the two triangles and solve the energy again on the new connectivity (up to 4 rounds, the best "
              "round kept); the uniform Laplacian of Sec. 3.3 squeezes triangles at border vertices where the "
              "surface leaves a wide opening."),
    ParamSpec("tangential", "bool", True,
              "Beyond the paper: after each energy solve, move the interior vertices within their tangent planes "
              "until the uniform umbrella U has no tangential part (the energy's shape, evenly spaced); E_DF "
              "alone squeezes triangles next to long border edges and wide openings."),
    ParamSpec("slivers", "bool", True,
              "Beyond the paper: after the swaps, lift the triangles below quality 0.3 by tangential moves, "
              "splits and collapses of the new vertices around them (up to 10 rounds), kept only when the "
              "minimum quality rises without folding or crossing the mesh more (a cap on a border edge whose "
              "inner vertex the energy pulled onto it cannot be swapped)."),
    ParamSpec("max_domain_area", "float", 6.0,
              "Beyond the paper: planar domains (the unfolding, the developments the repair tries) enclosing more "
              "than this multiple of the missing surface's area (estimated by developing the loop with the "
              "surrounding surface's angles) are not embedded, and the hole fails when none is left: a long "
              "strip-shaped hole can unfold to a round polygon whose patch bulges far out of the surface. "
              "0 = no limit.", minimum=0.0, maximum=1e6),
    ParamSpec("seed", "int", 0, "Seed of the simulated annealing (same seed, same patch).",
              minimum=0, maximum=2**31 - 1),
]


def crossing_faces(ctx, vertices, faces):
    """Patch faces that intersect the hole's surrounding faces or another patch face.

    Parameters
    ----------
    ctx : HoleContext
    vertices : (s, 3) float64  new vertices
    faces : (t, 3) int64  in Patch numbering

    Returns
    -------
    (h,) int64  indices into ``faces``
    """
    k, n_ctx = ctx.size, len(ctx.vertices)
    X = np.concatenate([ctx.vertices, vertices])
    joint = np.where(faces < k, faces, faces - k + n_ctx)
    allF = np.concatenate([joint, ctx.faces])
    return faces_intersecting(X, allF, np.arange(len(faces)), np.arange(len(allF)))


def clip_ears(ctx, Q, keep, ears, bad_vertices):
    """Repair step (beyond the paper): cut off the ear at each offending boundary vertex.

    An ear (prev, v, next) of the current sub-loop is clipped when its chord is no mesh edge,
    it has non-zero area, it does not cross the surrounding faces or earlier ears, and the
    planar sub-polygon stays simple without v. Clipped vertices are never neighbours within
    one round.

    Returns
    -------
    keep : (r,) int64  the new sub-loop
    ears : list of (3,) tuples
    clipped : int
    """
    keep = list(keep)
    ears = list(ears)
    forbidden = edge_pair_set(ctx.forbidden_edges)
    h = float(np.mean(np.linalg.norm(np.roll(ctx.points, -1, axis=0) - ctx.points, axis=1)))
    order = sorted(set(bad_vertices) & set(keep), key=lambda v: _corner_angle(ctx.points, keep, v))
    clipped, touched = 0, set()
    for v in order:
        if len(keep) <= 3 or v in touched:
            continue
        i = keep.index(v)
        a, b = keep[i - 1], keep[(i + 1) % len(keep)]
        if tuple(sorted((a, b))) in forbidden:
            continue
        if np.linalg.norm(np.cross(ctx.points[v] - ctx.points[a], ctx.points[b] - ctx.points[a])) <= 1e-12 * h * h:
            continue
        trial = keep[:i] + keep[i + 1:]
        if not linear_motion_is_simple(Q[trial], 1e-9 * h):
            continue
        ear = np.array([[a, v, b]])
        if len(crossing_faces(ctx, np.zeros((0, 3)), np.concatenate([np.asarray(ears, np.int64).reshape(-1, 3), ear]))):
            continue
        keep = trial
        ears.append((a, v, b))
        touched.update((a, v, b))
        clipped += 1
    return np.asarray(keep, np.int64), ears, clipped


def repair_crossings(ctx, domains, vertices, faces, energy, refinement, tangential=False, density="surrounding",
                     record=None, bad=None):
    """Repair (beyond the paper, option ``repair``): a patch that crosses nothing, best quality first.

    ``domains`` are planar polygons of the loop, the unfolding used first (its patch given as
    ``vertices``, ``faces``), then the loop's simple developments (:func:`..geometry.development.simple_developments`).
    When the first patch crosses the surrounding mesh, the patches of the other domains are
    tried as they are, least relaxed first, and the one of best minimum quality that crosses
    nothing is taken (the first reaching quality GOOD_QUALITY = 0.3 ends the search):
    the triangulation near a folded border face depends on the domain, and a domain whose
    patch clears the fold needs no clipped ear (an ear at a wide corner is a sliver;
    measured on bunny10k_textured's 22-edge hole: ear 0.116, the 0.2-relaxed development's
    patch 0.345). Only if none does are ears clipped (:func:`clip_ears`), in the first domain
    and then in the least relaxed development, until a patch crosses nothing (the fewest
    crossings otherwise).

    Parameters
    ----------
    ctx : HoleContext
    domains : list of ((k, 2) float64, str, float or None)  polygon, unfolding name, development blend
    vertices, faces : the patch of the first domain
    energy, refinement, tangential, density, record : see :func:`triangulate_and_embed`
    bad : (h,) int64, optional  :func:`crossing_faces` of the first patch, when already known

    Returns
    -------
    crossings : int  faces of the returned patch crossing the mesh
    vertices, faces : the patch
    clipped : int  ears clipped
    method : str  unfolding name of the domain used
    relax : float or None  its development blend
    """
    m = ctx.size
    if bad is None:
        bad = crossing_faces(ctx, vertices, faces)
    if len(bad) == 0:
        return 0, vertices, faces, 0, domains[0][1], domains[0][2]
    patches = [(vertices, faces, bad)]
    clean = []
    for domain, name, relax in domains[1:]:
        V, F = triangulate_and_embed(ctx, domain, np.arange(m), [], energy, refinement, tangential, density, record)
        b = crossing_faces(ctx, V, F)
        patches.append((V, F, b))
        if len(b) == 0:
            q = float(triangle_quality(np.concatenate([ctx.points, V]), F).min()) if len(F) else 0.0
            clean.append((q, V, F, name, relax))
            if q >= GOOD_QUALITY:  # good enough: more relaxed domains lose the loop's concavities
                break
    if clean:
        q, V, F, name, relax = max(clean, key=lambda c: c[0])
        return 0, V, F, 0, name, relax
    best = None
    # Ear clipping is costly (up to MAX_REPAIR_ROUNDS fills each): the first domain and the
    # least relaxed development only.
    for (domain, name, relax), (vertices, faces, bad) in list(zip(domains, patches))[:2]:
        keep, ears, n_clipped = np.arange(m), [], 0
        for _ in range(MAX_REPAIR_ROUNDS):
            if len(bad) == 0:
                break
            offending = np.unique(faces[bad][faces[bad] < m]).tolist()
            keep, ears, clipped_now = clip_ears(ctx, domain, keep, ears, offending)
            if clipped_now == 0:
                break
            n_clipped += clipped_now
            vertices, faces = triangulate_and_embed(ctx, domain, keep, ears, energy, refinement, tangential,
                                                    density, record)
            bad = crossing_faces(ctx, vertices, faces)
        if best is None or len(bad) < best[0]:
            best = (len(bad), vertices, faces, n_clipped, name, relax)
        if len(bad) == 0:
            break
    return best


def _quality_improving(V, F, A, B, replaced):
    """Swap filter for :func:`relax_edges`: the new pair's lower quality beats the old pair's."""
    old = np.minimum(triangle_quality(V, F[replaced[:, 0]]), triangle_quality(V, F[replaced[:, 1]]))
    new = np.minimum(triangle_quality(V, A), triangle_quality(V, B))
    return new > old + 1e-9


class _CrossingCounts:
    """``len(crossing_faces(ctx, vertices, faces))``, remembered per patch (by content) for one hole.

    The filter's later steps count the same patch more than once (the swaps' best round, the
    resampling's check, the sliver repair's input): one count each, the same numbers.
    """

    def __init__(self, ctx):
        self.ctx = ctx
        self._counts = {}

    @staticmethod
    def _key(vertices, faces):
        digest = hashlib.sha1()
        for a in (np.asarray(vertices, np.float64), np.asarray(faces, np.int64)):
            digest.update(repr(a.shape).encode())
            digest.update(np.ascontiguousarray(a).tobytes())
        return digest.digest()

    def remember(self, vertices, faces, count):
        self._counts[self._key(vertices, faces)] = int(count)

    def __call__(self, vertices, faces):
        key = self._key(vertices, faces)
        if key not in self._counts:
            self._counts[key] = len(crossing_faces(self.ctx, vertices, faces))
        return self._counts[key]


def improve_by_swaps(ctx, vertices, faces, energy, rounds=MAX_SWAP_ROUNDS, crossings=None, tangential=False,
                     resolve=True, count_crossings=None):
    """Quality-improving edge swaps followed by a new energy solve (beyond the paper, option ``swaps``).

    Sec. 3.3 places the interior vertices by a uniform-Laplacian energy on the connectivity
    of the planar refinement; at border vertices where the surface leaves a wide opening
    (gap angles near 300 degrees) the uniform weights pull interior vertices onto the border
    and squeeze triangles that were well shaped in the plane (measured: planar quality 0.98,
    spatial 0.14). Each round swaps the interior patch edges that fail the circumsphere test
    and whose swap raises the lower quality of their two triangles (no fold, no duplicate
    edge, never an edge the mesh already has, :func:`relax_edges`), then solves the energy
    again on the new connectivity, so the result still minimises E_AREA / E_DF exactly (then
    relaxes tangentially if ``tangential``, as the first embedding did). The round with the
    best minimum quality (then mean) that crosses nothing new is kept.

    Parameters
    ----------
    ctx : HoleContext
    vertices : (s, 3) float64  new vertices
    faces : (t, 3) int64  patch faces in Patch numbering (loop index i < k, new vertex k + j)
    energy : {'area', 'area_interior', 'fairing'}  see :func:`.embedding.embed_patch`
    rounds : int
    crossings : int, optional  faces of the given patch crossing the mesh (computed when needed)
    tangential : bool  see :func:`.embedding.embed_patch`
    resolve : bool
        Solve the energy again after each round (default). False keeps the vertices where they
        are (a patch sampled from the energy's shape on a finer refinement, density
        'surrounding': a new solve on the coarser connectivity would change the shape) and only
        relaxes them tangentially on the new connectivity if ``tangential``.
    count_crossings : callable, optional
        ``(vertices, faces) -> int``, the patch's faces crossing the mesh (default: the length of
        :func:`crossing_faces`; the filter passes one that remembers the patches it counted).

    Returns
    -------
    vertices : (s, 3) float64
    faces : (t, 3) int64
    swaps : int  edge swaps in the kept result
    """
    s = len(vertices)
    if s == 0:
        return vertices, faces, 0

    def score(X, F):
        q = triangle_quality(X, F)
        return float(q.min()), float(q.mean())

    start = score(np.concatenate([ctx.points, vertices]), faces)
    X, F, total = np.concatenate([ctx.points, vertices]), faces, 0
    better = []  # rounds scoring above the input: (score, round, interior, faces, swaps so far)
    for r in range(rounds):
        F, swapped = relax_edges(X, F, fixed_edges=ctx.forbidden_edges, allowed=_quality_improving)
        if swapped == 0:
            break
        total += swapped
        if resolve:
            interior = embed_patch(ctx, s, F, energy=energy, tangential=tangential)
        else:
            interior = relax_patch(ctx, X[ctx.size:], F) if tangential else X[ctx.size:]
        X = np.concatenate([ctx.points, interior])
        sc = score(X, F)
        if sc > start:
            better.append((sc, r, interior, F, total))
    return _best_round(ctx, better, vertices, faces, crossings, count_crossings)


def _best_round(ctx, better, vertices, faces, crossings, count_crossings):
    """The swaps' kept round: the earliest of the best score among the rounds crossing no more than the input.

    That is the round the running best (a round kept when it scores above the best so far and
    crosses no more than the input) ends on; taken best first, a patch's crossings are counted
    only until one passes (the input's only when that round crosses something), which spares the
    crossing tests of the rounds passed over (the most costly step after the solves).
    """
    if count_crossings is None:
        count_crossings = _CrossingCounts(ctx)
    for sc, _, interior, F, total in sorted(better, key=lambda b: (b[0][0], b[0][1], -b[1]), reverse=True):
        n = count_crossings(interior, F)
        if n == 0 or n <= (crossings if crossings is not None else count_crossings(vertices, faces)):
            return interior, F, total
    return vertices, faces, 0


def domain_area_ratios(P, gap_angles, domains):
    """Area of each planar domain, scaled to the loop's perimeter, over the missing surface's (beyond the paper).

    Parameters as :func:`domains_within_area`.

    Returns
    -------
    list of float  (0 for every domain of a loop whose development has no area: nothing to compare with)
    """
    reference = developed_area(P, gap_angles)
    if not reference > 0.0:
        return [0.0] * len(domains)
    perimeter = polygon_perimeter(P)
    return [abs(polygon_signed_area(D)) * (perimeter / polygon_perimeter(D)) ** 2 / reference
            for D, _, _ in domains]


def domains_within_area(P, gap_angles, domains, max_ratio):
    """The planar domains whose area is at most ``max_ratio`` times the missing surface's (beyond the paper).

    Unfolding keeps the loop's edge lengths, not its shape: a long strip-shaped hole (a scan
    line missing across a body) can unfold to a round polygon that encloses many times the
    strip's area, and its embedded patch bulges far out of the surface. Each domain, scaled to
    the loop's perimeter as Sec. 3.3 scales it, is compared with
    :func:`..geometry.development.developed_area`. Measured: on the benchmark's 62 holes the
    ratio is at most 1.9; on 632 fuzzed holes at most 4.8 apart from two, whose patches
    crossed the mesh anyway: a 159-edge hole of cow.obj (8.9) and a 697-edge strip across
    bunny.obj (14.9, 158 s of repair before it failed).

    Parameters
    ----------
    P : (m, 3) float64  loop
    gap_angles : (m,) float64
    domains : list of ((m, 2) float64, str, float or None)  see :func:`repair_crossings`
    max_ratio : float

    Returns
    -------
    list  the domains kept, in their order

    Raises
    ------
    HoleFillError
        when no domain is small enough.
    """
    ratios = domain_area_ratios(P, gap_angles, domains)
    kept = [d for d, r in zip(domains, ratios) if r <= max_ratio]
    if not kept:
        raise HoleFillError(
            f"every unfolding of the boundary encloses at least {min(ratios):.1f} times the area of the "
            f"missing surface (max_domain_area = {max_ratio:g}): a strip-shaped hole whose patch would bulge "
            f"out of the surface")
    return kept


class _PlanarDomains:
    """The planar domains of one hole, each computed when first needed.

    Developing the loop and testing a development for simplicity cost O(m^2) each (the exact
    clearance of every pair of segments), and the annealing's first projection is simple on
    most holes, whose patches then cross nothing: the fallback polygon is only developed when
    the first annealing run fails, the repair's developments only when the first patch crosses
    the mesh (the same polygons and the same choices as when all were developed up front).

    Parameters
    ----------
    P : (m, 3) float64  loop
    gaps : (m,) float64 or None  gap angles of the surrounding surface (None for a triangle)
    epsilon : float  relative clearance, as :func:`fill`'s
    developments : bool  the repair may try the loop's developments
    max_domain_area : float  as :func:`fill`'s (0: no bound)
    """

    def __init__(self, P, gaps, epsilon, developments, max_domain_area):
        self.P, self.gaps, self.epsilon = P, gaps, epsilon
        self.developments, self.max_domain_area = developments, max_domain_area
        self.relax = None  # blend of the fallback development, once developed (None: none simple)
        self._fallback = self._all = None

    def fallback(self):
        """The development offered to :func:`.unfolding.unfold_loop`: the least relaxed simple one, else the plain one."""
        if self._fallback is None:
            m = len(self.P)
            h = polygon_perimeter(self.P) / m
            self._fallback, self.relax = simple_development(self.P, self.gaps, self.epsilon * h)
            if self._fallback is None:  # offered anyway: unfold_loop then names it in its failure
                self._fallback = develop_loop(self.P, self.gaps)
        return self._fallback

    def _bounded(self):
        return self.max_domain_area > 0 and self.gaps is not None

    def first(self, Q, method):
        """[the unfolding's domain] if it is within the area bound, else every domain within it (:meth:`all`)."""
        first = [(Q, method, self.relax if method == "development" else None)]
        if not self._bounded() or domain_area_ratios(self.P, self.gaps, first)[0] <= self.max_domain_area:
            return first
        return self.all(Q, method)

    def all(self, Q, method):
        """The unfolding's domain, then the loop's other simple developments, those within the area bound.

        Raises
        ------
        HoleFillError
            when none is within the area bound (:func:`domains_within_area`).
        """
        if self._all is None:
            domains = [(Q, method, self.relax if method == "development" else None)]
            if self.developments:
                m = len(self.P)
                eps_abs = self.epsilon * polygon_perimeter(self.P) / m
                domains += [(D, "development", r) for D, r in simple_developments(self.P, self.gaps, eps_abs)
                            if not (method == "development" and r == self.relax)]
            if self._bounded():
                domains = domains_within_area(self.P, self.gaps, domains, self.max_domain_area)
            self._all = domains
        return self._all


def _development_domain(planar_domains):
    """Option ``domain='development'`` (beyond the paper): the loop's least relaxed simple development, no annealing.

    The development (:func:`..geometry.development.develop_loop`) turns by the angles the
    surrounding surface leaves at each loop vertex and walks the loop's edge lengths: on a
    developable surface (a crease between two flat flanks, a cylinder) it is the removed
    surface's own layout, on a curved one the closure spreads the angle deficit along the loop.
    Measured on the benchmark's 45 cut holes (mean patch-to-ground-truth distance per mille of
    the diagonal, default -> this option, the loop-length unfolding as the default): crease 4.05
    -> 2.55, crossing 0.46 -> 0.29, real-size 1.31 -> 0.78, large 2.06 -> 2.70 (the sphere's
    157-edge hole 1.26 -> 3.70), medium 1.64 -> 1.67, small 0.153 -> 0.192, all holes 2.01 -> 1.50.

    Returns
    -------
    Q : (m, 2) float64 or None  None when no development of the ladder is simple
    info : dict or None  as :func:`.unfolding.unfold_loop`'s
    """
    D = planar_domains.fallback()
    if planar_domains.relax is None:
        return None, None
    return D, {"method": "development", "restarts": 0, "sa_steps": 0, "accepted_steps": 0, "loop_lengths": False}


def _edge_ratio(ctx, vertices, faces):
    """Mean patch edge (each face's three edges) over the mean edge of the faces around the hole."""
    e = surrounding_edge_length(ctx)
    return float(edge_lengths(np.concatenate([ctx.points, vertices]), faces).mean() / e) if e > 0 else 1.0


def _corner_angle(P, keep, v):
    i = keep.index(v)
    a, b = P[keep[i - 1]] - P[v], P[keep[(i + 1) % len(keep)]] - P[v]
    return float(np.arccos(np.clip(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)), -1.0, 1.0)))


def fill(ctx, k=0.9, temperature=0.5, epsilon=1e-5, max_restarts=100, sa_steps=5000, step_bound="global",
         energy="area", refinement=True, fallback=True, repair=True, swaps=True, tangential=True, seed=0,
         area_rows="mesh", max_domain_area=6.0, density="surrounding", slivers=True, lengths="loop",
         domain="unfolding"):
    """Fill one hole by unfolding, triangulation and embedding (Sec. 3.1-3.3).

    The loop is unfolded into a simple planar polygon (:func:`.unfolding.unfold_loop`, Sec.
    3.1), triangulated and refined in the plane and embedded by the energy of Sec. 3.3
    (:func:`.unfolded_triangulation.triangulate_and_embed`, :mod:`.embedding`); the
    development fallback, the crossing repair and the swaps are beyond the paper.

    Parameters
    ----------
    ctx : HoleContext
        The hole and ``RINGS`` rings of faces around it (:func:`meshlab_holefill.core.holes.hole_context`).
    k, temperature : float
        Annealing constant (Boltzmann factor and cooling) and start temperature (Sec. 3.1, 4).
    epsilon : float
        Clearance kept between non-adjacent boundary segments, relative to the mean edge length.
    max_restarts, sa_steps : int
        Annealing runs before giving up, and moves per run.
    step_bound : {'global', 'local'}
        Bound of a move's length.
    lengths : {'loop', 'projection'}
        Edge lengths of the unfolded polygon (:func:`.unfolding.with_loop_lengths`).
    domain : {'unfolding', 'development'}
        Beyond the paper: 'development' takes the loop's simple development as the planar domain
        whenever there is one (:func:`_development_domain`).
    energy : {'area', 'fairing'}
        E_AREA or E_DF (Sec. 3.3); ``area_rows`` ({'mesh', 'interior'}) chooses E_AREA's rows.
    refinement : bool
        Planar refinement of Sec. 3.3.
    density : {'surrounding', 'twice', 'equilateral'}
        Its area bound (:func:`.unfolded_triangulation.triangulate_and_embed`).
    fallback, repair, swaps, tangential, slivers : bool
        Beyond the paper: development fallback, crossing repair, quality swaps, tangential relaxation,
        sliver repair (:func:`.slivers.repair_slivers`).
    seed : int
        Seed of the annealing.
    area_rows : {'mesh', 'interior'}
    max_domain_area : float
        Largest planar domain embedded, as a multiple of the missing surface's area (0: no limit).

    Returns
    -------
    Patch
        ``vertices`` (p, 3) float64 and ``faces`` (q, 3) int64 in loop-local indices (i < k:
        loop vertex i). ``info``: ``unfolding`` ('annealing' or 'development'), ``restarts``, ``sa_steps``,
        ``energy_pe_start`` / ``energy_pe_end`` (E_PE before / after annealing),
        ``development_relax`` (blend of the development used, or offered to the annealing
        after its first run failed, see :func:`simple_development`; None when none was developed), ``ears_clipped``, ``edge_swaps``, ``crossing_faces`` (left
        after repair; the filter rejects such a patch),
        ``unfolding_seconds`` (Sec. 3.1), ``embedding_seconds`` (Sec. 3.2-3.3: triangulation,
        refinement and energy solve, as the paper's embedding times), ``repair_seconds`` and
        ``swap_seconds``.

    Raises
    ------
    HoleFillError
        When no simple planar domain is found (or none within ``max_domain_area``), or the
        embedding fails.

    References
    ----------
    A. Brunton, S. Wuhrer, C. Shu, P. Bose and E. D. Demaine, "Filling Holes in Triangular
    Meshes by Curve Unfolding", IEEE International Conference on Shape Modeling and
    Applications (SMI), 2009.

    Examples
    --------
    A round hole in a bowl-shaped grid, its boundary unfolded into the plane and the patch embedded:

    >>> from meshlab_holefill.core import examples, hole_context
    >>> V, F, loop = examples.bowl_with_hole()
    >>> ctx = hole_context(V, F, loop, rings=RINGS)
    >>> patch = fill(ctx, seed=0)
    >>> examples.is_disc_patch(patch, ctx)  # closes the loop exactly once, as a disc
    True
    """
    P = ctx.points
    m = ctx.size
    rng = np.random.default_rng(seed)
    if energy == "area" and area_rows == "interior":
        energy = "area_interior"  # the embedding's name for E_AREA summed over P_Int only
    t0 = time.perf_counter()
    gaps = boundary_gap_angles(ctx.vertices, ctx.faces, m) if m > 3 else None
    planar_domains = _PlanarDomains(P, gaps, epsilon, repair and fallback and m > 3, max_domain_area)
    Q, unfold_info = _development_domain(planar_domains) if domain == "development" and m > 3 else (None, None)
    if Q is None:
        Q, unfold_info = unfold_loop(P, rng, k=k, temperature=temperature, epsilon=epsilon,
                                     max_restarts=max_restarts, sa_steps=sa_steps, step_bound=step_bound,
                                     fallback=planar_domains.fallback if fallback and m > 3 else None,
                                     lengths=lengths)
    method = unfold_info["method"]
    relax = planar_domains.relax
    domains = planar_domains.first(Q, method)
    Q, method, used = domains[0]
    if method == "development":
        relax = used
    t1 = time.perf_counter()
    records = []  # planar triangulations of the patches built, for the resampling
    vertices, faces = triangulate_and_embed(ctx, Q, np.arange(m), [], energy, refinement, tangential, density,
                                            records)
    t2 = time.perf_counter()
    n_bad, clipped = 0, 0
    if repair:
        bad = crossing_faces(ctx, vertices, faces)
        if len(bad):  # the other domains are only built for a patch that crosses the mesh
            domains = planar_domains.all(Q, method)
        n_bad, vertices, faces, clipped, method, used = repair_crossings(
            ctx, domains, vertices, faces, energy, refinement, tangential, density, records, bad=bad)
        if method == "development":
            relax = used
    counts = _CrossingCounts(ctx)
    if repair:
        counts.remember(vertices, faces, n_bad)
    n_swaps = 0
    t3 = time.perf_counter()
    planar = next((r for r in records if r.faces.shape == faces.shape and np.array_equal(r.faces, faces)), None)
    if swaps:
        vertices, faces, n_swaps = improve_by_swaps(ctx, vertices, faces, energy,
                                                    crossings=int(n_bad) if repair else None,
                                                    tangential=tangential, count_crossings=counts)
    t4 = time.perf_counter()
    resampled = False
    if (refinement and density == "surrounding" and planar is not None and len(vertices)
            and abs(_edge_ratio(ctx, vertices, faces) - 1.0) > RESAMPLE_TOLERANCE):
        def finish(V, F):
            return improve_by_swaps(ctx, V, F, energy, tangential=tangential, resolve=False,
                                    count_crossings=counts)[:2]

        resampled_patch = resample_patch(ctx, planar, vertices, tangential=tangential,
                                         finish=finish if swaps else None)
        # The sampled patch lies on the shape; it is kept unless it crosses more of the mesh.
        if counts(*resampled_patch) <= n_bad:
            vertices, faces = resampled_patch
            resampled = True
    t5 = time.perf_counter()
    sliver_rounds = 0
    if slivers:
        vertices, faces, sliver_rounds = repair_slivers(ctx, vertices, faces, counts)
    t6 = time.perf_counter()
    info = {
        "unfolding": method,
        "restarts": unfold_info["restarts"],
        "loop_lengths": unfold_info.get("loop_lengths", False),
        "sa_steps": unfold_info["sa_steps"],
        "energy_pe_start": unfold_info.get("energy_pe_start", 0.0),
        "energy_pe_end": unfold_info.get("energy_pe_end", 0.0),
        "development_relax": relax,
        "ears_clipped": clipped,
        "edge_swaps": n_swaps,
        "crossing_faces": int(n_bad),
        "unfolding_seconds": t1 - t0,
        "embedding_seconds": t2 - t1,
        "repair_seconds": t3 - t2,
        "swap_seconds": t4 - t3,
        "resampled": resampled,
        "resample_seconds": t5 - t4,
        "sliver_rounds": sliver_rounds,
        "sliver_seconds": t6 - t5,
    }
    return Patch(vertices=vertices, faces=faces, info=info)


_WARM = []  # set once the compiled kernels are loaded in this process


def warm_up():
    """Load the compiled kernels a fill calls now: a small hole filled, a small loop annealed.

    The kernels (the annealing's moves, the segment distances, the triangle intersection tests)
    are compiled on first use and cached on disk; loading them takes a few tenths of a second
    per process. Called before holes are filled in forked worker processes, it lets the workers
    inherit them instead of each loading them within its first hole's time.
    """
    if _WARM:
        return
    V, F, loop = examples.bowl_with_hole()
    fill(hole_context(V, F, loop, rings=RINGS))
    t = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False)
    ring = np.stack([np.cos(t), np.sin(t), 0.3 * np.cos(2.0 * t)], axis=1)
    for step_bound in ("global", "local"):
        anneal_loop(ring, np.random.default_rng(0), eps=1e-6, sa_steps=24, step_bound=step_bound,
                    stop_when_simple=False)
    _WARM.append(True)


WARM_UP = warm_up  # loads the compiled kernels before holes are filled in forked workers
