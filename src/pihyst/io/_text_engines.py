"""Vectorised readers of a block of delimited text: pihyst's own C parser of numeric
blocks (:mod:`pihyst.io._fastcsv`, built with the package: the default install's fast
path), else pyarrow's CSV reader when installed, else NumPy's ``loadtxt``.

Each returns the (n, k) float array of the wanted fields, or None when it does not take
the block whole (any field it cannot convert, a missing value, NaN or infinity, a line
with another number of fields, a quote, ...): the careful reader
(:mod:`pihyst.io._text_check`) then reads the block or names the fault. An engine may
refuse what is valid; it never accepts what the careful reader refuses.
"""

import importlib
import io
import re
from typing import Any

import numpy as np

_COMMENT_LINES = re.compile(rb"(?m)^[ \t]*#[^\n]*(?:\n|\Z)")
_BLANK_RUNS = re.compile(rb"[ \t]+")
_EDGE_SPACES = re.compile(rb"(?m)^ | $")


def engine_name():
    """'c', 'pyarrow' or 'numpy': the engine :func:`read_block` uses."""
    if _fast() is not None:
        return "c"
    return "pyarrow" if _arrow() is not None else "numpy"


_ARROW: list[Any] = []
_FAST: list[Any] = []


def _fast():
    """pihyst's C parser and writer (None if the package was built without it)."""
    if not _FAST:
        try:     # (by name: the compiled module, imported only when first needed)
            _FAST.append(importlib.import_module("pihyst.io._fastcsv"))
        except ImportError:
            _FAST.append(None)
    return _FAST[0]


def _arrow():
    if not _ARROW:
        try:
            import pyarrow
            import pyarrow.csv
            _ARROW.append((pyarrow, pyarrow.csv))
        except ImportError:
            _ARROW.append(None)
    return _ARROW[0]


def read_block(block, dialect, wanted, engine=None):
    """The wanted fields of a block (bytes, LF line ends, whole lines), or None."""
    if b"#" in block:
        block = _COMMENT_LINES.sub(b"", block)
    if not block.strip():
        return np.empty((0, len(wanted)))
    if dialect.decimal == "," and b"." in block:
        return None   # '1.5' in a decimal-comma file: the careful reader says where
    engine = engine or engine_name()
    if engine == "c":
        values = _fast().parse_block(block, dialect.separator, dialect.n_fields, list(wanted))
    elif engine == "pyarrow":
        values = _read_arrow(block, dialect, wanted)
    else:
        values = _read_numpy(block, dialect, wanted)
    if values is None or not np.isfinite(values).all():
        return None
    return values


def _read_arrow(block, dialect, wanted):
    pa, csv = _arrow()
    sep = dialect.separator
    if sep is None:
        if b'"' in block:
            return None
        block = _EDGE_SPACES.sub(b"", _BLANK_RUNS.sub(b" ", block))
        sep = " "
    elif b'"' in block and not _quotes_paired_per_line(block):
        return None
    names = [f"f{i}" for i in range(dialect.n_fields)]
    picked = [names[i] for i in wanted]
    try:
        table = csv.read_csv(
            io.BytesIO(block),
            read_options=csv.ReadOptions(column_names=names, block_size=1 << 24),
            parse_options=csv.ParseOptions(delimiter=sep, quote_char='"',
                                           newlines_in_values=False, ignore_empty_lines=True),
            convert_options=csv.ConvertOptions(
                column_types={n: pa.float64() for n in picked}, include_columns=picked,
                null_values=[""], strings_can_be_null=False, quoted_strings_can_be_null=False,
                decimal_point=dialect.decimal))
    except (pa.ArrowInvalid, pa.ArrowTypeError, ValueError):
        return None
    out = np.empty((table.num_rows, len(picked)))
    for j, name in enumerate(picked):
        column = table.column(name)
        if column.null_count:
            return None
        out[:, j] = column.to_numpy()
    return out


def _read_numpy(block, dialect, wanted):
    if b'"' in block:
        return None
    sep = dialect.separator
    if dialect.decimal == ",":
        block = block.replace(b",", b".")
    usecols = None
    if sep is not None:
        if not _same_field_counts(block, sep, dialect.n_fields):
            return None
        usecols = wanted
    try:
        text = block.decode("ascii")
        values = np.loadtxt(io.StringIO(text), delimiter=sep, usecols=usecols, ndmin=2,
                            dtype=float, comments=None)
    except (ValueError, UnicodeDecodeError):
        return None
    if usecols is None:
        if values.shape[1] != dialect.n_fields:
            return None
        values = values[:, wanted]
    return values


def _per_line_counts(block, byte):
    """Occurrences of ``byte`` on each line of ``block``, and each line's length."""
    b = np.frombuffer(block if block.endswith(b"\n") else block + b"\n", dtype=np.uint8)
    ends = np.flatnonzero(b == 10)
    hits = np.flatnonzero(b == byte)
    before = np.searchsorted(hits, ends)
    counts = np.diff(before, prepend=0)
    lengths = np.diff(ends, prepend=-1) - 1
    return counts, lengths


def _quotes_paired_per_line(block):
    """Whether no quoted field of the block goes on past its line (the careful reader
    refuses those; pyarrow would join the lines)."""
    counts, _ = _per_line_counts(block, ord('"'))
    return not np.any(counts % 2)


def _same_field_counts(block, sep, n_fields):
    """Whether every non-blank line of the block has ``n_fields`` fields."""
    counts, lengths = _per_line_counts(block, ord(sep))
    # a line of only spaces is blank (skipped) in the careful reader too
    blank = lengths == 0
    return bool(np.all(blank | (counts == n_fields - 1)))
