"""CSV files of docs/interfaces.md, written fast and atomically, and the former reader
interface :func:`read_columns` (now a thin layer over :mod:`pihyst.io._records`).

Errors are :class:`CSVError` with a one-line message ``FILE:LINE:COLUMN: what is wrong``
(line and column 1-based; column counts fields).
"""

import io as _io
import json
import os
import stat
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

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


def read_columns(path: str | os.PathLike[str], names: Sequence[str],
                 optional: Sequence[str] = ()) -> tuple[dict[str, NDArray[np.float64]],
                                                        NDArray[np.int_]]:
    """Read named columns of a delimited text file as float arrays.

    Every value must be a finite number; the file must have at least one data row.

    Parameters
    ----------
    path : str or os.PathLike
        The delimited text file, with a header line naming its columns.
    names : sequence of str
        The columns that must be there.
    optional : sequence of str
        Columns read when the header has them.

    Returns
    -------
    columns : dict of str to ndarray
        Every column of ``names`` and those of ``optional`` found, by name.
    lines : ndarray of int
        The 1-based file line of each data row.

    Raises
    ------
    CSVError
        A missing or repeated column, or a value that is not a finite number, with the
        file, line and column.

    Examples
    --------
    >>> import os, tempfile
    >>> from pihyst.io import read_columns
    >>> path = os.path.join(tempfile.mkdtemp(), "loop.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("voltage_V,displacement_um\\n0,0.5\\n10,1.5\\n")
    >>> columns, lines = read_columns(path, ["voltage_V"], optional=["displacement_um"])
    >>> columns["displacement_um"].tolist(), lines.tolist()
    ([0.5, 1.5], [2, 3])
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
    complete; pihyst's reader reads it back into the record's metadata.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write (``.csv``, or ``.parquet``, ``.h5``, ``.hdf5``).
    names : sequence of str
        The columns, in order.
    comments : sequence of str
        Lines that say what wrote the file, kept in its metadata.
    engine : str or None
        The number formatter (None: the fastest available).
    metadata : dict or None
        More metadata kept with the file.

    Examples
    --------
    >>> import os, tempfile
    >>> import numpy as np
    >>> from pathlib import Path
    >>> from pihyst.io import ColumnWriter
    >>> path = os.path.join(tempfile.mkdtemp(), "out.csv")
    >>> with ColumnWriter(path, ["voltage_V", "displacement_um"]) as w:
    ...     w.write({"voltage_V": np.array([0.0, 1.5]), "displacement_um": np.array([0.0, 0.25])})
    >>> print(Path(path).read_text(), end="")
    voltage_V,displacement_um
    0.0,0.0
    1.5,0.25
    """

    def __init__(self, path: str | os.PathLike[str], names: Sequence[str],
                 comments: Sequence[str] = (), engine: str | None = None,
                 metadata: dict[str, Any] | None = None) -> None:
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
            # a ParquetSink or HDF5Sink: write, commit, abort
            self._sink: Any = SINKS[self.format](self.path, self.names, self._described())
            self._file: Any = None     # an AtomicFile for CSV
            return
        self._sink = None
        self._file = AtomicFile(self.path)
        head = ",".join(self.names) + "\n"
        try:
            self._file.write(head.encode("utf-8"))
        except BaseException:
            self._file.abort()        # no caller holds this writer yet to abort it
            raise

    def write(self, columns: Mapping[str, ArrayLike]) -> None:
        """Append rows.

        Parameters
        ----------
        columns : mapping of str to array_like
            Every name of the header, each with the same number of values.

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.io import ColumnWriter
        >>> w = ColumnWriter(os.path.join(tempfile.mkdtemp(), "out.csv"), ["x"])
        >>> w.write({"x": [1.0, 2.0]})
        >>> w.rows
        2
        >>> w.abort()
        """
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

    def close(self) -> None:
        """Put the complete file in place (and its sidecar ``PATH.json``, if any).

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.io import ColumnWriter
        >>> path = os.path.join(tempfile.mkdtemp(), "out.csv")
        >>> w = ColumnWriter(path, ["x"])
        >>> w.write({"x": [1.0]})
        >>> os.path.exists(path)
        False
        >>> w.close()
        >>> os.path.exists(path)
        True
        """
        if self._sink is not None:
            self._sink.commit(self._described())
            return
        self._file.commit()
        write_sidecar(self.path, self.names, self.rows, self.comments, self.metadata)

    def abort(self) -> None:
        """Give the file up: nothing is left where it was to be.

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.io import ColumnWriter
        >>> path = os.path.join(tempfile.mkdtemp(), "out.csv")
        >>> w = ColumnWriter(path, ["x"])
        >>> w.write({"x": [1.0]})
        >>> w.abort()
        >>> os.path.exists(path)
        False
        """
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


def write_columns(path: str | os.PathLike[str], columns: Mapping[str, ArrayLike],
                  comments: Sequence[str] = (), metadata: dict[str, Any] | None = None) -> None:
    """Write named columns to ``path``, complete or not at all (:class:`ColumnWriter`).

    Parameters
    ----------
    path : str or os.PathLike
        The file to write (``.csv``, or ``.parquet``, ``.h5``, ``.hdf5``).
    columns : mapping of str to array_like
        The columns by name, each with the same number of values.
    comments : sequence of str
        Lines that say what wrote the file, in its sidecar ``PATH.json``.
    metadata : dict or None
        More metadata for the sidecar.

    Examples
    --------
    >>> import os, tempfile
    >>> from pathlib import Path
    >>> from pihyst.io import write_columns
    >>> path = os.path.join(tempfile.mkdtemp(), "out.csv")
    >>> write_columns(path, {"t": [0.0, 0.5], "y": [1.0, 2.0]})
    >>> print(Path(path).read_text(), end="")
    t,y
    0.0,1.0
    0.5,2.0
    """
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


def column_number(path: str | os.PathLike[str], name: str) -> int:
    """1-based position of column ``name`` in the header of ``path``, 0 if absent
    (for error messages that name a column).

    Parameters
    ----------
    path : str or os.PathLike
        A delimited text file with a header line.
    name : str
        The column's name.

    Returns
    -------
    int
        Its 1-based position, or 0 when the header has no such column (or the file no
        header).

    Examples
    --------
    >>> import os, tempfile
    >>> from pihyst.io import column_number
    >>> path = os.path.join(tempfile.mkdtemp(), "loop.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("time_s,voltage_V\\n0,1\\n")
    >>> column_number(path, "voltage_V"), column_number(path, "current_A")
    (2, 0)
    """
    try:
        columns = TextSource(path).columns
    except CSVError:
        return 0
    return columns.index(name) + 1 if name in columns else 0
