"""A hole next to another part: a unit sphere without its cap and a small closed ball where the cap was.

A patch that follows the sphere passes through the ball, which lies beyond the rings a filter
sees around its hole; the pipeline then fills the hole once more with the faces near that patch
as obstacles. For 8 placements of the ball (centre height, radius) and two cap heights, each
filter's status on the cap's hole is printed (``c`` closed, ``f`` failed), with the obstacle faces
the second fill saw and the reason of a failure, then the holes each filter closed.

    .venv/bin/python scripts/part_under_cap.py [--filters min_angle_bilateral,curve_unfolding,...]
"""
from __future__ import annotations

import argparse
import time

import numpy as np
import pymeshlab

from meshlab_holefill.array_api import fill_holes

PLACEMENTS = [(0.93, 0.04), (0.9, 0.06), (0.95, 0.03), (0.88, 0.05)]  # (centre height, radius) of the ball
CAPS = (0.8, 0.7)  # faces reaching above this height are removed
ALL = "min_angle_bilateral,curve_unfolding,lssvm_poisson,differential_evolution"


def generated(name, **kw):
    ms = pymeshlab.MeshSet()
    getattr(ms, name)(**kw)
    m = ms.current_mesh()
    return np.asarray(m.vertex_matrix(), np.float64), np.asarray(m.face_matrix(), np.int64)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--filters", default=ALL)
    args = ap.parse_args(argv)
    filters = args.filters.split(",")
    sphere_V, sphere_F = generated("create_sphere", radius=1.0, subdiv=4)
    closed = dict.fromkeys(filters, 0)
    for height, radius in PLACEMENTS:
        ball_V, ball_F = generated("create_sphere", radius=radius, subdiv=2)
        for cap in CAPS:
            V = np.concatenate([sphere_V, ball_V + [0.1, 0.0, height]])
            F = np.concatenate([sphere_F[sphere_V[sphere_F, 2].max(axis=1) < cap], ball_F + len(sphere_V)])
            row = []
            for name in filters:
                t = time.perf_counter()
                _, _, result = fill_holes(V, F, name, workers=1)
                hole = max(result["holes"], key=lambda h: h["boundary_edges"])
                closed[name] += hole["status"] == "closed"
                row.append(f"{name}: {hole['status'][0]} {time.perf_counter() - t:.2f} s obstacles "
                           f"{hole.get('obstacle_faces', '-')} {hole.get('reason') or ''}".rstrip())
            print(f"ball at {height}, radius {radius}, cap above {cap}:", "; ".join(row), flush=True)
    print("closed:", ", ".join(f"{name} {count}/{len(PLACEMENTS) * len(CAPS)}" for name, count in closed.items()))


if __name__ == "__main__":
    main()
