"""A filled layer as a binary PLY file that pymeshlab loads into the layer its arrays would build.

Loading such a file builds the mesh once, in its layer, where ``pymeshlab.Mesh`` copies it in its
constructor and ``add_mesh`` copies it again; :func:`.meshset_io.replace_current_mesh` says when
each way is taken.
"""
from __future__ import annotations

import numpy as np

__all__ = ["PLY_BLOCK_ROWS", "SELECTED_FLAG", "layer_ply_bytes", "write_layer_ply", "has_repeated_corners",
           "unit_range"]


def unit_range(colors):
    """Colours clipped to [0, 1] as pymeshlab requires; the array itself (no copy) when they already are."""
    colors = np.asarray(colors, np.float64)
    if colors.size == 0 or (colors.min() >= 0.0 and colors.max() <= 1.0):
        return colors
    return np.clip(colors, 0.0, 1.0)


PLY_BLOCK_ROWS = 1 << 18  # rows of a PLY element written at once: the file's copy of the mesh never exists whole

# The selection bit of VCG's per-vertex and per-face flags: pymeshlab's PLY reader takes a ``flags``
# property as the element's flags, so a selection written there needs no conditional selection after loading.
SELECTED_FLAG = 0x20


def _flags_field(lines, fields, selected):
    """Add the ``flags`` property to an element's header lines and fields, where a selection is written."""
    if selected is not None:
        lines.append("property int flags")
        fields.append(("flags", "<i4"))


_CHANNELS = ("red", "green", "blue", "alpha")


def _color_and_quality_fields(lines, fields, attrs):
    """Add an element's colour and quality properties, those of ``attrs`` (its ``color``, ``quality``)."""
    if "color" in attrs:
        for channel in _CHANNELS:
            lines.append(f"property uchar {channel}")
            fields.append((channel, "u1"))
    if "quality" in attrs:
        lines.append("property double quality")
        fields.append(("quality", "<f8"))


def _color_and_quality(block, attrs, rows):
    """Fill a block's colour and quality from ``attrs`` (their ``rows``)."""
    if "color" in attrs:
        colors = _color_bytes(attrs["color"][rows])
        for k, channel in enumerate(_CHANNELS):
            block[channel] = colors[:, k]
    if "quality" in attrs:
        block["quality"] = attrs["quality"][rows].ravel()


def _vertex_fields(vertex_attrs, selected=None):
    """(PLY header lines, numpy fields) of the vertex element.

    Colour and quality are written when the layer has them: the loaded layer has the per-vertex
    attributes the old one had, as after MeshLab's own filters (a mesh built by ``pymeshlab.Mesh``
    always has both, white and 0 where it was given none).
    """
    lines, fields = [], []
    for axis in "xyz":
        lines.append(f"property double {axis}")
        fields.append((axis, "<f8"))
    _color_and_quality_fields(lines, fields, vertex_attrs)
    if "texcoord" in vertex_attrs:
        lines += ["property float texture_u", "property float texture_v"]
        fields += [("texture_u", "<f4"), ("texture_v", "<f4")]
    _flags_field(lines, fields, selected)
    return lines, fields


def _face_fields(face_attrs, wedge, selected=None):
    """(PLY header lines, numpy fields) of the face element (colour, quality, wedge texture coordinates when present)."""
    lines, fields = ["property list uchar int vertex_indices"], [("corners", "u1"), ("vertex_indices", "<i4", 3)]
    _color_and_quality_fields(lines, fields, face_attrs)
    if wedge is not None:
        lines += ["property list uchar float texcoord", "property int texnumber"]
        fields += [("texcoords", "u1"), ("texcoord", "<f4", 6), ("texnumber", "<i4")]
    _flags_field(lines, fields, selected)
    return lines, fields


def _color_bytes(colors):
    """Colours in [0, 1] as the bytes pymeshlab.Mesh stores: clipped, times 255, truncated."""
    return (unit_range(colors) * 255.0).astype(np.uint8)


