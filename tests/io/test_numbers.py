"""Numbers as lab instruments write them (pihyst.io._numbers)."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pihyst.io._numbers import is_number, parse_number

finite = st.floats(allow_nan=False, allow_infinity=False)


@given(finite, st.sampled_from(["%r", "%.17g", "%.17e", "%.3f", "%g", "%+.10E"]))
def test_written_numbers_read_back(x, fmt):
    text = fmt % x
    if math.isinf(float(text)):  # rounded past the largest float: refused, rightly
        return
    assert parse_number(text) == float(text)
    assert parse_number(text.replace(".", ","), ",") == float(text)


@given(finite)
def test_repr_reads_back_exactly(x):
    assert parse_number(f"  {x!r} ") == x


@pytest.mark.parametrize("text,value", [("1.5", 1.5), ("-1.5e-3", -1.5e-3), ("+2", 2.0),
                                        (".5", 0.5), ("1.", 1.0), ("007", 7.0),
                                        ("1E+05", 1e5), ("-0", -0.0)])
def test_accepted(text, value):
    assert parse_number(text) == value


@pytest.mark.parametrize("text,reason", [
    ("1_5", "not a number"), ("0x10", "not a number"), ("1e", "not a number"),
    ("abc", "not a number"), ("nan", "not a finite number"), ("-inf", "not a finite number"),
    ("Infinity", "not a finite number"), ("NaN", "not a finite number"),
    ("1e999", "too large"), ("", "missing value"), ("  ", "missing value"),
    ("1,5", "a decimal comma?"), ("1.5.2", "not a number"), ("١٢", "not a number"),
    ("1 5", "not a number"), ("--1", "not a number"), ("e5", "not a number"),
])
def test_refused_with_a_reason(text, reason):
    with pytest.raises(ValueError, match=reason):
        parse_number(text)


def test_decimal_comma_only_when_asked():
    assert parse_number("1,5", ",") == 1.5
    with pytest.raises(ValueError, match="decimal comma"):
        parse_number("1.5", ",")
    assert not is_number("1,5") and is_number("1,5", ",")


@given(st.text(max_size=12))
def test_anything_accepted_is_a_finite_float_python_agrees_with(text):
    try:
        value = parse_number(text)
    except ValueError:
        return
    assert math.isfinite(value) and value == float(text.strip())
    assert "_" not in text and "x" not in text.lower()
