"""CSV files of docs/interfaces.md: one header row, columns found by name, extra
columns ignored, lines starting with ``#`` are comments.

Errors are :class:`CSVError` with a one-line message ``FILE:LINE:COLUMN: what is wrong``
(line and column 1-based; column counts fields).
"""

import csv
import io as _io
import os

import numpy as np

from pihyst._atomic import write_atomically
from pihyst.exceptions import CSVError


def read_columns(path, names, optional=()):
    """Read named columns of a CSV file as float arrays.

    Returns ``(columns, lines)``: a dict name -> array holding every column of ``names``
    (an error if absent) and those of ``optional`` that the header has, and the 1-based
    file line of each data row. Every value must be a finite number; the file must
    have at least one data row.
    """
    path = os.fspath(path)
    try:
        # utf-8-sig: a byte-order mark (Excel writes one) is not part of the first name
        with open(path, encoding="utf-8-sig", newline="") as f:
            text = f.read()
    except OSError as err:
        raise CSVError(path, 0, 0, f"cannot read file: {err.strerror}") from None
    except UnicodeDecodeError:
        raise CSVError(path, 1, 0, "not a text file (UTF-8 expected)") from None
    rows = [(n, row) for n, row in enumerate(csv.reader(_io.StringIO(text)), start=1)
            if row and not row[0].lstrip().startswith("#") and any(c.strip() for c in row)]
    if not rows:
        raise CSVError(path, 1, 0, "empty file: expected a header row naming the columns "
                       f"{', '.join(names)}")
    header_line, header = rows[0]
    header = [h.strip() for h in header]
    index = {}
    for name in names:
        if name not in header:
            hint = ("; columns must be separated by commas"
                    if len(header) == 1 and any(c in header[0] for c in ";\t") else "")
            raise CSVError(path, header_line, 0, f"missing column {name!r} in header "
                           f"({', '.join(header)}){hint}")
        index[name] = header.index(name)
    for name in optional:
        if name in header:
            index[name] = header.index(name)
    names = list(index)
    if len(rows) == 1:
        raise CSVError(path, header_line, 0, "no data rows after the header")
    values = np.empty((len(rows) - 1, len(names)))
    for i, (line, row) in enumerate(rows[1:]):
        for j, name in enumerate(names):
            col = index[name]
            if col >= len(row) or not row[col].strip():
                raise CSVError(path, line, col + 1, f"missing value for column {name!r}")
            try:
                v = float(row[col])
            except ValueError:
                raise CSVError(path, line, col + 1, f"column {name!r}: {row[col].strip()!r} "
                               "is not a number") from None
            if not np.isfinite(v):
                raise CSVError(path, line, col + 1, f"column {name!r}: {row[col].strip()} "
                               "is not a finite number")
            values[i, j] = v
    lines = np.array([line for line, _ in rows[1:]])
    return {name: values[:, j].copy() for j, name in enumerate(names)}, lines


def write_columns(path, columns, comments=()):
    """Write named columns (dict name -> array) to ``path``, complete or not at all."""
    names = list(columns)
    data = np.column_stack([np.asarray(columns[n], dtype=float) for n in names])
    out = _io.StringIO()
    for c in comments:
        out.write(f"# {c}\n")
    out.write(",".join(names) + "\n")
    np.savetxt(out, data, delimiter=",", fmt="%.17g")
    write_atomically(path, out.getvalue())


def column_number(path, name):
    """1-based position of column ``name`` in the header of ``path``, 0 if absent
    (for error messages that name a column)."""
    with open(path, encoding="utf-8-sig", newline="") as f:
        for row in csv.reader(f):
            if row and not row[0].lstrip().startswith("#") and any(c.strip() for c in row):
                fields = [h.strip() for h in row]
                return fields.index(name) + 1 if name in fields else 0
    return 0
