"""Our errors as pymeshlab's: what the MeshSet-facing doors raise is also a ``pymeshlab.PyMeshLabException``.

pymeshlab's built-in filters raise ``pymeshlab.PyMeshLabException`` for an unknown filter or
parameter; ours raise :class:`~meshlab_holefill.errors.FilterParameterError` (a ``ValueError``,
defined without pymeshlab). Through the MeshSet (its filter methods, ``apply_filter``, the
parameter listing) it comes as :class:`MeshSetFilterParameterError`, both at once, so that
``except pymeshlab.PyMeshLabException`` catches ours too.
"""
from __future__ import annotations

import functools

import pymeshlab

from ..core.parameters import FilterParameterError


class MeshSetFilterParameterError(FilterParameterError, pymeshlab.PyMeshLabException):
    """A filter parameter error raised through the MeshSet: a ``ValueError`` and a ``pymeshlab.PyMeshLabException``."""


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
