"""core.parameters: validation and conversion of filter parameters, without pymeshlab."""
import numpy as np
import pytest
from hypothesis import given, strategies as st

from meshlab_holefill.core.parameters import ParamSpec, Percentage, convert_param, resolve_params
from meshlab_holefill.errors import FilterParameterError

SPECS = [ParamSpec("n", "int", 3, "", minimum=1, maximum=10), ParamSpec("x", "float", 0.5, "", minimum=0.0),
         ParamSpec("flag", "bool", False, ""), ParamSpec("mode", "enum", "a", "", choices=("a", "b")),
         ParamSpec("radius", "length", Percentage(2), ""), ParamSpec("label", "string", "", "")]


def test_defaults_fill_in_and_a_percentage_is_of_the_diagonal():
    out = resolve_params(SPECS, {}, "f", bbox_diagonal=10.0)
    assert out == {"n": 3, "x": 0.5, "flag": False, "mode": "a", "radius": pytest.approx(0.2), "label": ""}


def test_an_unknown_name_is_refused_with_the_valid_ones():
    with pytest.raises(FilterParameterError, match=r"filter 'f' has no parameter 'nn'; valid parameters: n, x"):
        resolve_params(SPECS, {"nn": 1}, "f")


@pytest.mark.parametrize("name, value, message", [
    ("n", 2.5, "expected an int"), ("n", True, "expected an int"), ("n", 0, "0 is below the minimum 1"),
    ("n", 11, "11 is above the maximum 10"), ("x", "a", "expected a number"), ("x", float("nan"), "must be finite"),
    ("flag", 1, "expected a bool"), ("mode", "c", r"expected one of \['a', 'b'\]"),
    ("radius", "1%", "expected a number, pymeshlab.PureValue or pymeshlab.PercentageValue"),
    ("radius", float("inf"), "must be finite"), ("label", 3, "expected a string"),
])
def test_each_kind_refuses_what_it_cannot_take(name, value, message):
    spec = next(p for p in SPECS if p.name == name)
    with pytest.raises(FilterParameterError, match=f"filter 'f', parameter '{name}': {message}"):
        convert_param(spec, value, "f", 1.0)


def test_an_enum_takes_its_index_as_mlx_files_write_it():
    assert convert_param(SPECS[3], 1, "f") == "b"


@given(st.floats(0, 1e6), st.floats(1e-6, 1e6))
def test_a_length_is_absolute_or_a_percentage_of_the_diagonal(value, diagonal):
    spec = SPECS[4]
    assert convert_param(spec, value, "f", diagonal) == value
    assert convert_param(spec, Percentage(value), "f", diagonal) == pytest.approx(value / 100 * diagonal)


@given(st.integers(-5, 20))
def test_an_int_in_range_passes_unchanged_and_out_of_range_fails(n):
    if 1 <= n <= 10:
        assert convert_param(SPECS[0], np.int64(n), "f") == n
    else:
        with pytest.raises(FilterParameterError, match="minimum|maximum"):
            convert_param(SPECS[0], n, "f")
