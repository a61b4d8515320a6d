"""Scan-like test cases: a closed mesh whose vertices noise has moved along their normals.

A range scan measures each point with an error along the line of sight, which on a surface seen
face-on is an error along the normal. :func:`normal_noise` moves every vertex along its unit
normal by a Gaussian amount whose deviation is ``sigma`` times the mesh's mean edge length, so the
noise scales with the sampling, as a scanner's does with its resolution. The holes cut into such
a mesh have jagged, non-planar borders, and their ground truth is the noisy surface itself.
"""
from __future__ import annotations

import numpy as np

from ..geometry.quality import edge_lengths, vertex_normals

__all__ = ["normal_noise"]


def normal_noise(V, F, sigma, seed=0):
    """Vertices moved along their normals by Gaussian noise of ``sigma`` mean edge lengths.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int
    sigma : float
        Standard deviation of the displacement, in mean edge lengths of the mesh.
    seed : int

    Returns
    -------
    (n, 3) float64
        New positions (``V`` is not changed). Vertices without faces stay where they are.

    Examples
    --------
    >>> from meshlab_holefill.evaluation.analytic import analytic_mesh
    >>> V, F = analytic_mesh("sphere")
    >>> W = normal_noise(V, F, 0.2)
    >>> rms = np.sqrt(((W - V) ** 2).sum(axis=1).mean())
    >>> round(float(rms / edge_lengths(V, F).mean()), 1)  # 0.2 mean edge lengths
    0.2
    """
    V = np.asarray(V, np.float64)
    mean_edge = float(edge_lengths(V, F).mean()) if len(F) else 0.0
    offsets = sigma * mean_edge * np.random.default_rng(seed).standard_normal(len(V))
    return V + vertex_normals(V, F) * offsets[:, None]
