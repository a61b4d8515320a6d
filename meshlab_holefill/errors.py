"""The package's exceptions: the one module every layer may import (it imports nothing of the package)."""


class HoleFillError(RuntimeError):
    """An algorithm could not fill a hole; the message is the reason reported per hole."""


class MeshTopologyError(ValueError):
    """The mesh violates an assumption of the hole fillers (named in the message)."""


class FilterParameterError(ValueError):
    """A filter was called with an unknown, mistyped or out-of-range parameter."""


class MlxScriptError(ValueError):
    """A filter script cannot be run; nothing was applied.

    Attributes
    ----------
    problems : list of ScriptProblem
        Every problem found, each with its line, filter and parameter.
    """

    def __init__(self, message, problems=()):
        super().__init__(message)
        self.problems = list(problems)


class MlxRunError(MlxScriptError):
    """A step of a validated script failed while running; the steps before it were applied.

    Attributes
    ----------
    step : ScriptStep
    results : list of dict
        Results of the steps that ran.
    """

    def __init__(self, message, step, results):
        super().__init__(message)
        self.step = step
        self.results = results
