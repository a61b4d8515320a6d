"""Regenerate the MeshLab 2020.09 tables in meshlab_holefill/data/ from the real meshlabserver.

Needs the Debian packages ``meshlab`` (2020.09), ``xvfb`` and ``qtbase5-dev`` (for the Qt
headers of the shim) and a C++ compiler. ``meshlabserver -d FILE`` dumps every filter with its
parameters, but lists each parameter by its label ("Max size to be closed"), not by the name
a script uses ("MaxHoleSize"). ``meshlab_dump_shim.cpp``, preloaded, makes the dump print each
parameter as MeshLab writes it in a script instead (name, type and default value).

Writes (in meshlab_holefill/meshlab/mlx/)
    data/meshlab_2020_09_filters.tsv   every 2020.09 filter, its parameters in order, their types
                                       and defaults (defaults of an empty document: mesh-dependent
                                       ones are those of no mesh)
    data/meshlab_2020_09_names.tsv     each 2020.09 filter -> the pymeshlab python name of its
                                       current counterpart, with the parameters its old name
                                       implies and renamed parameters; or none, with the reason

Usage: .venv/bin/python scripts/meshlab_2020_09_tables.py
"""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "meshlab_holefill", "meshlab", "mlx", "data")

# 2020.09 filters that current MeshLab has under a name the rules of mlx_names do not find:
# name -> (python name, implied parameters, renamed parameters {2020 name: python name}).
RENAMED = {
    "Remove T-Vertices by Edge Flip": ("meshing_remove_t_vertices", {"method": 1}, {}),
    "Remove T-Vertices by Edge Collapse": ("meshing_remove_t_vertices", {"method": 0}, {}),
    "Repair non Manifold Edges by removing faces": ("meshing_repair_non_manifold_edges", {"method": 0}, {}),
    "Repair non Manifold Edges by splitting vertices": ("meshing_repair_non_manifold_edges", {"method": 1}, {}),
    "Define New Per Vertex Attribute": ("compute_new_custom_scalar_attribute_per_vertex", {}, {}),
    "Define New Per Face Attribute": ("compute_new_custom_scalar_attribute_per_face", {}, {}),
    "Smooths normals on a point sets": ("apply_normal_point_cloud_smoothing", {}, {}),
    "Simplfication: Edge Collapse for Marching Cube meshes":
        ("meshing_decimation_edge_collapse_for_marching_cube_meshes", {}, {}),
    "Select Visible Points": ("compute_selection_of_visible_convex_hull_per_vertex", {}, {}),
    "Select Folded Faces": ("compute_selection_bad_faces", {"usear": False, "usenf": False, "select_folded_faces": True},
                            {"AngleThreshold": "folded_faces_angle_threshold"}),
}
# 2020.09 filters without a counterpart in current MeshLab.
REMOVED = {
    "Compact faces": "removed in MeshLab 2022 (meshes are kept compact)",
    "Compact vertices": "removed in MeshLab 2022 (meshes are kept compact)",
    "CSG Operation": "removed in MeshLab 2022; the Boolean filters (generate_boolean_union, ...) replace it",
    "Change Visibility of layer(s)": "removed in MeshLab 2022 (layer visibility is no filter in pymeshlab)",
    "Change the current layer": "removed in MeshLab 2022 (use MeshSet.set_current_mesh)",
    "Delaunay Triangulation": "removed in MeshLab 2022",
    "Vertex Color Noise": "removed in MeshLab 2022 (apply_color_noising_per_vertex and "
                          "compute_color_perlin_noise_per_vertex take other parameters)",
    "Directional Geom. Preserv.": "removed in MeshLab 2022 (apply_coord_directional_preservation "
                                  "takes other parameters)",
    "Cross Field Creation": "removed in MeshLab 2022",
    "Global registration": "removed in MeshLab 2022 with its Super4PCS plugin",
}