def _flags(block, selected, rows):
    """The block's flags: SELECTED_FLAG on the selected ``rows``, 0 elsewhere."""
    if selected is not None:
        block["flags"] = np.where(selected[rows], SELECTED_FLAG, 0)


def _vertex_block(fields, V, vertex_attrs, selected, rows):
    block = np.empty(rows.stop - rows.start, dtype=fields)
    for k, axis in enumerate("xyz"):
        block[axis] = V[rows, k]
    _color_and_quality(block, vertex_attrs, rows)
    if "texcoord" in vertex_attrs:
        block["texture_u"], block["texture_v"] = vertex_attrs["texcoord"][rows].T
    _flags(block, selected, rows)
    return block


def _face_block(fields, F, face_attrs, wedge, selected, rows):
    block = np.empty(rows.stop - rows.start, dtype=fields)
    block["corners"] = 3
    block["vertex_indices"] = F[rows]
    _color_and_quality(block, face_attrs, rows)
    if wedge is not None:
        block["texcoords"] = 6
        block["texcoord"] = wedge[3 * rows.start:3 * rows.stop].reshape(-1, 6)
        block["texnumber"] = 0  # the one texture index pymeshlab.Mesh gives wedge coordinates
    _flags(block, selected, rows)
    return block


def layer_ply_bytes(n_vertices, n_faces, vertex_attrs, face_attrs, wedge, vertex_selected=None, face_selected=None):
    """The size in bytes of the file :func:`write_layer_ply` writes, less its header (under a kilobyte)."""
    vertex_row = np.dtype(_vertex_fields(vertex_attrs, vertex_selected)[1]).itemsize
    face_row = np.dtype(_face_fields(face_attrs, wedge, face_selected)[1]).itemsize
    return n_vertices * vertex_row + n_faces * face_row


def write_layer_ply(path, V, F, vertex_attrs, face_attrs, wedge, vertex_selected=None, face_selected=None):
    """Write a mesh and its attributes as a binary PLY that ``load_new_mesh`` reads into the layer
    ``pymeshlab.Mesh(...)`` + ``add_mesh`` would build from the same arrays (see :func:`.meshset_io._new_mesh`),
    less the per-vertex colour and quality that ``pymeshlab.Mesh`` adds where ``vertex_attrs`` has none.

    Doubles stay doubles (positions, quality); colours are the bytes pymeshlab.Mesh makes of
    them; texture coordinates are single precision as pymeshlab stores them. Written in blocks
    of PLY_BLOCK_ROWS rows. ``vertex_selected`` (n_vertices,) and ``face_selected`` (n_faces,),
    boolean, when given, are written as the elements' flags: the loaded layer has that selection.
    """
    vertex_lines, vertex_fields = _vertex_fields(vertex_attrs, vertex_selected)
    face_lines, face_fields = _face_fields(face_attrs, wedge, face_selected)
    header = (["ply", "format binary_little_endian 1.0", f"element vertex {len(V)}"] + vertex_lines
              + [f"element face {len(F)}"] + face_lines + ["end_header"])
    with open(path, "wb") as fh:
        fh.write(("\n".join(header) + "\n").encode("ascii"))
        for start in range(0, len(V), PLY_BLOCK_ROWS):
            rows = slice(start, min(start + PLY_BLOCK_ROWS, len(V)))
            _vertex_block(vertex_fields, V, vertex_attrs, vertex_selected, rows).tofile(fh)
        for start in range(0, len(F), PLY_BLOCK_ROWS):
            rows = slice(start, min(start + PLY_BLOCK_ROWS, len(F)))
            _face_block(face_fields, F, face_attrs, wedge, face_selected, rows).tofile(fh)


def has_repeated_corners(F):
    """Does a face of F name one vertex twice?"""
    F = np.asarray(F)
    return bool(len(F)) and bool(np.any((F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])))
