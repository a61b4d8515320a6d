"""The package's exceptions: the one module every layer may import (it imports nothing of the package)."""


class HoleFillError(RuntimeError):
    """An algorithm could not fill a hole; the message is the reason reported per hole."""


class MeshTopologyError(ValueError):
    """The mesh violates an assumption of the hole fillers (named in the message)."""


class FilterParameterError(ValueError):
    """A filter was called with an unknown, mistyped or out-of-range parameter."""
