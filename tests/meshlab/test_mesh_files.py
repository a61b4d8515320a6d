"""meshlab.mesh_files: arrays to and from pymeshlab, and MeshLab's point-to-surface distance."""
import os
import subprocess
import sys

import numpy as np
import pytest

from meshlab_holefill.meshlab.mesh_files import (is_mesh, load_mesh, mesh_arrays, meshset_from_arrays,
                                                 point_to_surface_distances)

from conftest import sample


def test_arrays_round_trip_through_a_meshset_and_a_file(tmp_path):
    V, F = load_mesh(sample("bone.ply"))
    assert V.dtype == np.float64 and F.dtype == np.int64 and V.shape[1] == F.shape[1] == 3
    ms = meshset_from_arrays(V, F, "bone")
    assert ms.current_mesh().label() == "bone" and is_mesh(ms) and is_mesh(ms.current_mesh())
    for source in (ms, ms.current_mesh()):
        V1, F1 = mesh_arrays(source)
        assert np.array_equal(V1, V) and np.array_equal(F1, F)
    ms.save_current_mesh(str(tmp_path / "bone.ply"))
    V2, F2 = load_mesh(tmp_path / "bone.ply")
    assert np.allclose(V2, V, atol=1e-6) and np.array_equal(F2, F)
    assert not is_mesh((V, F))
    with pytest.raises(TypeError, match="pymeshlab.Mesh"):
        mesh_arrays((V, F))


def test_point_to_surface_distances_of_a_unit_square():
    V = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    X = np.array([[0.5, 0.5, 2.0], [2.0, 0.5, 0.0], [-3.0, -4.0, 0.0]])
    assert point_to_surface_distances(X, V, F) == pytest.approx([2.0, 1.0, 5.0], abs=1e-6)
    assert point_to_surface_distances(np.empty((0, 3)), V, F).shape == (0,)


def test_a_cad_tessellation_keeps_the_faces_asked_for_and_refuses_a_count_out_of_range():
    from meshlab_holefill.meshlab.mesh_files import cad_tessellation, generated_mesh, remeshed

    V, F = remeshed(*generated_mesh("create_cube", size=1.0), 0.1)
    V2, F2 = cad_tessellation(V, F, 200)
    assert len(F2) == 200 and np.all(np.abs(V2) <= 0.501)  # still the unit cube (to the remeshing's accuracy)
    for faces in (0, len(F)):
        with pytest.raises(ValueError, match="faces must be between 1 and"):
            cad_tessellation(V, F, faces)


# The union of a box and a cylinder (the arrays' file) remeshed, in a new process: by MeshLab in
# that process ("meshlab"), or by remeshed ("remeshed"); the vertex count is printed.
_REMESH_IN_A_PROCESS = """
import sys, numpy as np, pymeshlab
from meshlab_holefill.meshlab.mesh_files import meshset_from_arrays, mesh_arrays, remeshed
given = np.load(sys.argv[1])
if sys.argv[2] == "meshlab":
    ms = meshset_from_arrays(given["V"], given["F"])
    ms.meshing_surface_subdivision_midpoint(iterations=8, threshold=pymeshlab.PureValue(0.2))
    ms.meshing_isotropic_explicit_remeshing(iterations=10, targetlen=pymeshlab.PureValue(0.1), featuredeg=30.0,
                                            maxsurfdist=pymeshlab.PureValue(0.005))
    V = mesh_arrays(ms)[0]
else:
    V = remeshed(given["V"], given["F"], 0.1)[0]
print(len(V))
"""


def test_remeshing_does_not_depend_on_the_memory_the_calling_process_leaves(tmp_path):
    from meshlab_holefill.evaluation.creased import _box, _cylinder
    from meshlab_holefill.meshlab.mesh_files import boolean_mesh, remeshed

    V, F = boolean_mesh("union", _box(), _cylinder(0.3, 1.3))
    np.savez(tmp_path / "union.npz", V=V, F=F)

    def vertices(how, pattern):
        """Vertex count of the remeshing in a process whose new memory glibc fills with ``pattern``."""
        run = subprocess.run([sys.executable, "-c", _REMESH_IN_A_PROCESS, str(tmp_path / "union.npz"), how],
                             capture_output=True, check=True, env={**os.environ, "MALLOC_PERTURB_": pattern})
        return int(run.stdout)

    # MeshLab's remeshing reads memory it has not set, so on some machines the pattern changes its mesh (on one
    # machine 739 vertices instead of 764 under 255); whether it does depends on the machine's allocator, so only the
    # fixed remeshing's side is asserted.
    clean = vertices("meshlab", "0")
    assert vertices("remeshed", "255") == vertices("remeshed", "90") == clean == len(remeshed(V, F, 0.1)[0])
