"""The C writer and parser of numeric text (pihyst.io._fastcsv) against their plain twins:
``repr`` for writing, ``float`` for reading, bit for bit."""

import math
import struct

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

from pihyst.io import _csv, _text_engines

fast = _text_engines._fast()
pytestmark = pytest.mark.skipif(fast is None, reason="pihyst.io._fastcsv is not built")

any_float = st.floats(allow_nan=True, allow_infinity=True)
# the doubles whose shortest decimal has 15, 16 or 17 digits, from their bits
any_bits = st.integers(0, 2**64 - 1).map(lambda b: struct.unpack("<d", struct.pack("<Q", b))[0])
HARD = [0.0, -0.0, 1.0, 0.1, 0.3, 1e16, 1e-5, 1e-4, 9.999999999999999e22, 1e23, 5e-324,
        2.2250738585072014e-308, 1.7976931348623157e308, 2.0**60, 2.0**-60,
        123456789012345678.0, 1234567890123456.0, 0.1 + 0.2, 4.35, 9007199254740993.0,
        float("nan"), float("inf"), -float("inf")]


def as_repr(values):
    return "".join(f"{float(v)!r}\n" for v in values).encode("ascii")


@given(st.lists(st.one_of(any_float, any_bits), min_size=1, max_size=50))
@example(HARD)
def test_writer_writes_what_repr_writes(values):
    assert fast.format_rows([np.array(values, dtype=float)]) == as_repr(values)


def test_writer_on_a_million_values_of_every_kind():
    rng = np.random.default_rng(7)
    values = np.concatenate([
        rng.normal(0, 100, 200_000), np.arange(200_000) / 1e4, rng.uniform(0, 150, 100_000),
        10.0 ** rng.uniform(-30, 30, 200_000), rng.integers(-10**6, 10**6, 100_000),
        rng.integers(0, 2**64, 200_000, dtype=np.uint64).view(np.float64)])
    assert fast.format_rows([values]) == as_repr(values)


@given(st.lists(st.floats(allow_nan=False, allow_infinity=False), min_size=1, max_size=20),
       st.integers(1, 4))
def test_rows_of_several_columns_equal_the_plain_writer(values, k):
    columns = [np.array(values) / (j + 1) for j in range(k)]
    assert fast.format_rows(columns) == _csv.format_rows(columns, engine="numpy")
    assert _csv.format_rows(columns) == _csv.format_rows(columns, engine="numpy")


def test_writer_refuses_columns_of_other_lengths():
    with pytest.raises(ValueError, match="one length"):
        fast.format_rows([np.zeros(3), np.zeros(2)])
    assert fast.format_rows([]) == b"" and fast.format_rows([np.zeros(0)]) == b""


digits = st.text("0123456789", min_size=1, max_size=25)


@st.composite
def decimals(draw):
    """Decimal text of the grammar, up to 25 significant digits, any exponent."""
    sign = draw(st.sampled_from(["", "-", "+"]))
    whole, frac = draw(digits), draw(st.one_of(st.none(), digits))
    mantissa = whole if frac is None else f"{whole}.{frac}"
    exp = draw(st.one_of(st.none(), st.integers(-340, 320)))
    return sign + mantissa + ("" if exp is None else f"e{exp}")


def parse(texts):
    return fast.parse_block("".join(t + "\n" for t in texts).encode("ascii"), ",", 1, [0])


@given(st.lists(decimals(), min_size=1, max_size=30))
@example(["9007199254740993", "1.00000000000000011102230246251565404236316680908203125",
          "0.1", "5e-324", "2.4703282292062328e-324", "1e22", "1e23", "1.7976931348623157e308",
          "0.000000000000000000000000000001", "123456789012345678901234567890",
          "9.999999999999999e22", "-0", "0e999"])
def test_parser_reads_what_float_reads(texts):
    expected = [float(t) for t in texts]
    got = parse(texts)
    if not all(math.isfinite(v) for v in expected):
        assert got is None           # the careful reader names the field
        return
    assert np.array_equal(got[:, 0].view(np.int64), np.array(expected).view(np.int64))


@given(st.lists(st.one_of(any_bits, st.floats(allow_nan=False, allow_infinity=False)),
                min_size=1, max_size=50))
def test_written_values_read_back_to_the_same_bits(values):
    values = np.array([v for v in values if math.isfinite(v)] or [0.0])
    got = fast.parse_block(fast.format_rows([values, -values]), ",", 2, [0, 1])
    assert np.array_equal(got.view(np.int64), np.column_stack([values, -values]).view(np.int64))


def test_near_midpoints_read_exactly():
    # the decimals halfway between neighbouring doubles, and a hair either side: the
    # cases where rounding twice (to long double, then double) would go wrong
    rng = np.random.default_rng(3)
    xs = rng.uniform(1, 1e6, 2000)
    texts = []
    for x in xs:
        up = np.nextafter(x, np.inf)
        mid = (float.fromhex(x.hex()) + up) / 2      # not exact: the nearest to halfway
        for v in (mid, np.nextafter(mid, 0), np.nextafter(mid, np.inf)):
            texts.append(f"{v:.17g}")
            texts.append(f"{v:.19g}")
    from decimal import Decimal
    for x in xs[:300]:   # the exact halfway points, written with all their digits
        exact = (Decimal(float(x)) + Decimal(float(np.nextafter(x, np.inf)))) / 2
        texts.append(f"{exact:.19e}")
    got = parse(texts)
    assert np.array_equal(got[:, 0], np.array([float(t) for t in texts]))
