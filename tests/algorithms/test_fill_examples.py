"""The Examples sections of the four algorithms' ``fill`` docstrings run as doctests (numpy only, no pymeshlab)."""
import doctest
import importlib

import pytest

FILTER_MODULES = ["hu2012.min_angle_bilateral", "brunton2009.curve_unfolding", "xu2013.lssvm_poisson",
                  "xie_zou2013.differential_evolution"]


@pytest.mark.parametrize("module", FILTER_MODULES)
def test_fill_examples_run(module):
    mod = importlib.import_module(f"meshlab_holefill.algorithms.{module}")
    assert "Examples" in mod.fill.__doc__ and "References" in mod.fill.__doc__
    result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0
    assert result.failed == 0
