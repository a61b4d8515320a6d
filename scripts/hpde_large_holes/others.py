import os
import sys, glob, numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from stages import holes_of
from meshlab_holefill.core.holes import hole_context
from meshlab_holefill.evaluation.metrics import compact_mesh, hausdorff_one_way
from meshlab_holefill.algorithms.brunton2009 import curve_unfolding as cu
out = {}
for path in sorted(glob.glob(os.environ.get("HPDE_CASES", "/tmp/hpde/cases") + "/*.npz")):
    for name, V, Fc, G, loop, diag in holes_of(path):
        gtV, gtF = compact_mesh(V, G)
        ctx = hole_context(V, Fc, loop, rings=cu.RINGS)
        try:
            p = cu.fill(ctx)
            cV, cF = compact_mesh(np.concatenate([ctx.points, p.vertices]), p.faces)
            d = round(1000 * hausdorff_one_way(cV, cF, gtV, gtF)["mean"] / diag, 3)
        except Exception:
            d = None
        # flat: loop only (no interior) approximated by a fan to centroid
        out[name] = d
        print(name, d, flush=True)

print("MEAN", np.mean([v for v in out.values() if v is not None]))
