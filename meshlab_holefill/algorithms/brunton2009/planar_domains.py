"""The planar domains a curve-unfolding patch may be built on: Sec. 3.1's unfolding and the developments.

:class:`PlanarDomains` yields, lazily, the unfolded loop (Sec. 3.1) and the loop's simple
developments (beyond the paper, :mod:`meshlab_holefill.geometry.development`) that the fallback
and the crossing repair try; :func:`domains_within_area` drops domains enclosing many times
the missing surface's area; :func:`development_domain` is the domain of ``domain='development'``.
"""
from __future__ import annotations

from ...geometry.development import develop_loop, developed_area, simple_development, simple_developments
from ...geometry.triangulate import polygon_perimeter, polygon_signed_area
from ...errors import HoleFillError

__all__ = ["PlanarDomains", "domain_area_ratios", "domains_within_area", "development_domain"]


def domain_area_ratios(P, gap_angles, domains, reference=None):
    """Area of each planar domain, scaled to the loop's perimeter, over the missing surface's (beyond the paper).

    Parameters as :func:`domains_within_area`.

    Returns
    -------
    list of float  (0 for every domain of a loop whose development has no area: nothing to compare with)
    """
    if reference is None:
        reference = developed_area(P, gap_angles)
    if not reference > 0.0:
        return [0.0] * len(domains)
    perimeter = polygon_perimeter(P)
    return [abs(polygon_signed_area(D)) * (perimeter / polygon_perimeter(D)) ** 2 / reference
            for D, _, _ in domains]


def domains_within_area(P, gap_angles, domains, max_ratio, reference=None):
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
    reference : float, optional  the missing surface's area, :func:`..geometry.development.developed_area` (P, gap_angles)

    Returns
    -------
    list  the domains kept, in their order

    Raises
    ------
    HoleFillError
        when no domain is small enough.
    """
    ratios = domain_area_ratios(P, gap_angles, domains, reference)
    kept = [d for d, r in zip(domains, ratios) if r <= max_ratio]
    if not kept:
        raise HoleFillError(
            f"every unfolding of the boundary encloses at least {min(ratios):.1f} times the area of the "
            f"missing surface (max_domain_area = {max_ratio:g}): a strip-shaped hole whose patch would bulge "
            f"out of the surface")
    return kept


class PlanarDomains:
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
    shared : dict, optional
        The developments of this loop already made, shared by the domains of the fills of one hole
        with the same parameters (``domain='smoothest'`` fills it on two domains): each is developed
        once, each object still reports only what it was asked for.
    """

    def __init__(self, P, gaps, epsilon, developments, max_domain_area, shared=None):
        self.P, self.gaps, self.epsilon = P, gaps, epsilon
        self.developments, self.max_domain_area = developments, max_domain_area
        self.relax = None  # blend of the fallback development, once developed (None: none simple)
        self._fallback = self._all = None
        self._shared = {} if shared is None else shared

    def fallback(self):
        """The development offered to :func:`.unfolding.unfold_loop`: the least relaxed simple one, else the plain one."""
        if self._fallback is None:
            if "fallback" not in self._shared:
                m = len(self.P)
                h = polygon_perimeter(self.P) / m
                D, relax = simple_development(self.P, self.gaps, self.epsilon * h)
                if D is None:  # offered anyway: unfold_loop then names it in its failure
                    D = develop_loop(self.P, self.gaps)
                self._shared["fallback"] = (D, relax)
            self._fallback, self.relax = self._shared["fallback"]
        return self._fallback

    def _bounded(self):
        return self.max_domain_area > 0 and self.gaps is not None

    def _reference_area(self):
        """The missing surface's area the domains are compared with (:func:`domain_area_ratios`)."""
        if "reference" not in self._shared:
            self._shared["reference"] = developed_area(self.P, self.gaps)
        return self._shared["reference"]

    def first(self, Q, method):
        """[the unfolding's domain] if it is within the area bound, else every domain within it (:meth:`all`)."""
        first = [(Q, method, self.relax if method == "development" else None)]
        if not self._bounded() or (domain_area_ratios(self.P, self.gaps, first, self._reference_area())[0]
                                   <= self.max_domain_area):
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
                if "developments" not in self._shared:
                    self._shared["developments"] = simple_developments(self.P, self.gaps, eps_abs)
                domains += [(D, "development", r) for D, r in self._shared["developments"]
                            if not (method == "development" and r == self.relax)]
            if self._bounded():
                domains = domains_within_area(self.P, self.gaps, domains, self.max_domain_area,
                                              self._reference_area())
            self._all = domains
        return self._all


def development_domain(planar_domains):
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
