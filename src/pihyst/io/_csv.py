"""CSV files of docs/interfaces.md, written fast and atomically, and the former reader
interface :func:`read_columns` (now a thin layer over :mod:`pihyst.io._records`).

Errors are :class:`CSVError` with a one-line message ``FILE:LINE:COLUMN: what is wrong``
(line and column 1-based; column counts fields).
"""

import io as _io
import json
import os
import stat

import numpy as np

from pihyst._atomic import AtomicFile
from pihyst.exceptions import CSVError
from pihyst.io._column_sinks import (
    SIDECAR_FORMAT,
    SINKS,
    check_output_format,
    output_format,
)
from pihyst.io._text_check import data_line_of
from pihyst.io._text_source import TextSource

WRITE_ROWS = 1 << 16


def read_columns(path, names, optional=()):
    """Read named columns of a delimited text file as float arrays.

    Returns ``(columns, lines)``: a dict name -> array holding every column of ``names``
    (an error if absent) and those of ``optional`` that the header has, and the 1-based
    file line of each data row. Every value must be a finite number; the file must
    have at least one data row.
    """
    src = TextSource(path)
    if not src.columns:
        raise CSVError(src.path, src.dialect.first_line, 0, "no header line naming the "
                       f"columns {', '.join(names)}")
    index = {}
    for name in [*names, *optional]:
        hits = [i for i, c in enumerate(src.columns) if c == name]
        if len(hits) > 1:
            raise CSVError(src.path, src.dialect.header_line, hits[1] + 1,
                           f"column {name!r} appears {len(hits)} times in the header")
        if hits:
            index[name] = hits[0]
        elif name in names:
            raise CSVError(src.path, src.dialect.header_line, 0, f"missing column {name!r} "
                           f"in header ({', '.join(src.columns)})")
    values = np.concatenate(list(src.blocks(list(index.values()))))
    blocks = [(first, block) for first, block, _ in src._blocks()]
    lines = np.array([data_line_of(blocks, src.dialect, i) for i in range(len(values))]) \
        if len(values) < 10_000 else _all_lines(blocks)
    return {n: values[:, j].copy() for j, n in enumerate(index)}, lines


def _all_lines(blocks):
    from pihyst.io._text_format import is_skipped
    out = []
    for first, block in blocks:
        for number, raw in enumerate(block.split(b"\n"), start=first):
            if not is_skipped(raw.decode("utf-8", errors="replace")):
                out.append(number)
    return np.array(out)


class ColumnWriter:
    """A CSV file written block by block that appears only once complete, through
    :class:`pihyst._atomic.AtomicFile`: rows go to an unnamed file in the target's
    folder (nothing is left if the process is killed), put in place by :meth:`close`;
    :meth:`abort`, or an exception inside ``with ColumnWriter(...)``, gives it up.

    Values are written as the shortest decimal that reads back exactly, as Python's
    ``repr`` writes them (:func:`format_rows`).

    An output named ``.parquet``, ``.h5`` or ``.hdf5`` is written in that format instead
    (:mod:`pihyst.io._column_sinks`; pyarrow, h5py), its metadata inside the file.

    The file is plain CSV: one header line, then numbers, so that NumPy's and pandas'
    default readers open it (``np.genfromtxt(names=True, delimiter=",")``,
    ``np.loadtxt(skiprows=1, delimiter=",")``, ``pandas.read_csv``). What used to be
    ``#`` comment lines (``comments``: what wrote it, with which options) goes to a
    sidecar, ``PATH.json`` beside it (:func:`sidecar_path`), written once the CSV is
    complete; pihyst's reader reads it back into the record's metadata."""

    def __init__(self, path, names, comments=(), engine=None, metadata=None):
        self.path = os.fspath(path)
        self.engine = engine
        self.names = list(names)
        self.comments = [str(c) for c in comments]
        self.metadata = dict(metadata or {})
        self.rows = 0
        self.format = output_format(self.path)
        if self.format != "csv":
            # Parquet or HDF5: the metadata inside the file, no sidecar
            check_output_format(self.path)
            self._sink = SINKS[self.format](self.path, self.names, self._described())
            self._file = None
            return
        self._sink = None
        self._file = AtomicFile(self.path)
        head = ",".join(self.names) + "\n"
        try:
            self._file.write(head.encode("utf-8"))
        except BaseException:
            self._file.abort()        # no caller holds this writer yet to abort it
            raise

    def write(self, columns):
        """Append rows: a dict name -> array with every name of the header."""
        data = [np.ascontiguousarray(columns[n], dtype=np.float64) for n in self.names]
        n = len(data[0])
        if self._sink is not None:
            self._sink.write(data)
            self.rows += n
            return
        for start in range(0, n, WRITE_ROWS):
            self._file.write(format_rows([a[start:start + WRITE_ROWS] for a in data],
                                         self.engine))
        self.rows += n

    def _described(self):
        return described(self.path, self.names, self.rows, self.comments, self.metadata)

    def close(self):
        if self._sink is not None:
            self._sink.commit(self._described())
            return
        self._file.commit()
        write_sidecar(self.path, self.names, self.rows, self.comments, self.metadata)

    def abort(self):
        if self._sink is not None:
            self._sink.abort()
        else:
            self._file.abort()

    def __enter__(self):
        return self

    def __exit__(self, kind, value, tb):
        if kind is None:
            self.close()
        else:
            self.abort()


