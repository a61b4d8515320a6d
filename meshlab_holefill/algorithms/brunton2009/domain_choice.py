"""Which planar domain a curve-unfolding patch is built on, when both are at hand (beyond the paper).

Option ``domain='smoothest'`` (:func:`smoothest_patch`): the hole is filled on Sec. 3.1's
unfolded loop and on the loop's development over the surrounding surface's angles, each by the
whole filter (Sec. 3.2-3.3 and the steps after them), and the patch
that meets the surrounding surface with the smaller mean bend across the hole's border
(:func:`meshlab_holefill.core.border_bend.border_bend`) is kept. Neither domain wins everywhere: the development is the removed
surface's own layout on developable surfaces (creases, cylinders, the flanks of a CAD part) and
drifts on large holes of curved ones, where the unfolding is closer. Either way the patch that
continues the surface without a kink at the border is the one that bends like the missing
surface there, which needs no ground truth to measure.
"""
from __future__ import annotations

import numpy as np

from ...errors import HoleFillError
from ...geometry.development import enclosed_curvature
from ...core.border_bend import border_bend

__all__ = ["DOMAINS", "smoothest_patch", "development_is_candidate"]

DOMAINS = ("unfolding", "development")  # the candidates, in the order a tie is decided


def development_is_candidate(gap_angles):
    """Whether the development competes with the unfolding: the loop encloses less than a full turn of curvature.

    On the surface the loop turns by 2 pi - K, K its enclosed Gaussian curvature
    (:func:`geometry.development.enclosed_curvature`); a simple planar polygon turns by 2 pi, so
    the development (:func:`geometry.development.develop_loop`) bends every corner by K / m to
    close. From |K| = 2 pi on (a loop round more than a hemisphere's worth of curvature turns by 0
    or less on the surface, a saddle's by 4 pi or more) that changes the loop's total turning by a
    full turn or more and the layout no longer resembles the missing surface's: the unfolding
    alone is used.
    airplane.obj Loop-subdivided once, ``scripts/large_holes.py``'s airplane1_s1 hole 0 (296
    edges, K = 7.2 rad): the border bend chose the development's patch,
    11.40 per mille of the bounding-box diagonal from the ground truth, where the unfolding's is
    5.10 (CGAL's Liepa fill 4.89); no other hole of those 24 or of the benchmark suite reaches it.

    Parameters
    ----------
    gap_angles : (m,) float64  from :func:`geometry.development.boundary_gap_angles`

    Returns
    -------
    bool
    """
    return abs(enclosed_curvature(gap_angles)) < 2.0 * np.pi


def smoothest_patch(ctx, fill_on):
    """The patch of the two planar domains that bends least against the surrounding surface.

    A patch that would still cross the mesh (the filter rejects it) loses to one that does
    not; then the smaller :func:`border_bend` wins, a tie going to Sec. 3.1's unfolding.
    The patches are judged finished (after the swaps, resampling and sliver repair): judged as
    embedded, with only the winner finished, the choice differed on 76 of 436 holes where both
    domains compete, the filter took 0.69 of the time on the benchmark's 45 cut holes (one
    core, 2.19 -> 1.51 s) and ``scripts/unseen_holes.py --seeds 1,2,3,4,5,6`` moved little
    (per mille, closed 1.045 -> 1.040, creased 2.311 -> 2.341, CAD 5.962 -> 5.857, real-size
    1.071 -> 1.081, noisy 1.379 -> 1.372), but the benchmark's crease holes went from 2.706 to
    2.952 (cylinder_rims hole 0, the other domain kept: 1.49 -> 3.79).

    Parameters
    ----------
    ctx : HoleContext
    fill_on : callable
        ``fill_on(domain) -> Patch``, the filter with its other parameters, ``domain`` in
        :data:`DOMAINS`; may raise HoleFillError.

    Returns
    -------
    Patch
        The kept patch, its ``info`` with ``domain`` (the winner) and ``border_bends`` (degrees
        per domain, None for a domain whose fill failed).

    Raises
    ------
    HoleFillError
        The unfolding's, when neither domain gives a patch.
    """
    patches, errors = {}, []
    for domain in DOMAINS:
        try:
            patches[domain] = fill_on(domain)
        except HoleFillError as exc:
            errors.append(exc)
    if not patches:
        raise errors[0]
    bends = {domain: border_bend(ctx, p.vertices, p.faces) for domain, p in patches.items()}
    bends = {domain: bend if bend == bend else None for domain, bend in bends.items()}  # NaN: no border edge

    def rank(domain):
        bend = bends[domain]
        return patches[domain].info.get("crossing_faces", 0) > 0, float("inf") if bend is None else bend

    best = min(patches, key=rank)  # dicts keep DOMAINS' order and min the first of equals
    patch = patches[best]
    patch.info.update(domain=best, border_bends={domain: bends.get(domain) for domain in DOMAINS})
    return patch
