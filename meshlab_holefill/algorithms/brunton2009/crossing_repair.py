"""The crossing repair of the curve-unfolding filter (beyond the paper).

Brunton et al. (Sec. 3.3) accept that a patch may intersect the mesh; the filter contract does
not. :func:`crossing_faces` finds the patch faces that cross the hole's surroundings or each
other (:class:`CrossingCounts` remembers the counts of one hole's patches), and
:func:`repair_crossings` replaces a crossing patch by the best patch of another planar domain
that crosses nothing, else clips the ears of the boundary vertices involved
(:func:`clip_ears`) and fills the rest of the loop again. :class:`MadePatches` keeps what the
repair makes for one hole, which the filter fills on two domains with the same other domains.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ...core.crossings import context_crossings
from ...geometry.quality import triangle_quality
from ...core.content_key import content_key
from ...geometry.topology import edge_pair_set
from .unfolded_triangulation import triangulate_and_embed
from .linear_motion import linear_motion_is_simple

__all__ = ["GOOD_QUALITY", "MAX_REPAIR_ROUNDS", "CrossingCounts", "DomainPatch", "MadePatches", "crossing_faces",
           "clip_ears", "repair_crossings"]

MAX_REPAIR_ROUNDS = 4  # rounds of ear clipping when a patch crosses its surroundings
GOOD_QUALITY = 0.3  # repair stops trying domains at a clean patch of this minimum quality (poor triangles are below it)


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
    return context_crossings(ctx, np.concatenate([ctx.points, vertices]), np.asarray(faces, np.int64).reshape(-1, 3))


def _corner_angle(P, keep, v):
    i = keep.index(v)
    a, b = P[keep[i - 1]] - P[v], P[keep[(i + 1) % len(keep)]] - P[v]
    return float(np.arccos(np.clip(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)), -1.0, 1.0)))


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
                     record=None, bad=None, made=None):
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
    made : MadePatches, optional
        What was made for this hole before, with these options; the patches and ear clippings made
        here are added to it.

    Returns
    -------
    crossings : int  faces of the returned patch crossing the mesh
    vertices, faces : the patch
    clipped : int  ears clipped
    method : str  unfolding name of the domain used
    relax : float or None  its development blend
    """
    if bad is None:
        bad = crossing_faces(ctx, vertices, faces)
    if len(bad) == 0:
        return 0, vertices, faces, 0, domains[0][1], domains[0][2]
    if made is None:
        made = MadePatches(energy, refinement, tangential, density)
    record = [] if record is None else record
    patches = [(vertices, faces, bad)]
    clean = []
    for domain, name, relax in domains[1:]:
        made_patch = made.patch(ctx, domain)
        record.extend(made_patch.records)
        V, F, b = made_patch.vertices.copy(), made_patch.faces.copy(), made_patch.crossings(ctx).copy()
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
        n_bad, vertices, faces, n_clipped = made.clipped(ctx, domain, vertices, faces, bad, record)
        if best is None or n_bad < best[0]:
            best = (n_bad, vertices, faces, n_clipped, name, relax)
        if n_bad == 0:
            break
    return best


def _clipped_until_clear(ctx, domain, vertices, faces, bad, energy, refinement, tangential, density, record):
    """Ears clipped at the crossing faces' boundary vertices and the rest filled again, round by round
    (at most MAX_REPAIR_ROUNDS), from the whole loop's patch on ``domain``: (crossings, vertices, faces, clipped)."""
    m = ctx.size
    keep, ears, n_clipped = np.arange(m), [], 0
    for _ in range(MAX_REPAIR_ROUNDS):
        if len(bad) == 0:
            break
        offending = np.unique(faces[bad][faces[bad] < m]).tolist()
        keep, ears, clipped_now = clip_ears(ctx, domain, keep, ears, offending)
        if clipped_now == 0:
            break
        n_clipped += clipped_now
        vertices, faces = triangulate_and_embed(ctx, domain, keep, ears, energy, refinement, tangential, density,
                                                record)
        bad = crossing_faces(ctx, vertices, faces)
    return len(bad), vertices, faces, n_clipped


