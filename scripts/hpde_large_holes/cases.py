"""Build the HPDE large-hole cases: (name, V, F_cut, holes, diag, analytic) saved as npz."""
import os, sys, numpy as np, pymeshlab
from meshlab_holefill.evaluation.analytic import ANALYTIC_SURFACES, analytic_mesh
from meshlab_holefill.evaluation.cut_holes import cut_holes
from meshlab_holefill.meshlab.mesh_files import load_mesh, mesh_arrays
SAMPLES = os.path.join(os.path.dirname(pymeshlab.__file__), "tests", "sample_meshes")
OUT = os.environ.get("HPDE_CASES", "/tmp/hpde/cases") + ""
os.makedirs(OUT, exist_ok=True)

def base(name):
    if name in ANALYTIC_SURFACES:
        return analytic_mesh(name)
    if name == "bunny_sub":
        ms = pymeshlab.MeshSet(); ms.load_new_mesh(os.path.join(SAMPLES, "bunny.obj"))
        ms.meshing_surface_subdivision_loop(iterations=1, threshold=pymeshlab.PercentageValue(0))
        while ms.current_mesh().face_number() < 150000:
            ms.meshing_surface_subdivision_loop(iterations=1, threshold=pymeshlab.PercentageValue(0))
        return mesh_arrays(ms)
    return load_mesh(os.path.join(SAMPLES, name))

for name in sys.argv[1:]:
    V, F = base(name)
    for seed in (0, 1):
        sizes = ["large", "irregular"]
        shapes = ["compact", "irregular"] if seed == 0 else ["irregular", "compact"]
        try:
            Fc, holes = cut_holes(V, F, sizes=sizes, shapes=shapes, seed=seed, strict=False)
        except Exception as e:
            print(name, seed, "cut failed", e); continue
        rem = np.zeros(len(F), np.int64) - 1
        for h, hole in enumerate(holes):
            rem[hole.face_indices] = h
        np.savez(f"{OUT}/{name}_{seed}.npz", V=V, F=F, hole_of_face=rem,
                 edges=np.array([h.boundary_edges for h in holes]))
        print(name, seed, len(F), [h.boundary_edges for h in holes], flush=True)
