"""Which files a batch works on and where each one's output goes: files, folders, globs, naming.

Every problem (a pattern that matches nothing, an output that would overwrite an input, two
inputs with the same output) is found here, before any work starts.
"""
from __future__ import annotations

import glob
import hashlib
import os
from dataclasses import dataclass

# Formats the batch reads when it walks a folder (pymeshlab reads more; a file named
# explicitly or by a glob is taken whatever its extension).
MESH_EXTENSIONS = (".ply", ".obj", ".stl", ".off", ".3ds", ".dae", ".gltf", ".glb", ".wrl", ".x3d", ".ptx")
# Formats a batch writes (--format).
OUTPUT_FORMATS = ("ply", "obj", "stl", "off")


class BatchInputError(ValueError):
    """A batch that cannot start: no input, a clash of outputs with inputs, a bad option."""


@dataclass(frozen=True)
class FileItem:
    """One input file and its outputs.

    Attributes
    ----------
    input : str
        Absolute path of the mesh to repair.
    output : str
        Absolute path of the repaired mesh.
    result : str
        Absolute path of the per-file result JSON (``output + ".json"``).
    name : str
        The output's path relative to the output folder (used in reports and task keys).
    size : int
        Input size in bytes (the largest files are started first).
    """

    input: str
    output: str
    result: str
    name: str
    size: int


def _folder_files(folder, skip):
    """Mesh files under ``folder`` (recursive, sorted), leaving out everything under ``skip``."""
    found = []
    for root, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if os.path.realpath(os.path.join(root, d)) != skip)
        found += [os.path.join(root, f) for f in sorted(files) if f.lower().endswith(MESH_EXTENSIONS)]
    return found


def expand_inputs(inputs, out):
    """Files named by ``inputs``, each with the folder its output path is relative to.

    Parameters
    ----------
    inputs : str, os.PathLike or sequence of them
        Files, folders (walked recursively for mesh files) and glob patterns (``**`` allowed).
    out : str
        The output folder; files under it are never taken as inputs.

    Returns
    -------
    list of (str, str or None)
        ``(absolute path, folder)``: ``folder`` is the input folder the file was found in, or
        None for a file named directly or by a pattern. Duplicates are dropped.

    Raises
    ------
    BatchInputError
        An input that is neither a file, nor a folder, nor a pattern matching a file; a folder
        without mesh files.
    """
    if isinstance(inputs, (str, os.PathLike)):
        inputs = [inputs]
    skip = os.path.realpath(out)
    items, seen = [], set()
    for given in map(os.fspath, inputs):
        if os.path.isdir(given):
            found = [(f, os.path.abspath(given)) for f in _folder_files(given, skip)]
            what = f"folder {given!r} has no mesh files ({', '.join(MESH_EXTENSIONS)})"
        elif os.path.isfile(given):
            found, what = [(given, "")], ""
        else:
            found = [(f, None) for f in sorted(glob.glob(given, recursive=True)) if os.path.isfile(f)]
            what = f"no file matches {given!r}"
        if not found:
            raise BatchInputError(what)
        for path, folder in found:
            real = os.path.realpath(path)
            # files found under the output folder are earlier outputs; a file named there is checked later
            earlier_output = folder != "" and (real + os.sep).startswith(skip + os.sep)
            if real not in seen and not earlier_output:
                seen.add(real)
                items.append((os.path.abspath(path), folder or None))
    if not items:
        raise BatchInputError(f"every file found lies inside the output folder {out}; "
                              "choose an output folder apart from the inputs")
    return items


def output_extension(path, format):
    """The output's extension: ``format`` if given, else the input's own if a batch can write it, else ply."""
    if format is not None:
        format = format.lower().lstrip(".")
        if format not in OUTPUT_FORMATS:
            raise BatchInputError(f"unknown output format {format!r}; choose one of {', '.join(OUTPUT_FORMATS)}")
        return "." + format
    ext = os.path.splitext(path)[1].lower()
    return ext if ext.lstrip(".") in OUTPUT_FORMATS else ".ply"


def plan_outputs(inputs, out, format=None):
    """Output and result paths for every input file.

    A file found in an input folder keeps its path below that folder; a file named directly keeps
    its name. Two inputs that would get the same output (``scan.ply`` and ``scan.obj`` written as
    ply) get their source extension added (``scan_ply.ply``, ``scan_obj.ply``).

    Parameters
    ----------
    inputs : see :func:`expand_inputs`
    out : str
        Output folder (need not exist yet).
    format : {"ply", "obj", "stl", "off"}, optional
        Output format for every file; default: each input's own when it is one of those.

    Returns
    -------
    list of FileItem
        In input order.

    Raises
    ------
    BatchInputError
        See :func:`expand_inputs`; also an output that would overwrite an input, and outputs
        that still clash after the extension is added.
    """
    out = os.path.abspath(os.fspath(out))
    found = expand_inputs(inputs, out)
    names = []
    for path, folder in found:
        rel = os.path.relpath(path, folder) if folder else os.path.basename(path)
        names.append(os.path.splitext(rel)[0] + output_extension(path, format))
    counts = {}
    for name in names:
        counts[name] = counts.get(name, 0) + 1
    for i, (path, _) in enumerate(found):
        if counts[names[i]] > 1:
            stem, ext = os.path.splitext(names[i])
            names[i] = f"{stem}_{os.path.splitext(path)[1].lstrip('.').lower()}{ext}"
    return _checked_items(found, names, out)


def _checked_items(found, names, out):
    by_output = {}
    inputs = {os.path.realpath(path): path for path, _ in found}
    items = []
    for (path, _), name in zip(found, names):
        output = os.path.join(out, name)
        real = os.path.realpath(output)
        if real in inputs or os.path.realpath(output + ".json") in inputs:
            raise BatchInputError(f"the output of {path} would overwrite the input {inputs.get(real, path)}; "
                                  "choose another --out folder (or another --format)")
        if real in by_output:
            raise BatchInputError(f"{by_output[real]} and {path} would both be written to {output}; "
                                  "give them in separate runs or folders")
        by_output[real] = path
        items.append(FileItem(path, output, output + ".json", name, os.path.getsize(path)))
    return items


def sha256_file(path, chunk=1 << 20):
    """Hex SHA-256 of a file's content."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(chunk), b""):
            h.update(block)
    return h.hexdigest()
