"""Our errors as pymeshlab's: what the MeshSet-facing doors raise is also a ``pymeshlab.PyMeshLabException``.

pymeshlab's built-in filters raise ``pymeshlab.PyMeshLabException`` for an unknown filter or
parameter; ours raise :class:`~meshlab_holefill.errors.FilterParameterError` (a ``ValueError``,
defined without pymeshlab). Through the MeshSet (its filter methods, ``apply_filter``, the
parameter listing) it comes as :class:`MeshSetFilterParameterError`, both at once, so that
``except pymeshlab.PyMeshLabException`` catches ours too. Script errors are raised as
:class:`MlxScriptError` / :class:`MlxRunError` of this module, subclasses of the ones in
:mod:`meshlab_holefill.errors` that are also ``PyMeshLabException``.
"""
from __future__ import annotations

import functools

import pymeshlab

from .. import errors
from ..errors import FilterParameterError


class MeshSetFilterParameterError(FilterParameterError, pymeshlab.PyMeshLabException):
    """A filter parameter error raised through the MeshSet: a ``ValueError`` and a ``pymeshlab.PyMeshLabException``."""


class MlxScriptError(errors.MlxScriptError, pymeshlab.PyMeshLabException):
    """A filter script cannot be run (nothing was applied): a ``ValueError`` and a ``pymeshlab.PyMeshLabException``."""


class MlxRunError(MlxScriptError, errors.MlxRunError):
    """A step of a validated script failed while running (the steps before it were applied)."""


def raises_meshset_errors(function):
    """Decorate a door so that a :class:`FilterParameterError` leaves it as a :class:`MeshSetFilterParameterError`."""

    @functools.wraps(function)
    def door(*args, **kwargs):
        try:
            return function(*args, **kwargs)
        except MeshSetFilterParameterError:
            raise
        except FilterParameterError as exc:
            raise MeshSetFilterParameterError(*exc.args).with_traceback(exc.__traceback__) from None

    return door


def pymeshlab_filter_list():
    """pymeshlab's own ``filter_list()`` (its built-in filters), also after :mod:`.doors` extended it."""
    function = pymeshlab.filter_list
    return getattr(function, "pymeshlab_original", function)()
