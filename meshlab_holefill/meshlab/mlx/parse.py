"""FilterScript XML read into elements with line numbers, and the errors a script can raise."""
from __future__ import annotations

from dataclasses import dataclass, field
from xml.parsers import expat

from ..exceptions import MlxRunError, MlxScriptError
from . import names as mlx_names

__all__ = ["MlxRunError", "MlxScriptError", "ScriptProblem", "last_recorded_filter", "parse_xml"]


@dataclass
class ScriptProblem:
    source: str
    line: int | None
    filter: str | None
    parameter: str | None
    message: str

    def __str__(self):
        where = f"{self.source}:{self.line}" if self.line else self.source
        parts = [where]
        if self.filter is not None:
            parts.append(f"filter '{self.filter}'")
        if self.parameter is not None:
            parts.append(f"parameter '{self.parameter}'")
        return ": ".join(parts + [self.message])


@dataclass
class _Element:
    """An XML element of the script with its line number."""

    tag: str
    line: int
    attrs: dict
    children: list = field(default_factory=list)

    @property
    def name(self):
        return self.attrs.get("name")


def parse_xml(data, source):
    """Parse FilterScript XML into _Element trees (root's children: filters, theirs: params)."""
    parser = expat.ParserCreate()
    stack = []
    root = []

    def start(tag, attrs):
        element = _Element(tag, parser.CurrentLineNumber, dict(attrs))
        if stack:
            stack[-1].children.append(element)
        else:
            root.append(element)
        stack.append(element)

    def end(tag):
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        problem = ScriptProblem(source, exc.lineno, None, None,
                                f"malformed XML: {expat.ErrorString(exc.code)} (column {exc.offset + 1})")
        raise MlxScriptError(str(problem), [problem]) from None
    top = root[0]
    if top.tag != "FilterScript":
        problem = ScriptProblem(source, top.line, None, None,
                                f"not a MeshLab filter script: the root element is <{top.tag}>, not <FilterScript>")
        raise MlxScriptError(str(problem), [problem])
    return top


def last_recorded_filter(record, python_name):
    """The last ``<filter>`` of pymeshlab's own record of a MeshSet, if it is ``python_name``.

    pymeshlab keeps every built-in filter applied to a MeshSet, with all its parameters in
    MeshLab form (``ms.save_filter_script``); the registration keeps that record, as bytes,
    of each built-in call, and a written script takes the call's parameters from it.

    Parameters
    ----------
    record : bytes
        The .mlx text pymeshlab wrote just after the call.
    python_name : str

    Returns
    -------
    _Element or None
        The ``<filter>`` element, or None when the last record is another filter.
    """
    filters = [e for e in parse_xml(record, "pymeshlab record").children if e.tag == "filter"]
    if not filters:
        return None
    understood = mlx_names.resolve_filter(filters[-1].name or "")
    if understood is None or understood.python_name != python_name:
        return None
    return filters[-1]