def dump_2020_09(workdir):
    """Text of ``meshlabserver -d`` with every parameter written as a script ``<Param>``."""
    shim = os.path.join(workdir, "shim.so")
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "Qt5Xml"], check=True, capture_output=True,
                           text=True).stdout.split()
    subprocess.run(["g++", "-shared", "-fPIC", "-O2", "-o", shim, os.path.join(HERE, "meshlab_dump_shim.cpp")]
                   + flags + ["-ldl"], check=True)
    out = os.path.join(workdir, "dump.txt")
    version = subprocess.run(["xvfb-run", "-a", "meshlabserver", "-h"], capture_output=True, text=True).stdout
    subprocess.run(["xvfb-run", "-a", "meshlabserver", "-d", out], check=True, capture_output=True,
                   env=dict(os.environ, LD_PRELOAD=shim))
    with open(out, encoding="utf-8", errors="replace") as f:
        return f.read(), re.search(r"MeshLabServer version: (\S+)", version).group(1)


def parse_dump(text):
    """List of (filter name, [attribute dict of each <Param>])."""
    from xml.dom.minidom import parseString

    filters = []
    for section in re.split(r"\\section f\d+ ", text)[1:]:
        name = section.split("\n", 1)[0].strip()
        params = [dict(parseString(xml).documentElement.attributes.items())
                  for xml in re.findall(r"<TD> (<Param [^>]*/>) </TD>", section)]
        filters.append((name, params))
    return filters


def counterpart(name, params):
    """(python name, implied, renamed, note) of a 2020.09 filter in current pymeshlab."""
    from meshlab_holefill.meshlab.mlx import names as mlx_names

    if name in REMOVED:
        return None, {}, {}, REMOVED[name]
    if name in RENAMED:
        return (*RENAMED[name], "")
    understood = mlx_names.resolve_filter(name)
    if understood is None or understood.ours:
        raise SystemExit(f"no current counterpart known for the 2020.09 filter {name!r}: add it to RENAMED or REMOVED")
    return understood.python_name, {}, {}, ""


def main():
    sys.path.insert(0, os.path.join(HERE, ".."))
    with tempfile.TemporaryDirectory() as workdir:
        text, version = dump_2020_09(workdir)
    filters = parse_dump(text)
    with open(os.path.join(DATA, "meshlab_2020_09_filters.tsv"), "w", encoding="utf-8") as f:
        f.write(f"# MeshLab {version} filters and parameters (meshlabserver -d, scripts/meshlab_2020_09_tables.py)\n")
        f.write("filter\tparameter\ttype\tdefault\n")
        for name, params in filters:
            if not params:
                f.write(f"{name}\t\t\t\n")
            for p in params:
                default = {k: v for k, v in p.items() if k not in ("name", "type")}
                if p["type"] in ("RichSaveFile", "RichOpenFile") and os.path.isabs(default.get("value", "")):
                    # MeshLab's file defaults are names in the directory it runs in: keep the name only
                    default["value"] = os.path.basename(default["value"])
                f.write(f"{name}\t{p['name']}\t{p['type']}\t{json.dumps(default, sort_keys=True)}\n")
    with open(os.path.join(DATA, "meshlab_2020_09_names.tsv"), "w", encoding="utf-8") as f:
        f.write(f"# MeshLab {version} filter name -> pymeshlab python name (scripts/meshlab_2020_09_tables.py)\n")
        f.write("filter\tpython_name\timplied\trenamed\tnote\n")
        for name, params in sorted(filters):
            python_name, implied, renamed, note = counterpart(name, params)
            f.write(f"{name}\t{python_name or ''}\t{json.dumps(implied) if implied else ''}\t"
                    f"{json.dumps(renamed) if renamed else ''}\t{note}\n")
    print(f"MeshLab {version}: {len(filters)} filters, {sum(len(p) for _, p in filters)} parameters")


if __name__ == "__main__":
    main()
