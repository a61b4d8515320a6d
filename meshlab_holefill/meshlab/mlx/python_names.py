"""MeshLab's rule from a MeshLab (display or parameter) name to the pymeshlab python name."""
from __future__ import annotations

import re

__all__ = ["python_param_name"]

# pymeshlab's computePythonName appends '_' to these (its list, including its missing comma
# that leaves out "def" and "from", so that the names agree with pymeshlab's).
_PYMESHLAB_KEYWORDS = {
    "False", "await", "else", "import", "pass", "None", "break", "except", "in", "raise", "True", "class",
    "finally", "is", "return", "and", "continue", "for", "lambda", "try", "as", "def\tfrom", "nonlocal",
    "while", "assert", "del", "global", "not", "with", "async", "elif", "if", "or", "yield",
}
_REMOVED_CHARACTERS = re.compile(r"""[()\[\].,'":+]+""")


def python_param_name(mlx_name):
    """MeshLab's rule from a MeshLab name to the pymeshlab python name.

    Lower case; ``' '``, ``'/'`` and ``'-'`` become ``'_'``; the characters ``()[].,'":+``
    are removed; a python keyword gets a trailing ``'_'`` ("lambda" -> "lambda_"). This is
    pymeshlab's ``computePythonName`` (which also produced the pre-2022 filter names from
    display names); pymeshlab's regular expression does not remove ``[]``, this one does,
    so that the result is always an identifier (no MeshLab name contains them).
    """
    name = mlx_name.lower().replace(" ", "_").replace("/", "_").replace("-", "_")
    name = _REMOVED_CHARACTERS.sub("", name)
    if name in _PYMESHLAB_KEYWORDS:
        name += "_"
    return name
