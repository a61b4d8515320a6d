"""scripts/demo.py, the README's first Quick start command: every filter closes the bunny scan's 5 holes."""
import importlib.util
import os

import pymeshlab

import meshlab_holefill

DEMO = os.path.join(os.path.dirname(__file__), "..", "scripts", "demo.py")


def test_demo_fills_the_bunny_scan_with_every_filter(tmp_path, capsys):
    spec = importlib.util.spec_from_file_location("demo", DEMO)
    demo = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(demo)
    demo.main(str(tmp_path))
    names = meshlab_holefill.filter_list() + ["meshing_close_holes"]
    rows = {line.split("|")[1].strip(): [c.strip() for c in line.split("|")[2:-1]]
            for line in (tmp_path / "summary.md").read_text().splitlines() if line.startswith("| meshing")}
    assert sorted(rows) == sorted(names)
    for name, cells in rows.items():
        closed, left = cells[0], cells[5]
        assert closed == "5 / 5" and left == "0", (name, cells)
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(tmp_path / f"{name}.ply"))
        assert ms.current_mesh().face_number() > 9999
        topo = ms.get_topological_measures()  # the written file really is closed
        assert topo["boundary_edges"] == 0 and topo["non_two_manifold_edges"] == 0, name
    assert float(rows["meshing_close_holes_lssvm_poisson"][7]) > 0  # Sec. 3.1 split some border edges
