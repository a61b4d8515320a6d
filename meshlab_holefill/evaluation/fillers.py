"""The contestants of a comparison: our filters, the third-party anchors and MeshLab's Close Holes.

A :class:`Filler` is a filter with fixed parameters; :func:`parse_fillers` reads them from the
``--filters`` text of ``compare`` and ``scripts/benchmark.py``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..meshlab.registration import filter_list, is_builtin_filter, parse_text_value
from .anchors import ANCHORS, is_anchor

__all__ = ["BASELINE", "Filler", "anchor_fillers", "default_fillers", "parse_fillers"]

BASELINE = "meshing_close_holes"


@dataclass
class Filler:
    """A filter with fixed parameters, as one contestant of the comparison."""

    label: str
    filter: str
    params: dict = field(default_factory=dict)


def _parse_value(text):
    # "all" (maxholesize covering every hole), enum names and "5%" stay text here.
    return parse_text_value(text, percentages=False)


def _resolve_name(name):
    ours = filter_list()
    if name in ours or name == BASELINE or is_anchor(name) or is_builtin_filter(name):
        return name
    matches = [f for f in ours if f.endswith(name) or f.endswith("_" + name)]
    if len(matches) == 1:
        return matches[0]
    raise ValueError(f"unknown filter '{name}' (ours: {', '.join(ours)}; third-party: {', '.join(ANCHORS)}; "
                     "or any pymeshlab filter name)")


def default_fillers(refinehole=False):
    """Every registered filter of ours with its defaults, the third-party anchors, MeshLab's Close Holes twice.

    The anchors (:data:`.anchors.ANCHORS`: ``cgal_liepa``, ``pymeshfix``) get ``maxholesize``
    "all"; one whose package is not installed is skipped with a note when the comparison runs.

    ``meshing_close_holes`` runs with its defaults (holes up to 30 edges) and with a
    ``maxholesize`` covering every hole ("all", resolved per comparison), optionally also with
    ``refinehole=True``.

    Returns
    -------
    list of Filler
    """
    out = [Filler(name, name) for name in filter_list()]
    out += anchor_fillers()
    out += [Filler(f"{BASELINE} (default)", BASELINE),
            Filler(f"{BASELINE} (all holes)", BASELINE, {"maxholesize": "all"})]
    if refinehole:
        out.append(Filler(f"{BASELINE} (all holes, refined)", BASELINE, {"maxholesize": "all", "refinehole": True}))
    return out


def anchor_fillers():
    """The third-party fillers with their defaults and a ``maxholesize`` covering every hole.

    Returns
    -------
    list of Filler
    """
    return [Filler(name, name, {"maxholesize": "all"}) for name in ANCHORS]


def parse_fillers(spec, refinehole=False):
    """Fillers from ``--filters`` text.

    Entries are separated by commas (or given as a list); each is ``name`` or
    ``name:param=value[:param=value...]`` (a comma-separated ``param=value`` right after an
    entry also belongs to it). ``name`` may be a unique suffix of one of our filters
    (``min_angle_bilateral``); ``ours`` means all registered filters of ours, ``anchors`` the
    third-party fillers (``cgal_liepa``, ``pymeshfix``; each also by name) and ``baseline``
    the two ``meshing_close_holes`` variants. ``maxholesize=all`` covers every hole; the
    anchors get it unless their ``maxholesize`` is given.

    Returns
    -------
    list of Filler
    """
    if spec is None or spec == "" or spec == []:
        return default_fillers(refinehole)
    items = spec if isinstance(spec, (list, tuple)) else [spec]
    tokens = [t.strip() for item in items for t in str(item).split(",") if t.strip()]
    entries = []
    for tok in tokens:
        if "=" in tok and ":" not in tok and entries:
            entries[-1].append(tok)
        else:
            entries.append(tok.split(":"))
    out = []
    for name, *assignments in entries:
        params = {}
        for a in assignments:
            if "=" not in a:
                raise ValueError(f"filter parameter '{a}' of '{name}' must be param=value")
            key, value = a.split("=", 1)
            params[key.strip()] = _parse_value(value.strip())
        if name == "ours":
            out += [Filler(n, n, dict(params)) for n in filter_list()]
            continue
        if name == "baseline":
            out += [f for f in default_fillers(refinehole) if f.filter == BASELINE]
            continue
        if name == "anchors":
            out += [Filler(f.label, f.filter, {**f.params, **params}) for f in anchor_fillers()]
            continue
        full = _resolve_name(name)
        if is_anchor(full):
            label = full if not params else f"{full} ({', '.join(f'{k}={v}' for k, v in params.items())})"
            out.append(Filler(label, full, {"maxholesize": "all", **params}))
            continue
        label = full if not params else f"{full} ({', '.join(f'{k}={v}' for k, v in params.items())})"
        out.append(Filler(label, full, params))
    labels = [f.label for f in out]
    dupes = {x for x in labels if labels.count(x) > 1}
    if dupes:
        raise ValueError(f"filter given twice: {', '.join(sorted(dupes))}")
    return out
