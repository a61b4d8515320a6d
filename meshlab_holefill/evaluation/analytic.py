"""The analytic test surfaces of the benchmark: a unit sphere and a torus (R = 1, r = 0.4), meshed and exact.

Their meshes, the exact distance to the surface they sample and its area (Xu et al.'s error
normalisation) are used by the benchmark suite, the stage measurements and the tests, so that
all of them measure on the same surfaces.
"""
from __future__ import annotations

import numpy as np

from ..meshlab.mesh_files import generated_mesh

__all__ = ["ANALYTIC_SURFACES", "analytic_area", "analytic_distance", "analytic_mesh"]

ANALYTIC_SURFACES = ("sphere", "torus")
TORUS_RADII = (1.0, 0.4)  # centre-line and tube radius


def _check(name):
    if name not in ANALYTIC_SURFACES:
        raise ValueError(f"unknown analytic surface '{name}' (known: {', '.join(ANALYTIC_SURFACES)})")


def analytic_mesh(name):
    """(V, F) of the surface meshed by pymeshlab: the sphere at subdivision 5 (20,480 faces), the torus
    192 x 96 (36,864 faces)."""
    _check(name)
    if name == "sphere":
        return generated_mesh("create_sphere", subdiv=5)
    return generated_mesh("create_torus", hradius=TORUS_RADII[0], vradius=TORUS_RADII[1], hsubdiv=192, vsubdiv=96)


def analytic_distance(name):
    """A function (N, 3) points -> (N,) signed distance to the exact surface (positive outside)."""
    _check(name)
    if name == "sphere":
        return lambda X: np.linalg.norm(X, axis=1) - 1.0
    R, r = TORUS_RADII
    return lambda X: np.hypot(np.hypot(X[:, 0], X[:, 1]) - R, X[:, 2]) - r


def analytic_area(name):
    """Area of the exact surface."""
    _check(name)
    R, r = TORUS_RADII
    return 4 * np.pi if name == "sphere" else 4 * np.pi ** 2 * R * r
