"""The analytic surfaces: their meshes sample them, their distance and area are the exact ones."""
import numpy as np
import pytest

from meshlab_holefill.core.holes import boundary_loops
from meshlab_holefill.evaluation.analytic import ANALYTIC_SURFACES, analytic_area, analytic_distance, analytic_mesh


@pytest.mark.parametrize("name, faces", [("sphere", 20480), ("torus", 36864)])
def test_the_mesh_is_closed_and_samples_the_surface_whose_area_it_approaches(name, faces):
    V, F = analytic_mesh(name)
    assert len(F) == faces and len(boundary_loops(F)) == 0
    assert np.abs(analytic_distance(name)(V)).max() < 1e-6
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
    assert area == pytest.approx(analytic_area(name), rel=2e-3)  # inscribed: slightly less


def test_the_distance_is_signed_and_exact_off_the_surface():
    sphere, torus = analytic_distance("sphere"), analytic_distance("torus")
    np.testing.assert_allclose(sphere(np.array([[0.0, 0.0, 2.0], [0.5, 0.0, 0.0]])), [1.0, -0.5])
    np.testing.assert_allclose(torus(np.array([[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 0.0]])), [-0.4, 0.6, 0.6])


@pytest.mark.parametrize("call", [analytic_mesh, analytic_distance, analytic_area])
def test_an_unknown_surface_is_refused_by_name(call):
    assert ANALYTIC_SURFACES == ("sphere", "torus")
    with pytest.raises(ValueError, match="unknown analytic surface 'cube'"):
        call("cube")
