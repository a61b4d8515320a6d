"""Eq. 14 solved exactly (L-BFGS-B inside the arc bounds, and unbounded) against the DE result, per mille of the diagonal.

Shows whether the DE's convergence limits the prediction on large holes: it does not when
d_exact ~ d_de (the arcs and the objective, not the optimiser, set the error).
"""
import glob, json, os, sys, numpy as np
from scipy.optimize import minimize
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from stages import holes_of, pm
from meshlab_holefill.core.holes import hole_context
from meshlab_holefill.evaluation.metrics import point_to_surface_distances, compact_mesh
from meshlab_holefill.algorithms.xie_zou2013 import differential_evolution as de, _algorithm2 as A2
from meshlab_holefill.algorithms.xie_zou2013 import prediction as PR, sections as S


def section_data(V, Fc, loop):
    """P1, P2, TV1, TV2, Nv and m of the section planes HPDE's first attempt uses."""
    ctx = hole_context(V, Fc, loop, rings=de.RINGS)
    edge_len, base, normals, seg = A2.boundary_step(ctx, 90.0)
    split = seg["split"] if A2.attempt_order(base, normals, seg, np.radians(12.0))[0][0] else None
    tangent, inward = S.boundary_frames(base.points, normals)
    pairs, _ = S.correspondences(base.points, tangent, inward, split, np.radians(12.0))
    a, b = pairs[:, 0], pairs[:, 1]
    Nv, _ = S.section_normals(base.points, pairs, normals[a] + normals[b])
    W = S.border_third_vertices(ctx)
    _, TV_a = S.ring_intersections(ctx.points, base.edge[a], base.points[a], Nv, W[base.edge[a]])
    _, TV_b = S.ring_intersections(ctx.points, base.edge[b], base.points[b], Nv, W[base.edge[b]])
    P1, P2, TV1, TV2 = base.points[a], base.points[b], TV_a, -TV_b
    ok = PR.forward_tangents(P1, P2, TV1, TV2)
    P1, P2, TV1, TV2, Nv = P1[ok], P2[ok], TV1[ok], TV2[ok], Nv[ok]
    m, _ = PR.prediction_counts(np.linalg.norm(P2 - P1, axis=1), edge_len)
    return P1, P2, TV1, TV2, Nv, m, edge_len


def exact_minimum(prob, bounded=True):
    """Per plane, the minimiser of Eq. 14 from the Eq. 16 start (inside [L_i2, U_i2] when bounded)."""
    Y = prob.y_init.copy()
    for i in range(len(prob.m)):
        sub = PR.subset(prob, np.array([i]))
        f = lambda y: float(PR.angle_variation(sub, y.reshape(1, 1, -1))[0, 0])  # noqa: E731
        r = minimize(f, sub.y_init[0].copy(), method="L-BFGS-B" if bounded else "BFGS",
                     bounds=list(zip(sub.lower[0], sub.upper[0])) if bounded else None, options=dict(maxiter=2000))
        Y[i, :int(sub.m[0])] = r.x
    return Y


if __name__ == "__main__":
    for path in sorted(glob.glob(os.environ.get("HPDE_CASES", "/tmp/hpde/cases") + "/*.npz")):
        if len(sys.argv) > 1 and not any(s in path for s in sys.argv[1:]):
            continue
        for name, V, Fc, G, loop, diag in holes_of(path):
            P1, P2, TV1, TV2, Nv, m, _ = section_data(V, Fc, loop)
            prob, frames = PR.section_problems(P1, P2, TV1, TV2, Nv, m)
            Y, _, _ = PR.predict_y(prob, **A2.PredictionOptions().de_options())
            gtV, gtF = compact_mesh(V, G)
            d = lambda Yv: pm(point_to_surface_distances(PR.predicted_points(P1, frames, prob, Yv)[0], gtV, gtF), diag)  # noqa: E731
            print(json.dumps(dict(hole=name, d_init=d(prob.y_init), d_de=d(Y), d_exact=d(exact_minimum(prob)),
                                  d_exact_unbounded=d(exact_minimum(prob, False)))), flush=True)