def format_rows(columns, engine=None):
    """CSV bytes of equal-length float columns, no header, each value the shortest
    decimal that reads back exactly, as Python's ``repr`` writes it: with pihyst's C
    writer (:mod:`pihyst.io._fastcsv`, built with the package), else (or with
    ``engine="numpy"``, its plain twin) ``repr`` itself; ``engine="pyarrow"`` uses
    pyarrow's writer (the same numbers, written ``1`` rather than ``1.0``)."""
    if engine == "pyarrow":
        import pyarrow as pa
        import pyarrow.csv as pcsv
        out = _io.BytesIO()
        table = pa.table({f"c{j}": c for j, c in enumerate(columns)})
        pcsv.write_csv(table, out, pcsv.WriteOptions(include_header=False))
        return out.getvalue()
    from pihyst.io._text_engines import _fast
    fast = _fast() if engine != "numpy" else None
    if fast is not None:
        return fast.format_rows(columns)
    line = ",".join(["%r"] * len(columns)) + "\n"
    flat = np.column_stack(columns).ravel().tolist()
    return ((line * len(columns[0])) % tuple(flat)).encode("ascii")


def write_columns(path, columns, comments=(), metadata=None):
    """Write named columns (dict name -> array) to ``path``, complete or not at all
    (``comments`` and ``metadata`` in its sidecar ``PATH.json``)."""
    with ColumnWriter(path, list(columns), comments, metadata=metadata) as w:
        w.write(columns)




def sidecar_path(path):
    """The sidecar of a CSV file pihyst writes: ``out.csv`` -> ``out.csv.json``."""
    return os.fspath(path) + ".json"


def write_sidecar(path, names, rows, comments=(), metadata=None):
    """The metadata of the CSV file ``path`` (its columns, rows, what wrote it) as JSON
    beside it; nothing for a device or FIFO (a stream has no place beside it) or when
    there is nothing to say."""
    if not (comments or metadata):
        return
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return
    except OSError:
        return
    from pihyst._atomic import write_atomically
    data = described(path, names, rows, comments, metadata)
    write_atomically(sidecar_path(path), json.dumps(data, indent=1, default=str) + "\n")


def described(path, names, rows, comments=(), metadata=None):
    """The metadata pihyst keeps with a record it writes (in a CSV's sidecar, a Parquet
    schema's or an HDF5 file's ``pihyst`` key): what wrote it, its columns and rows."""
    from pihyst._version import __version__
    return {"format": SIDECAR_FORMAT, "pihyst_version": __version__,
            "file": os.path.basename(os.fspath(path)), "columns": list(names),
            "rows": int(rows), "comments": list(comments), **(metadata or {})}


def read_sidecar(path):
    """The sidecar of ``path`` as a dict when there is one that pihyst wrote for this
    very file, else None (a sidecar that is not JSON, or for another file, is ignored:
    it is metadata, not data)."""
    side = sidecar_path(path)
    try:
        with open(side, encoding="utf-8") as f:
            data = json.load(f)
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("format") != SIDECAR_FORMAT \
            or data.get("file") != os.path.basename(os.fspath(path)):
        return None
    return data


def column_number(path, name):
    """1-based position of column ``name`` in the header of ``path``, 0 if absent
    (for error messages that name a column)."""
    try:
        columns = TextSource(path).columns
    except CSVError:
        return 0
    return columns.index(name) + 1 if name in columns else 0
