"""Per section plane: arc start angles vs the true end slopes, and the true profile height vs the arcs' (over the chord).

Usage: profiles.py CASE_SUBSTRING [HOLE_SUFFIX]. Columns: chord length in EdgeLen, start angles of
L_arc / U_arc (degrees), slope of the removed surface at both ends along the chord, the highest
point of the removed surface over the chord and of each arc, as fractions of the chord length.
"""
import glob, os, sys, numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from stages import holes_of, line_hits
from optimum import section_data
from meshlab_holefill.evaluation.metrics import compact_mesh
from meshlab_holefill.algorithms.xie_zou2013 import prediction as PR

for path in sorted(glob.glob(os.environ.get("HPDE_CASES", "/tmp/hpde/cases") + "/*.npz")):
    if not any(s in path for s in sys.argv[1:2]):
        continue
    for name, V, Fc, G, loop, diag in holes_of(path):
        if len(sys.argv) > 2 and not name.endswith(sys.argv[2]):
            continue
        P1, P2, TV1, TV2, Nv, m, el = section_data(V, Fc, loop)
        prob, frames = PR.section_problems(P1, P2, TV1, TV2, Nv, m)
        gtV, gtF = compact_mesh(V, G)
        print(name, "planes", len(P1))
        for i in range(0, len(P1), max(1, len(P1) // 25)):
            L = prob.length[i]
            xs = np.linspace(0.02, 0.98, 25) * L
            t = line_hits(P1[i] + xs[:, None] * frames[i, 0], np.repeat(frames[i, 1][None], 25, 0), gtV, gtF)
            arc = lambda th: PR.arc_height(th[i:i + 1], prob.length[i:i + 1], xs[None])[0].max() / L  # noqa: E731
            s0, s1 = (np.degrees(np.arctan2(t[0], xs[0])), np.degrees(np.arctan2(t[-1], L - xs[-1])))
            print(f"{i:3d} L/EdgeLen {L / el:5.1f}  arcs {np.degrees(prob.theta_lower[i]):5.1f} "
                  f"{np.degrees(prob.theta_upper[i]):5.1f}  true slopes {s0:5.1f} {s1:5.1f}  height/L true "
                  f"{np.nanmax(t) / L if np.isfinite(t).any() else np.nan:4.2f} L_arc {arc(prob.theta_lower):4.2f} "
                  f"U_arc {arc(prob.theta_upper):4.2f}")
