"""The careful, line-by-line reader of delimited text: slow, exact, and the judge.

The fast engines (:mod:`pihyst.io._text_engines`) hand a block back to it whenever they
do not accept the block whole; it then either reads the block to the same values or
raises :class:`CSVError` at the exact line and column of the first fault.
"""

import numpy as np

from pihyst.exceptions import CSVError
from pihyst.io._numbers import parse_number
from pihyst.io._text_format import FieldError, is_skipped, split_fields


def block_lines(block, first_line):
    """(line number, text) of the lines of a block of bytes with LF line ends."""
    for number, raw in enumerate(block.split(b"\n"), start=first_line):
        if not raw:
            continue
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as err:
            raise CSVError(None, number, 0, f"not UTF-8 text (byte {raw[err.start]:#04x})") \
                from None
        yield number, text


def field_count_error(path, number, fields, dialect):
    n, expected = len(fields), dialect.n_fields
    column = expected + 1 if n > expected else n + 1
    hint = ""
    if n > expected and dialect.separator == ",":
        hint = ("; a decimal comma in a comma-separated file? Use ';' or tab as the "
                "separator, or quote the numbers")
    return CSVError(path, number, column,
                    f"{n} fields where {dialect.where()} has {expected}{hint}")


def check_block(path, block, first_line, dialect, wanted, labels):
    """Values of the fields ``wanted`` (0-based) of every data line of ``block``, as an
    (n, len(wanted)) array; or :class:`CSVError` at the first fault."""
    rows = []
    try:
        for number, text in block_lines(block, first_line):
            if is_skipped(text):
                continue
            try:
                fields = split_fields(text, dialect.separator)
            except FieldError as err:
                raise CSVError(path, number, err.column, str(err)) from None
            if len(fields) != dialect.n_fields:
                raise field_count_error(path, number, fields, dialect)
            row = []
            for index, label in zip(wanted, labels):
                try:
                    row.append(parse_number(fields[index], dialect.decimal))
                except ValueError as err:
                    reason = str(err)
                    message = (f"missing value for column {label}" if reason == "missing value"
                               else f"column {label}: {reason}")
                    raise CSVError(path, number, index + 1, message) from None
            rows.append(row)
    except CSVError as err:
        if err.path is None:
            raise CSVError(path, err.line, err.column, err.message) from None
        raise
    return np.array(rows, dtype=float).reshape(len(rows), len(wanted))


def data_line_of(block_iter, dialect, row):
    """1-based line of the 0-based data row ``row``, from the (first line, block) pairs of
    the file's data part; None past the end."""
    seen = 0
    for first_line, block in block_iter:
        for number, raw in enumerate(block.split(b"\n"), start=first_line):
            text = raw.decode("utf-8", errors="replace")
            if is_skipped(text):
                continue
            if seen == row:
                return number
            seen += 1
    return None
