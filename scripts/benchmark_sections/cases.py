"""The suite's meshes: pymeshlab's samples, analytic, CAD-like, real-size and noisy cases."""
from __future__ import annotations

import os

import numpy as np
import pymeshlab

from meshlab_holefill.evaluation.analytic import ANALYTIC_SURFACES, analytic_area, analytic_distance, analytic_mesh
from meshlab_holefill.evaluation.comparison import MeshCase
from meshlab_holefill.evaluation.creased import CREASED_CASES, creased_case
from meshlab_holefill.evaluation.cut_holes import cut_holes
from meshlab_holefill.evaluation.noisy import normal_noise
from meshlab_holefill.evaluation.virtual_scan import virtual_scan_case
from meshlab_holefill.meshlab.mesh_files import load_mesh, mesh_arrays


SAMPLES = os.path.join(os.path.dirname(pymeshlab.__file__), "tests", "sample_meshes")
CLOSED = ["bunny.obj", "bone.ply", "cow.obj", "airplane.obj", "sphere", "torus"]
NATURAL = ["bunny10k_textured.obj", "face000.ply"]
# CAD-like meshes with holes a crease runs through, and interpenetrating parts (evaluation.creased)
CREASED = list(CREASED_CASES)
# A scan-sized mesh with holes of 200-375 boundary edges (ground truth kept): the bunny Loop-subdivided once
REAL_SIZE = ["bunny_212k"]
# A scan-like mesh: noise along the normals (evaluation.noisy), holes with jagged borders
NOISY = ["cow_noisy"]
NOISE_SIGMA = 0.3  # mean edge lengths
CASES = CLOSED + NATURAL + CREASED + REAL_SIZE + NOISY
REAL_SIZE_HOLES = ("irregular", "large", "irregular")  # targets 250, 150, 250 boundary edges
SCAN_NOISE = 0.15  # mean edge lengths: the noisy one of the virtual scans

def load_case(name):
    """The suite's meshes as MeshCase (analytic distance functions for the sphere and torus)."""
    analytic = area = None
    if name in CREASED_CASES:
        return creased_case(name)
    if name == "bunny_212k":
        return real_size_case()
    if name == "cow_noisy":
        return noisy_case()
    if name in ANALYTIC_SURFACES:
        V, F = analytic_mesh(name)
        analytic, area = analytic_distance(name), analytic_area(name)
    else:
        V, F = load_mesh(os.path.join(SAMPLES, "rangemaps", name) if name == "face000.ply" else os.path.join(SAMPLES, name))
    return MeshCase(name, V, F, analytic=analytic, surface_area=area)


def real_size_case(seed=0):
    """The bunny Loop-subdivided once (about 212k faces) with three holes of 150-375 boundary edges.

    The holes are cut once (``cut_holes``, irregular and compact shapes) and handed to the
    comparison as given holes, so every filler fills the same large holes of a scan-sized mesh.
    """
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(SAMPLES, "bunny.obj"))
    ms.meshing_surface_subdivision_loop(iterations=1, threshold=pymeshlab.PercentageValue(0))
    V, F = mesh_arrays(ms)
    _, holes = cut_holes(V, F, sizes=REAL_SIZE_HOLES, seed=seed)
    removed = np.zeros(len(F), bool)
    removed[np.concatenate([h.face_indices for h in holes])] = True
    return MeshCase("bunny_212k", V, F, removed=removed, given_class="real-size")


def noisy_case(seed=0):
    """cow.obj Loop-subdivided twice (about 93k faces), moved by :func:`normal_noise` (``NOISE_SIGMA``), four holes cut.

    The holes (about 20, 60, 150 and 250 boundary edges) are cut once, after the noise, and handed
    to the comparison as given holes of class "noisy": the ground truth is the noisy surface.
    """
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(SAMPLES, "cow.obj"))
    ms.meshing_surface_subdivision_loop(iterations=2, threshold=pymeshlab.PercentageValue(0))
    V, F = mesh_arrays(ms)
    V = normal_noise(V, F, NOISE_SIGMA, seed=seed)
    _, holes = cut_holes(V, F, sizes=("small", "medium", "large", "irregular"), seed=seed, strict=False)
    removed = np.zeros(len(F), bool)
    removed[np.concatenate([h.face_indices for h in holes])] = True
    return MeshCase("cow_noisy", V, F, removed=removed, given_class="noisy")


def _subdivided(sample, iterations):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(os.path.join(SAMPLES, sample))
    ms.meshing_surface_subdivision_loop(iterations=iterations, threshold=pymeshlab.PercentageValue(0))
    return mesh_arrays(ms)


def scan_cases(seed=1):
    """Two virtual range scans (:func:`virtual_scan_case`) from a direction drawn with ``seed``.

    The bunny Loop-subdivided once (about 212k faces), clean, and cow.obj Loop-subdivided twice
    (about 93k faces) with scanner noise (``SCAN_NOISE``): their holes are what the scanner did
    not see inside the seen sheet (occlusion shadows, grazing strips; often pinched).
    """
    direction = np.random.default_rng(seed).normal(size=3)
    return [virtual_scan_case("bunny_scan", *_subdivided("bunny.obj", 1), direction),
            virtual_scan_case("cow_scan_noisy", *_subdivided("cow.obj", 2), direction, noise=SCAN_NOISE, seed=seed)]
