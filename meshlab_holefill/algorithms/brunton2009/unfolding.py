"""Unfolding a boundary loop into a simple planar polygon (Brunton et al. 2009, Sec. 3.1).

The loop is moved vertex by vertex by simulated annealing (Press et al., Numerical Recipes
Sec. 10.9) to lower the planarity energy E_PE (the angles between the normals n_i of
consecutive vertex triples), never letting two non-adjacent segments come closer than
epsilon, and then projected to its best-fitting plane; the projection is accepted when the
loop reaches it by a linear motion without self-intersection, otherwise annealing restarts.

Readings of what Sec. 3.1 leaves open:

* **Restart.** A run without a simple projection restarts from the original loop with the
  next random numbers of the same generator (one seed fixes the whole sequence).
* **Lengths.** An unfolding in the sense of linkages (Sec. 3.1 "unfold the loop ... by
  gradually moving the vertices", "a planar curve with similar curvature as the boundary loop")
  keeps the edge lengths, but the projection to the best plane shortens every edge by the cosine
  of its tilt: by up to 30 % on a loop around a crease, whose two flanks tilt away from the best
  plane on either side. The accepted projection's edge directions are kept and the loop's own
  edge lengths walked along them, closed by the smallest relative change of the lengths
  (:func:`with_loop_lengths`, ``lengths='loop'``, the default); the projection itself when that
  polygon is not simple. Measured on the benchmark's 45 cut holes (mean patch-to-ground-truth
  distance per mille of the diagonal, projection -> loop lengths): crease 4.92 -> 4.00, crossing
  0.73 -> 0.46, real-size 1.35 -> 1.31, large 1.89 -> 1.93, medium 1.68 -> 1.64, small 0.155 ->
  0.153, all holes 2.34 -> 1.98 (``lengths='projection'`` keeps the projection, scaled to the
  loop's perimeter in Sec. 3.3 as before).
* **Units.** epsilon is relative to the loop's mean edge length (the paper's 1e-5 is in model
  units), which makes the method scale invariant.

The annealing's own readings (move, energy, direction, schedule, stopping rule) are in
:mod:`.annealing`.

Beyond the paper, :func:`geometry.development.develop_loop` gives a fallback polygon for loops the annealing does not
unfold (loops wrapped around a tube or a knob project onto themselves from every side), and
:func:`geometry.development.simple_development` relaxes it towards the convex polygon until it is simple.
"""
from __future__ import annotations

import numpy as np

from ...errors import HoleFillError
from ...geometry.development import close_lengths
from ...geometry.segments import min_segment_distance
from .linear_motion import linear_motion_is_simple, project_to_best_plane
from .annealing import anneal_loop

__all__ = ["with_loop_lengths", "unfold_loop"]


def with_loop_lengths(Q, P, eps):
    """The unfolded polygon with the loop's edge lengths: the projection's edge directions, the loop's lengths.

    Reading of Sec. 3.1 (module docstring, **Lengths**): edge i keeps the direction it has in
    the projection Q and gets the length of loop edge i; the polygon is closed by the smallest
    relative change of those lengths (:func:`..geometry.development.close_lengths`, no edge
    shorter than 2 % of its length), the first vertex staying where it is.

    Parameters
    ----------
    Q : (m, 2) float64  simple projected polygon
    P : (m, 3) float64  the loop
    eps : float  absolute clearance the polygon must keep (d_MD > eps)

    Returns
    -------
    (m, 2) float64 or None  None when the polygon is not simple (or Q has a zero-length edge)
    """
    Q = np.asarray(Q, np.float64)
    edges = np.roll(Q, -1, axis=0) - Q
    planar = np.linalg.norm(edges, axis=1)
    if not np.all(planar > 0.0):
        return None
    directions = edges / planar[:, None]
    lengths = close_lengths(np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1), directions)
    R = Q[0] + np.concatenate([[[0.0, 0.0]], np.cumsum(lengths[:, None] * directions, axis=0)[:-1]])
    if not np.all(np.isfinite(R)) or not linear_motion_is_simple(R, eps):
        return None
    return R


