"""Stage-by-stage error of HPDE on large cut holes (per mille of the bbox diagonal)."""
import glob, sys, os, json, time, numpy as np
from meshlab_holefill.core.holes import boundary_loops, hole_context
from meshlab_holefill.evaluation.metrics import point_to_surface_distances, hausdorff_one_way, compact_mesh
from meshlab_holefill.algorithms.xie_zou2013 import differential_evolution as de, _algorithm2 as A2
from meshlab_holefill.algorithms.xie_zou2013 import prediction as PR, sections as S

def holes_of(path):
    d = np.load(path)
    V, F, hof = d["V"], d["F"], d["hole_of_face"]
    Fc = F[hof < 0]
    diag = float(np.linalg.norm(V.max(0) - V.min(0)))
    loops = boundary_loops(Fc)
    for h in range(hof.max() + 1):
        G = F[hof == h]
        gv = set(np.unique(G).tolist())
        loop = max(loops, key=lambda lp: len(gv.intersection(np.asarray(lp.vertices).tolist())))
        yield os.path.basename(path)[:-4] + f"#{h}", V, Fc, G, loop, diag

def line_hits(O, D, V, G):
    """t of the nearest hit of lines O + t D with triangles V[G] (nan when none)."""
    A, B, C = V[G[:, 0]], V[G[:, 1]], V[G[:, 2]]
    e1, e2 = B - A, C - A
    out = np.full(len(O), np.nan)
    for s in range(0, len(O), 256):
        o, d = O[s:s+256, None], D[s:s+256, None]
        p = np.cross(d, e2[None]); det = np.einsum("qtd,td->qt", p, e1)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1 / det; tv = o - A[None]
            u = np.einsum("qtd,qtd->qt", tv, p) * inv
            q = np.cross(tv, e1[None]); v = np.einsum("qtd,qtd->qt", d * np.ones_like(tv), q) * inv
            t = np.einsum("qtd,td->qt", q, e2) * inv
        ok = (u >= -1e-9) & (v >= -1e-9) & (u + v <= 1 + 1e-9) & np.isfinite(t)
        t = np.where(ok, t, np.inf)
        i = np.argmin(np.abs(t), axis=1)
        tt = t[np.arange(len(t)), i]
        out[s:s+256] = np.where(np.isfinite(tt), tt, np.nan)
    return out

def pm(x, diag):
    x = np.asarray(x); x = x[np.isfinite(x)]
    return round(1000 * float(np.mean(np.abs(x))) / diag, 3) if len(x) else float("nan")

def analyse(name, V, Fc, G, loop, diag, params):
    ctx = hole_context(V, Fc, loop, rings=de.RINGS)
    k = ctx.size
    edge_len, base, normals, seg = A2.boundary_step(ctx, 90.0)
    attempts = A2.attempt_order(base, normals, seg, np.radians(12.0))
    segmented = attempts[0][0]
    split = seg["split"] if segmented else None
    P = ctx.points
    tangent, inward = S.boundary_frames(base.points, normals)
    pairs, cinfo = S.correspondences(base.points, tangent, inward, split, np.radians(12.0))
    a, b = pairs[:, 0], pairs[:, 1]
    Nv, flat = S.section_normals(base.points, pairs, normals[a] + normals[b])
    W = S.border_third_vertices(ctx)
    AP_a, TV_a = S.ring_intersections(P, base.edge[a], base.points[a], Nv, W[base.edge[a]])
    AP_b, TV_b = S.ring_intersections(P, base.edge[b], base.points[b], Nv, W[base.edge[b]])
    P1, P2, TV1, TV2 = base.points[a], base.points[b], TV_a, -TV_b
    ok = PR.forward_tangents(P1, P2, TV1, TV2)
    P1, P2, TV1, TV2, Nv = P1[ok], P2[ok], TV1[ok], TV2[ok], Nv[ok]
    m, M = PR.prediction_counts(np.linalg.norm(P2 - P1, axis=1), edge_len)
    prob, frames = PR.section_problems(P1, P2, TV1, TV2, Nv, m)
    Y, f, g = PR.predict_y(prob, **A2.PredictionOptions().de_options())
    valid = np.arange(prob.x.shape[1])[None, :] < prob.m[:, None]
    pl, col = np.nonzero(valid)
    ex, ey = frames[pl, 0], frames[pl, 1]
    base3 = P1[pl] + prob.x[pl, col, None] * ex
    def pts(y):
        return base3 + y[pl, col, None] * ey
    gtV, gtF = compact_mesh(V, G)
    dist = lambda X: point_to_surface_distances(X, gtV, gtF)
    t_true = line_hits(base3, ey, gtV, gtF)
    lo, up = prob.lower[pl, col], prob.upper[pl, col]
    yv = Y[pl, col]
    inside = (t_true >= lo - 1e-12) & (t_true <= up + 1e-12)
    width = up - lo
    r = dict(hole=name, k=k, n=len(base), segmented=bool(segmented), dihedral=None if seg["dihedral"] is None else round(float(np.degrees(seg["dihedral"])), 1),
             pairs=len(pairs), dropped=int((~ok).sum()), predicted=int(len(pl)),
             d_lower=pm(dist(pts(prob.lower)), diag), d_upper=pm(dist(pts(prob.upper)), diag),
             d_init=pm(dist(pts(prob.y_init)), diag), d_de=pm(dist(pts(Y)), diag),
             d_chord=pm(dist(pts(np.zeros_like(Y))), diag),
             y_err_de=pm(yv - t_true, diag), y_err_mid=pm(0.5 * (lo + up) - t_true, diag), width=pm(width, diag),
             gt_in_bounds=round(float(np.mean(inside[np.isfinite(t_true)])), 2), gt_hit=round(float(np.mean(np.isfinite(t_true))), 2),
             y_err_clip=pm(np.clip(t_true, lo, up) - t_true, diag))
    # the full fill
    rec = {}
    t0 = time.perf_counter()
    patch = de.fill(ctx, record=rec, **params)
    r["sec"] = round(time.perf_counter() - t0, 1)
    pV = np.concatenate([ctx.points, patch.vertices])
    cV, cF = compact_mesh(pV, patch.faces)
    r["d_smoothed"] = pm(dist(rec["smoothed_points"]), diag) if len(rec.get("smoothed_points", [])) else None
    r["d_final"] = round(1000 * hausdorff_one_way(cV, cF, gtV, gtF)["mean"] / diag, 3)
    r["layout"] = patch.info.get("layout"); r["kept"] = patch.info.get("kept_share")
    return r

if __name__ == "__main__":
    params = json.loads(os.environ.get("HPDE_PARAMS", "{}"))
    rows = []
    for path in sorted(glob.glob(os.environ.get("HPDE_CASES", "/tmp/hpde/cases") + "/*.npz")):
        if len(sys.argv) > 1 and not any(s in path for s in sys.argv[1:]):
            continue
        for item in holes_of(path):
            try:
                r = analyse(*item, params)
            except Exception as e:
                import traceback; traceback.print_exc()
                r = dict(hole=item[0], error=str(e))
            print(json.dumps(r), flush=True)
            rows.append(r)
    fin = [r["d_final"] for r in rows if "d_final" in r]
    print("MEAN final", np.mean(fin), "n", len(fin))