@dataclass
class DomainPatch:
    """The whole loop's patch on one planar domain (:func:`triangulate_and_embed`), as :class:`MadePatches` keeps it."""

    vertices: np.ndarray  # (s, 3) new vertices
    faces: np.ndarray  # (t, 3) in Patch numbering
    records: list  # the PlanarPatch triangulate_and_embed recorded for it
    seconds: float  # what making it took
    crossing: np.ndarray = None  # its crossing_faces, once asked for

    def crossings(self, ctx):
        """:func:`crossing_faces` of the patch, found once."""
        if self.crossing is None:
            self.crossing = crossing_faces(ctx, self.vertices, self.faces)
        return self.crossing


@dataclass
class MadePatches:
    """The crossing repair's work for one hole with one set of embedding options, each piece made once.

    The filter's default domain choice fills the hole on the unfolding and on the development
    (:func:`.domain_choice.smoothest_patch`), and the repair of either tries the same other
    domains and clips ears in the same ones: the noisy cow's 250-edge hole of
    ``scripts/unseen_holes.py`` (seed 5) embedded 24 of its 48 patches twice when filled again
    with the mesh faces its first patch crossed. The whole loop's patch on a domain
    (:meth:`patch`) and the ear clipping from it (:meth:`clipped`) are deterministic in the
    domain, so each is made once; a caller gets copies and the same records.
    """

    energy: str
    refinement: bool
    tangential: bool
    density: str
    _patches: dict = field(default_factory=dict)
    _clipped: dict = field(default_factory=dict)

    def patch(self, ctx, domain, embed=None):
        """The :class:`DomainPatch` of the whole loop on the planar polygon ``domain`` ((k, 2) float64).

        ``embed`` is :func:`triangulate_and_embed` or a caller's name for it.
        """
        key = content_key(np.asarray(domain, np.float64))
        if key not in self._patches:
            embed = triangulate_and_embed if embed is None else embed
            built, t0 = [], time.perf_counter()
            vertices, faces = embed(ctx, domain, np.arange(ctx.size), [], self.energy, self.refinement,
                                    self.tangential, self.density, built)
            self._patches[key] = DomainPatch(vertices, faces, built, time.perf_counter() - t0)
        return self._patches[key]

    def clipped(self, ctx, domain, vertices, faces, bad, record):
        """:func:`_clipped_until_clear` from the patch (vertices, faces) on ``domain`` with crossing faces ``bad``.

        Returns (crossings, vertices, faces, clipped) and extends ``record`` with the PlanarPatch
        records of the fills, as a first run does.
        """
        key = content_key(np.asarray(domain, np.float64), np.asarray(vertices, np.float64),
                          np.asarray(faces, np.int64))
        if key not in self._clipped:
            built = []
            result = _clipped_until_clear(ctx, domain, vertices, faces, bad, self.energy, self.refinement,
                                          self.tangential, self.density, built)
            self._clipped[key] = (result, built)
        (n_bad, vertices, faces, n_clipped), built = self._clipped[key]
        record.extend(built)
        return n_bad, vertices.copy(), faces.copy(), n_clipped


class CrossingCounts:
    """``len(crossing_faces(ctx, vertices, faces))``, remembered per patch (by content) for one hole.

    The filter's later steps count the same patch more than once (the swaps' best round, the
    resampling's check, the sliver repair's input): one count each, the same numbers.
    """

    def __init__(self, ctx):
        self.ctx = ctx
        self._counts = {}

    @staticmethod
    def _key(vertices, faces):
        return content_key(np.asarray(vertices, np.float64), np.asarray(faces, np.int64))

    def remember(self, vertices, faces, count):
        self._counts[self._key(vertices, faces)] = int(count)

    def __call__(self, vertices, faces):
        key = self._key(vertices, faces)
        if key not in self._counts:
            self._counts[key] = len(crossing_faces(self.ctx, vertices, faces))
        return self._counts[key]