def unfold_loop(P, rng, k=0.9, temperature=0.5, epsilon=1e-5, max_restarts=100, sa_steps=5000,
                step_bound="global", fallback=None, lengths="loop"):
    """Unfold a boundary loop into a simple planar polygon (Sec. 3.1).

    Anneal (:func:`anneal_loop`), project to the best-fitting plane
    (:func:`project_to_best_plane`) and accept if the linear motion to the projection keeps
    the loop simple (:func:`linear_motion_is_simple`); otherwise restart from the original
    loop, at most ``max_restarts`` annealing runs in all. A ``fallback`` polygon (e.g.
    :func:`geometry.development.develop_loop`), beyond the paper, is tried after the first failed run; if it is
    simple it is used and the remaining restarts are skipped.

    Parameters
    ----------
    P : (m, 3) float64
        Boundary loop in order, m >= 3.
    rng : numpy.random.Generator
    k, temperature, sa_steps, step_bound : see :func:`anneal_loop`
    epsilon : float
        Clearance threshold relative to the loop's mean edge length.
    max_restarts : int
        Maximum number of annealing runs (paper: 100).
    fallback : (m, 2) float64 or callable, optional
        The fallback polygon, or a function returning it, called only when the first run fails
        (developing a loop costs O(m^2)).
    lengths : {'loop', 'projection'}
        Edge lengths of the accepted projection: 'loop' = the loop's own (:func:`with_loop_lengths`,
        the projection where that polygon is not simple), 'projection' = as projected.

    Returns
    -------
    Q : (m, 2) float64
        Simple planar polygon, vertex i the image of loop vertex i.
    info : dict
        ``method`` ('annealing' or 'development'), ``restarts`` (annealing runs - 1),
        ``sa_steps`` (moves over all runs), ``accepted_steps``, ``energy_pe_start``,
        ``energy_pe_end`` (E_PE before and after the last run), ``d_md_start``, ``loop_lengths``
        (the annealed projection got the loop's edge lengths).

    Raises
    ------
    HoleFillError
        For a degenerate loop (non-finite, touching itself, zero area) or when no run
        gives a simple projection and the fallback is not simple either (e.g. a knotted loop).
    """
    P = np.asarray(P, np.float64)
    m = len(P)
    if m < 3:
        raise HoleFillError("a boundary loop needs at least 3 vertices")
    if not np.all(np.isfinite(P)):
        raise HoleFillError("boundary loop has non-finite coordinates")
    h = float(np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1).mean())
    if not h > 0:
        raise HoleFillError("boundary loop has zero length")
    eps = epsilon * h
    d_md = min_segment_distance(P)
    if d_md <= eps:
        raise HoleFillError(f"boundary loop touches itself (d_MD = {d_md:.3g} <= epsilon = {eps:.3g}); "
                            "curve unfolding needs a simple loop")
    info = {"method": "annealing", "restarts": 0, "sa_steps": 0, "accepted_steps": 0, "d_md_start": d_md,
            "loop_lengths": False}
    runs = max(int(max_restarts), 1)
    for run in range(runs):
        annealed, stats = anneal_loop(P, rng, k=k, temperature=temperature, eps=eps,
                                      sa_steps=sa_steps, step_bound=step_bound)
        info.update(restarts=run, sa_steps=info["sa_steps"] + stats["steps"],
                    accepted_steps=info["accepted_steps"] + stats["accepted"],
                    energy_pe_start=stats["energy_start"], energy_pe_end=stats["energy_end"])
        Q, _, _ = project_to_best_plane(annealed)
        # A run that ended on a simple projection has passed this test (the same answer with far
        # pairs only bounded); the exact distances of every pair are measured only otherwise.
        if stats["simple"] or linear_motion_is_simple(Q, eps):
            R = with_loop_lengths(Q, P, eps) if lengths == "loop" else None
            info["loop_lengths"] = R is not None
            return (Q if R is None else R), info
        if run == 0 and fallback is not None:
            polygon = np.asarray(fallback() if callable(fallback) else fallback, np.float64)
            if linear_motion_is_simple(polygon, eps):
                info["method"] = "development"
                return polygon, info
    if m == 3:
        raise HoleFillError("boundary loop is a degenerate (zero-area) triangle")
    raise HoleFillError(f"curve unfolding failed: no annealing run out of {runs} gave a loop whose projection "
                        "to its best-fitting plane is simple"
                        + (", nor is the loop's development" if fallback is not None else "")
                        + " (knotted or strongly wrapped boundary)")
