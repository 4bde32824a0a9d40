"""Records as they come: one reader for delimited text and array files, with the columns,
units, sensor lag and start a user names; block by block for records larger than memory.

:func:`read_record` returns one :class:`Record`; :func:`open_record` returns a
:class:`RecordReader` whose :meth:`~RecordReader.chunks` yields the same samples as
consecutive :class:`Record` blocks (bit for bit the same values). docs/records.md.
"""

import importlib
import importlib.util
import os
import re
import shlex
import sys
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pihyst.exceptions import CSVError, InvalidArgumentError, PihystWarning, RecordError
from pihyst.io._array_sources import ArraySource, function_source, open_array_source
from pihyst.io._inputs import kind_of
from pihyst.io._lab_formats import GUESSES, TableSource, open_lab_source
from pihyst.io._text_source import TextSource
from pihyst.model._units import display_unit

QUANTITIES = ("voltage", "displacement", "time")
DEFAULT_NAMES = {"voltage": "voltage_V", "displacement": "displacement_um", "time": "time_s"}
UNIT_FACTORS = {"m": 1e6, "mm": 1e3, "um": 1.0, "µm": 1.0, "nm": 1e-3}
_UNIT_IN_NAME = re.compile(r"(?:[_ \[(]|^)(m|mm|um|µm|nm)[\])]?\s*$")
# a time or voltage column named in another unit (time_ms, 'U [kV]') is converted too
TIME_FACTORS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "ns": 1e-9, "min": 60.0,
                "sec": 1.0}
VOLTAGE_FACTORS = {"v": 1.0, "mv": 1e-3, "kv": 1e3}
_TIME_UNIT_IN_NAME = re.compile(r"(?:[_ \[(]|^)(s|ms|us|µs|ns|min|sec)[\])]?\s*$",
                                re.IGNORECASE)
# a column whose name says it holds time (a time column not used is named in a warning)
_TIME_LIKE = re.compile(r"^(time|zeit|t|timestamp|x_value|elapsed)(?:\b|[_ \[(])",
                        re.IGNORECASE)
_VOLTAGE_UNIT_IN_NAME = re.compile(r"(?:[_ \[(]|^)(v|mv|kv)[\])]?\s*$", re.IGNORECASE)
EXTENSIONS = {".npy": "npy", ".npz": "npz", ".mat": "mat", ".h5": "hdf5", ".hdf5": "hdf5",
              ".he5": "hdf5", ".parquet": "parquet", ".pq": "parquet"}
# lab software's formats, read whole (pihyst.io._lab_formats)
LAB_EXTENSIONS = {".lvm": "lvm", ".tdms": "tdms", ".xlsx": "xlsx", ".xlsm": "xlsx"}
BLOCK_ROWS = 1 << 20


@dataclass(frozen=True, eq=False)
class Record:
    """Samples of a record, as :func:`read_record` and :meth:`RecordReader.chunks` return
    them.

    Parameters
    ----------
    voltage : ndarray or None
        The actuator's voltage (V).
    displacement : ndarray or None
        The displacement (µm).
    time : ndarray or None
        The sample times (s).
    source : str
        The file the samples come from.
    metadata : dict
        What was found and applied (format, columns, units, lag, skipped samples).
    start : int
        The index of the first sample in the whole record (0 unless this is a block of
        a longer one).
    reader : RecordReader or None
        The reader it comes from, which locates a sample in the file for
        :meth:`error`.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.io import Record
    >>> rec = Record(voltage=np.array([0.0, 5.0]), displacement=np.array([0.1, 1.2]))
    >>> len(rec), rec.time is None
    (2, True)
    """

    voltage: np.ndarray | None = None
    displacement: np.ndarray | None = None
    time: np.ndarray | None = None
    source: str = ""
    metadata: dict[str, Any] = field(default_factory=dict)
    start: int = 0
    reader: Any = field(default=None, repr=False)

    def __len__(self) -> int:
        for a in (self.voltage, self.displacement, self.time):
            if a is not None:
                return len(a)
        return 0

    def error(self, index: int, quantity: str, message: str) -> RecordError:
        """A :class:`RecordError` naming the file, line and column (or variable and
        sample) of sample ``index`` of this record: for messages about the values.

        Parameters
        ----------
        index : int
            The sample, 0-based within this record (or block).
        quantity : str
            ``"voltage"``, ``"displacement"`` or ``"time"``.
        message : str
            What is wrong with it.

        Returns
        -------
        RecordError
            The error, to raise.

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.io import open_record
        >>> path = os.path.join(tempfile.mkdtemp(), "loop.csv")
        >>> with open(path, "w") as f:
        ...     _ = f.write("time_s,voltage_V,displacement_um\\n0,0,0\\n0.1,5,1.2\\n0.2,10,2.6\\n")
        >>> rec = open_record(path).read()
        >>> print(str(rec.error(2, "voltage", "above the limit")).replace(path, "PATH"))
        PATH:4:2: above the limit
        """
        if self.reader is None:
            return RecordError(self.source or "record", f"{quantity} sample "
                               f"{self.start + index}: {message}")
        return self.reader.error(self.start + index, quantity, message)


class RecordReader:
    """An opened record with its reading options. Use :meth:`read` for all samples, or
    :meth:`chunks` for blocks; :meth:`error` locates a sample for a message.

    Parameters
    ----------
    path : str or os.PathLike
        Delimited text (any separator, header or not), ``.npy``, ``.npz``, ``.mat``,
        ``.h5``/``.hdf5``, ``.parquet``, ``.lvm``, ``.tdms``, ``.xlsx``; or anything, with
        ``reader``.
    voltage, displacement, time : str, int or None
        The column (name or 1-based number; in array files a variable, ``NAME:K`` or
        ``K``); None: found by name. ``time="none"`` ignores a time column.
    rate : float or None
        Sample rate (Hz), for a record without a time column.
    displacement_unit : str or None
        m, mm, um or nm (default: from the column name, else um).
    voltage_gain : float or None
        The voltage column times this is the actuator's voltage (default 1).
    displacement_gain : float or None
        The displacement column (in its unit) times this is the displacement (default 1;
        -1 for a sensor that counts the other way, such as a distance to the target).
    lag : int
        The sensor answers this many samples late: displacement[k + lag] goes with
        voltage[k].
    skip_until : float or None
        Drop the samples before this time (s).
    separator : str or None
        Text: the field separator, when not found right.
    decimal_comma : bool or None
        Text: numbers written with a decimal comma (None: detected).
    reader : callable, str or None
        A function, ``module:function`` or ``file.py:function`` called with ``path``,
        returning a dict of arrays ``voltage``, ``displacement``, ``time`` and
        ``metadata``.
    sheet : str or None
        Spreadsheets: the sheet to read (default: the first).
    units_row : bool or None
        Text: True, the line under the header holds the units; False, there is none;
        None: detected.
    need : str or sequence of str
        The quantities that must be there.
    optional : str or sequence of str
        The quantities read when there.

    Raises
    ------
    RecordError
        A file that cannot be read or lacks a needed column (:class:`CSVError` for text,
        with file, line and column).
    InvalidArgumentError
        Options that are not valid.

    Examples
    --------
    >>> import os, tempfile
    >>> from pihyst.io import open_record
    >>> path = os.path.join(tempfile.mkdtemp(), "loop.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("time_s,voltage_V,displacement_um\\n0,0,0\\n0.1,5,1.2\\n0.2,10,2.6\\n")
    >>> with open_record(path, need="voltage") as reader:
    ...     reader.read().voltage.tolist()
    [0.0, 5.0, 10.0]
    """

    def __init__(self, path: str | os.PathLike[str], *, voltage: str | int | None = None,
                 displacement: str | int | None = None, time: str | int | None = None,
                 rate: float | None = None, displacement_unit: str | None = None,
                 voltage_gain: float | None = None,
                 displacement_gain: float | None = None, lag: int = 0,
                 skip_until: float | None = None, separator: str | None = None,
                 decimal_comma: bool | None = None, reader: Any = None,
                 sheet: str | None = None, units_row: bool | None = None,
                 need: str | Sequence[str] = ("voltage", "displacement"),
                 optional: str | Sequence[str] = ("time",)) -> None:
        self.path = os.fspath(path)
        # one quantity may be named alone (need="time"), not spelt out letter by letter
        self.need = (need,) if isinstance(need, str) else tuple(need)
        optional = (optional,) if isinstance(optional, str) else tuple(optional)
        self.optional = optional + (("time",) if skip_until is not None else ())
        unknown = set(self.need) - set(QUANTITIES)
        if unknown:
            raise InvalidArgumentError(f"unknown quantities {sorted(unknown)}")
        self.source = _open_source(self.path, reader, separator, decimal_comma, sheet,
                                   units_row)
        found = dict(self.source.extra.get("found", {}) if isinstance(self.source, ArraySource)
                     else getattr(self.source, "found", {}))
        self.rate_why = "--rate" if rate is not None else found.pop(
            "rate_why", "the reader's metadata 'rate'")
        self.rate = (_positive(rate, "--rate") if rate is not None else
                     _positive(found.get("rate"), "the reader's metadata 'rate'"))
        self.why: dict[str, str] = {}       # quantity -> why its column was taken
        self.warnings: list[str] = []       # what the user should know: said, never silent
        self.notes = list(getattr(self.source, "notes", ()))
        specs = {"voltage": voltage, "displacement": displacement, "time": time}
        # --time none: the user said the time column is not to be used
        self.time_none = time is not None and str(time).strip().lower() == "none"
        if rate is None and self.rate is not None and time is None:
            # the file's sample period gives the time only if it has no time column
            self.refs = self._resolve(specs)
            if "time" in self.refs:
                self.notes.append(f"time from {self.labels_of('time')}, not from "
                                  f"{self.rate_why}")
                self.rate = None
        else:
            self.refs = self._resolve(specs)
        if not self.refs:
            # the time a rate defines needs a column to count the samples of
            optional = sorted(set(self.optional) - set(self.need))
            raise InvalidArgumentError(
                f"no column to read: need={self.need!r}"
                + (f", and the optional {', '.join(DEFAULT_NAMES[q] for q in optional)} is "
                   f"not in the record" if optional else "")
                + ("; the rate gives the time, but it needs a column to count the samples"
                   if self.rate is not None else "")
                + ": name the quantities to read in need (voltage, displacement, time)")
        self.labels = {q: self._label(r) for q, r in self.refs.items()}
        self._unused_time_columns()
        self.voltage_gain = (
            _finite(voltage_gain, "--voltage-gain") if voltage_gain is not None else
            _finite(found.get("voltage_gain", 1.0), "the reader's metadata 'voltage_gain'"))
        if self.voltage_gain == 0:
            raise InvalidArgumentError("--voltage-gain must not be 0")
        self.displacement_gain = (
            _finite(displacement_gain, "--displacement-gain")
            if displacement_gain is not None else
            _finite(found.get("displacement_gain", 1.0),
                    "the reader's metadata 'displacement_gain'"))
        if self.displacement_gain == 0:
            raise InvalidArgumentError("--displacement-gain must not be 0")
        self.unit, self.unit_from = self._unit(displacement_unit, found)
        self.named_units = {q: self._unit_in_name(q, pattern, factors) for q, pattern, factors
                            in (("time", _TIME_UNIT_IN_NAME, TIME_FACTORS),
                                ("voltage", _VOLTAGE_UNIT_IN_NAME, VOLTAGE_FACTORS))}
        if not (isinstance(lag, (int, np.integer)) and lag >= 0):
            raise InvalidArgumentError(f"--lag must be a whole number of samples >= 0, got "
                                       f"{lag!r}")
        both = "voltage" in self.refs and "displacement" in self.refs
        self.lag = int(lag) if both else 0
        self.skip_until = None if skip_until is None else _finite(skip_until, "--skip-until")
        if self.skip_until is not None and "time" not in self.refs and self.rate is None:
            raise InvalidArgumentError(f"--skip-until needs a time column in {self.path} or "
                                       f"--rate")
        if "time" in self.refs and self.rate is not None:
            raise InvalidArgumentError(f"--rate is for records without a time column; this one "
                                       f"has time in {self.labels['time']} (use --time none to "
                                       f"ignore it)")
        self.skipped = 0
        self.n_samples: int | None = None
        for message in self.warnings:
            warnings.warn(message, PihystWarning, stacklevel=3)

    # ---------------------------------------------------------------- columns
    def labels_of(self, quantity: str) -> str:
        """Where ``quantity`` is read from, as the messages name it.

        Parameters
        ----------
        quantity : str
            ``"voltage"``, ``"displacement"`` or ``"time"``, one the record is read with.

        Returns
        -------
        str
            Its column (name and number) or variable.

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.io import open_record
        >>> path = os.path.join(tempfile.mkdtemp(), "loop.csv")
        >>> with open(path, "w") as f:
        ...     _ = f.write("time_s,voltage_V,displacement_um\\n0,0,0\\n0.1,5,1.2\\n0.2,10,2.6\\n")
        >>> open_record(path).labels_of("displacement")
        "column 3 'displacement_um'"
        """
        return self._label(self.refs[quantity])

    def _names(self):
        """The names of the columns (or variables) of the record, with their refs."""
        src = self.source
        if isinstance(src, TextSource):
            return [(n, i) for i, n in enumerate(src.columns)]
        if isinstance(src, ArraySource):
            return [(n, (n, None)) for n, a in src.variables.items() if len(a.shape) == 1]
        return []

    def _unused_time_columns(self):
        """A warning for each column named like a time that the record is read without,
        when the command reads the time."""
        if "time" not in self.need and "time" not in self.optional or self.time_none:
            return
        used = self.refs.get("time")
        for name, ref in self._names():
            if ref == used or ref in self.refs.values():
                continue
            if _TIME_LIKE.search(name):
                now = (f"the time is {self.labels['time']}" if used is not None else
                       f"the time is k / {self.rate:g} Hz ({self.rate_why})"
                       if self.rate is not None else "the record is read without time")
                self.warnings.append(f"{self.path}: column {name!r} looks like a time but "
                                     f"is not used ({now}); name it with --time "
                                     f"{name!r} to use it")

    def _resolve(self, specs):
        refs = {}
        for q in QUANTITIES:
            spec = specs[q]
            # a rate gives the time: the time column is looked for only to refuse both
            needed = q in self.need and not (q == "time" and self.rate is not None)
            if spec is not None and str(spec).strip().lower() == "none":
                if needed:
                    raise InvalidArgumentError(f"--{q} none: this command needs the {q}"
                                               + (" (or --rate HZ)" if q == "time" else ""))
                continue
            if q not in self.need and spec is None and q not in self.optional:
                continue
            if spec is not None:
                self.why[q] = f"--{q}"
            ref = self._ref(q, spec, needed)
            if ref is not None:
                refs[q] = ref
        seen = {}
        for q, ref in refs.items():
            if ref in seen:
                raise RecordError(self.path, f"the {seen[ref]} and the {q} are both read "
                                             f"from {self._label(ref)}")
            seen[ref] = q
        return refs

    def _ref(self, quantity, spec, needed):
        src = self.source
        if isinstance(src, ArraySource):
            if spec is not None:
                return src.resolve(spec, quantity)
            ref = src.default([DEFAULT_NAMES[quantity], quantity])
            if ref is None and isinstance(src, TableSource):
                guessed = self._unit_guess(quantity) or src.guess(quantity)
                if guessed is not None:
                    ref, self.why[quantity] = guessed
            if ref is None and needed:
                raise RecordError(self.path, f"no {DEFAULT_NAMES[quantity]!r} for the "
                                  f"{quantity}: name it with --{quantity} NAME, NAME:K or K"
                                  + (" (or give the sample rate, --rate HZ)"
                                     if quantity == "time" else "")
                                  + f" ({src.inventory()})")
            return ref
        if spec is None and src.columns and DEFAULT_NAMES[quantity] not in src.columns:
            guessed = self._text_guess(quantity)
            if guessed is not None:
                return guessed
        return _text_column(src, quantity, spec, needed)

    def _text_guess(self, quantity):
        """The column of a text record without the default name that its header names
        as ``quantity``: a time column in another unit (``time_ms``, ``t [us]``); for
        the columns a PI data recorder names, the voltage and displacement too."""
        names = self.source.columns
        by_unit = self._unit_guess(quantity)
        if by_unit is not None:
            ref, self.why[quantity] = by_unit
            return ref
        if quantity == "time":
            hits = [i for i, n in enumerate(names) if _TIME_LIKE.search(n)]
            why = "its name"
        elif getattr(self.source, "gcs_names", False):
            hits = [i for i, n in enumerate(names) if GUESSES[quantity].search(n)
                    and not _TIME_LIKE.search(n)
                    and not (quantity == "displacement" and GUESSES["voltage"].search(n))]
            if len(hits) > 1:
                from pihyst.io._lab_formats import PREFERRED
                preferred = [i for i in hits if PREFERRED.search(names[i])]
                if len(preferred) != 1:
                    raise RecordError(self.path, f"several columns may hold the "
                                   f"{quantity} ({', '.join(repr(names[i]) for i in hits)}):"
                                   f" name one with --{quantity} NAME or NUMBER")
                hits = preferred
            why = "guessed from its NAME in the header"
        else:
            return None
        if len(hits) == 1:
            self.why[quantity] = why
            return hits[0]
        return None

    def _label(self, ref):
        if isinstance(self.source, ArraySource):
            return self.source.label(ref)
        name = self.source.columns[ref] if self.source.columns else None
        return f"column {ref + 1}" + (f" {name!r}" if name else "")

    def _column_name(self, quantity):
        """The name of the column (or array variable) ``quantity`` is read from, if any."""
        ref = self.refs.get(quantity)
        names = self.source.columns if isinstance(self.source, TextSource) else ()
        return names[ref] if isinstance(ref, int) and names else (
            ref[0] if isinstance(ref, tuple) else None)

    def _unit_guess(self, quantity):
        """(ref, why) of the one column whose unit in the file (a units row, a channel's
        unit) is a unit of ``quantity``, else None."""
        units = getattr(self.source, "units", None) or {}
        factors = {"time": TIME_FACTORS, "voltage": VOLTAGE_FACTORS,
                   "displacement": UNIT_FACTORS}[quantity]
        hits = [(key, unit) for key, unit in units.items()
                if unit.replace("μ", "µ").lower().replace("µ", "u") in
                {k.replace("µ", "u").lower() for k in factors}]
        if len(hits) != 1:
            return None
        key, unit = hits[0]
        ref = key if isinstance(self.source, TextSource) else (key, None)
        return ref, f"its unit {unit!r} in the file"

    def _file_unit(self, quantity):
        """The unit the file gives the column of ``quantity`` (a units row, a channel's
        unit label), else None."""
        ref = self.refs.get(quantity)
        units = getattr(self.source, "units", None)
        if ref is None or not units:
            return None
        key = ref if isinstance(self.source, TextSource) else ref[0]
        return units.get(key)

    def _unit_in_name(self, quantity, pattern, factors):
        """(unit, factor to s or V, where) of a time or voltage column whose name or the
        file's unit for it gives a unit other than s or V (``time_ms``, ``U [kV]``, a
        units row), else None."""
        name = self._column_name(quantity)
        m = pattern.search(name or "")
        where = f"column name {name!r}"
        if m is None:
            unit = self._file_unit(quantity)
            if unit is None:
                return None
            key = unit.lower().replace("µ", "u").replace("μ", "u")
            if key not in factors:
                if quantity in self.refs:
                    raise RecordError(self.path, f"{self.labels_of(quantity)}: unit {unit!r} "
                                      f"(from the file) is not a {quantity} unit "
                                      f"({', '.join(sorted(factors))})")
                return None
            factor = factors[key]
            return None if factor == 1.0 else (unit, factor, f"the file's unit {unit!r}")
        unit = m.group(1)
        factor = factors[unit.lower().replace("µ", "u")]
        return None if factor == 1.0 else (unit, factor, where)

    def _unit(self, given, found):
        if given is not None:
            unit, where = given, "option"
        elif found.get("displacement_unit"):
            unit, where = found["displacement_unit"], "reader"
        else:
            unit, where = "um", "default"
            name = self._column_name("displacement")
            m = _UNIT_IN_NAME.search(name or "")
            if m:
                unit, where = m.group(1), f"column name {name!r}"
            elif self._file_unit("displacement") is not None:
                given = self._file_unit("displacement")
                unit = given.strip().replace("μ", "µ").lower()
                where = f"the file's unit {given!r}"
                if unit not in UNIT_FACTORS:
                    raise RecordError(self.path, f"{self.labels_of('displacement')}: unit "
                                      f"{given!r} (from the file) is not a length unit "
                                      "(m, mm, um, nm); give --displacement-unit")
        unit = "um" if unit == "µm" else unit
        if unit not in UNIT_FACTORS:
            option = ("the reader's metadata 'displacement_unit'" if where == "reader"
                      else "--displacement-unit")
            raise InvalidArgumentError(f"{option} must be one of m, mm, um, nm; got {unit!r}")
        return unit, where

    # ---------------------------------------------------------------- reading
    def _raw_blocks(self, block_rows, progress):
        order = list(self.refs)
        if isinstance(self.source, TextSource):
            blocks = self.source.blocks([self.refs[q] for q in order], progress)
        else:
            blocks = self.source.blocks([self.refs[q] for q in order], block_rows, progress)
        for values in blocks:
            yield {q: values[:, j] for j, q in enumerate(order)}

    def chunks(self, block_rows: int | None = None,
               progress: Callable[[int, int], object] | None = None) -> Iterator[Record]:
        """The record as consecutive :class:`Record` blocks (about ``block_rows`` samples
        each for array files; text files are read in blocks of bytes).

        Parameters
        ----------
        block_rows : int or None
            Samples per block of an array file (default 2**20).
        progress : callable or None
            ``progress(done, total)``, called after each block.

        Yields
        ------
        Record
            The next block, its ``start`` the index of its first sample.

        Raises
        ------
        RecordError
            No samples left after the lag and the skipped start, or bad data (with its
            file, line and column).

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.io import open_record
        >>> path = os.path.join(tempfile.mkdtemp(), "loop.csv")
        >>> with open(path, "w") as f:
        ...     _ = f.write("time_s,voltage_V,displacement_um\\n0,0,0\\n0.1,5,1.2\\n0.2,10,2.6\\n")
        >>> [(block.start, len(block)) for block in open_record(path).chunks()]
        [(0, 3)]
        """
        transform = _Transform(self)
        start = 0
        for raw in self._raw_blocks(block_rows or BLOCK_ROWS, progress):
            out = transform.feed(raw)
            # kept current while streaming: error() locates a sample of a block through it
            self.skipped = transform.skipped
            n = max((len(a) for a in out.values() if a is not None), default=0)
            if n:
                yield Record(**out, source=self.path, metadata=self.metadata(), start=start,
                             reader=self)
                start += n
        self.skipped = transform.skipped
        self.n_samples = start
        if start == 0:
            raise RecordError(self.path, "no samples left"
                              + (f" after --skip-until {self.skip_until:g} s"
                                 if self.skip_until is not None else "")
                              + (f" after --lag {self.lag}" if self.lag else ""))

    def read(self, progress: Callable[[int, int], object] | None = None) -> Record:
        """All samples as one :class:`Record`, gathered into arrays sized from the part
        of the file read so far (so that the record is held about once, not twice).

        Parameters
        ----------
        progress : callable or None
            ``progress(done, total)``, called after each block read.

        Returns
        -------
        Record
            Every sample.

        Raises
        ------
        RecordError
            No samples left after the lag and the skipped start, or bad data (with its
            file, line and column).

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.io import open_record
        >>> path = os.path.join(tempfile.mkdtemp(), "loop.csv")
        >>> with open(path, "w") as f:
        ...     _ = f.write("time_s,voltage_V,displacement_um\\n0,0,0\\n0.1,5,1.2\\n0.2,10,2.6\\n")
        >>> open_record(path, lag=1).read().displacement.tolist()
        [1.2, 2.6]
        """
        seen = [0, 0]

        def track(done, total):
            seen[:] = done, total
            if progress is not None:
                progress(done, total)
        gathered: dict[str, np.ndarray] = {}
        n = 0
        for rec in self.chunks(progress=track):
            k = len(rec)
            for q in QUANTITIES:
                a = getattr(rec, q)
                if a is None:
                    continue
                buf = gathered.get(q)
                if buf is None or n + k > buf.size:
                    done, total = seen
                    expected = int((n + k) * total / done * 1.02) + 1 if done else 0
                    grown = np.empty(max(expected, int((n + k) * 1.25) + 1))
                    if buf is not None:
                        grown[:n] = buf[:n]
                    buf = gathered[q] = grown
                buf[n:n + k] = a
            n += k
        joined: dict[str, np.ndarray | None] = {q: None for q in QUANTITIES}
        for q, buf in gathered.items():
            buf.resize(n, refcheck=False)   # in place: nothing else refers to it
            joined[q] = buf
        return Record(**joined, source=self.path, metadata=self.metadata(), start=0,
                      reader=self)

    # ---------------------------------------------------------------- describing
    def metadata(self) -> dict[str, Any]:
        """What was found and applied: format, columns and why, units, rate, lag,
        skipped samples, warnings.

        Returns
        -------
        dict
            JSON-ready values, as written in the outputs' metadata.

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.io import open_record
        >>> path = os.path.join(tempfile.mkdtemp(), "loop.csv")
        >>> with open(path, "w") as f:
        ...     _ = f.write("time_s,voltage_V,displacement_um\\n0,0,0\\n0.1,5,1.2\\n0.2,10,2.6\\n")
        >>> open_record(path).metadata()["columns"]["voltage"]
        "column 2 'voltage_V'"
        """
        meta = {"file": self.path, **{k: v for k, v in self.source.metadata().items()
                                      if not k.startswith("_")}}
        if isinstance(self.source, TextSource) and self._sidecar() is not None:
            meta["sidecar"] = self._sidecar()
            meta["pihyst_metadata"] = self._sidecar()   # as for Parquet and HDF5
        meta["columns"] = dict(self.labels)
        if self.why:
            meta["columns_why"] = dict(self.why)
        if self.warnings:
            meta["warnings"] = list(self.warnings)
        meta["displacement_unit"] = self.unit
        for q in ("voltage", "time"):
            if self.named_units.get(q) is not None:
                meta[f"{q}_unit"] = self.named_units[q][0]
        if self.voltage_gain != 1.0:
            meta["voltage_gain"] = self.voltage_gain
        if self.displacement_gain != 1.0:
            meta["displacement_gain"] = self.displacement_gain
        if self.rate is not None:
            meta["rate_hz"] = self.rate
        if self.lag:
            meta["lag_samples"] = self.lag
        if self.skip_until is not None:
            meta["skip_until_s"] = self.skip_until
            meta["skipped_samples"] = self.skipped
        if self.n_samples is not None:
            meta["samples"] = self.n_samples
        if getattr(self.source, "skipped_ticks", None):
            meta["skipped_ticks"] = self.source.skipped_ticks
        return meta

    def _sidecar(self):
        if not hasattr(self, "_sidecar_data"):
            from pihyst.io._csv import read_sidecar, sidecar_path
            data = read_sidecar(self.path)
            self._sidecar_data = data
            self._sidecar_name = sidecar_path(self.path)
        return self._sidecar_data

    def describe(self) -> str:
        """One line for the user: what was read from where.

        Returns
        -------
        str
            The file, its layout, the columns read and what was applied to them.

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.io import open_record
        >>> path = os.path.join(tempfile.mkdtemp(), "loop.csv")
        >>> with open(path, "w") as f:
        ...     _ = f.write("time_s,voltage_V,displacement_um\\n0,0,0\\n0.1,5,1.2\\n0.2,10,2.6\\n")
        >>> line = open_record(path, displacement_unit="nm").describe()
        >>> print(line.replace(path, "PATH"))
        read PATH: ...
        """
        parts = [f"{q} {self.labels[q]}" + (f" ({self.why[q]})" if q in self.why else "")
                 for q in QUANTITIES if q in self.labels]
        notes = []
        if "displacement" in self.refs and self.unit != "um":
            notes.append(f"displacement in {display_unit(self.unit)} ({self.unit_from}) -> µm")
        for q, base in (("voltage", "V"), ("time", "s")):
            named = self.named_units.get(q)
            if named is not None:
                notes.append(f"{q} in {named[0]} ({named[2]}) -> {base}")
        if self.voltage_gain != 1.0 and "voltage" in self.refs:
            notes.append(f"voltage x {self.voltage_gain:g}")
        if self.displacement_gain != 1.0 and "displacement" in self.refs:
            notes.append(f"displacement x {self.displacement_gain:g}")
        if self.rate is not None:
            notes.append(f"{self.rate:g} Hz" + ("" if self.rate_why == "--rate"
                                                 else f" ({self.rate_why})"))
        notes.extend(self.notes)
        if getattr(self.source, "skipped_ticks", None):
            notes.append(f"{self.source.skipped_ticks} ticks without a valid reading "
                         "skipped (see sensor_status, supply_status)")
        if isinstance(self.source, TextSource) and self._sidecar() is not None:
            notes.append(f"metadata from {os.path.basename(self._sidecar_name)}")
        elif isinstance(self.source, ArraySource) and "pihyst_metadata" in self.source.extra:
            where = "key-value metadata" if self.source.kind == "parquet" else "attributes"
            notes.append(f"metadata from its {where} (written by pihyst)")
        if self.lag:
            notes.append(f"displacement {self.lag} sample(s) later")
        if self.skip_until is not None:
            notes.append(f"{self.skipped} samples before {self.skip_until:g} s skipped")
        layout = self.source.metadata().get("layout", self.source.metadata()["format"])
        n = "" if self.n_samples is None else f"{self.n_samples} samples, "
        return (f"read {self.path}: {n}{layout}; " + ", ".join(parts)
                + ("; " + ", ".join(notes) if notes else ""))

    def error(self, index: int, quantity: str, message: str) -> RecordError:
        """A :class:`RecordError` at sample ``index`` (0-based, after lag and skip) of
        ``quantity``: file:line:column for text, variable and sample for arrays.

        Parameters
        ----------
        index : int
            The sample, 0-based in the record as read.
        quantity : str
            ``"voltage"``, ``"displacement"`` or ``"time"``.
        message : str
            What is wrong with it.

        Returns
        -------
        RecordError
            The error, to raise.

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.io import open_record
        >>> path = os.path.join(tempfile.mkdtemp(), "loop.csv")
        >>> with open(path, "w") as f:
        ...     _ = f.write("time_s,voltage_V,displacement_um\\n0,0,0\\n0.1,5,1.2\\n0.2,10,2.6\\n")
        >>> err = open_record(path, lag=1).error(0, "displacement", "too large")
        >>> print(str(err).replace(path, "PATH"))
        PATH:3:3: too large
        """
        row = self.skipped + index + (self.lag if quantity == "displacement" else 0)
        if quantity not in self.refs:
            return RecordError(self.path, f"sample {index}: {message}")
        return self.source.error(row, self.refs[quantity], message)

    def close(self) -> None:
        """Close the file (array files; text is read block by block without holding it).

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.io import open_record
        >>> path = os.path.join(tempfile.mkdtemp(), "loop.csv")
        >>> with open(path, "w") as f:
        ...     _ = f.write("time_s,voltage_V,displacement_um\\n0,0,0\\n0.1,5,1.2\\n0.2,10,2.6\\n")
        >>> reader = open_record(path)
        >>> reader.close()
        """
        if isinstance(self.source, ArraySource):
            self.source.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class _Transform:
    """Units, gain, time from the rate, the sensor lag and the skipped start, applied to
    raw blocks as they come (state carried across blocks)."""

    def __init__(self, reader):
        self.r = reader
        self.raw_rows = 0
        self.to_drop = reader.lag           # leading displacement samples without voltage
        self.queue = {}
        self.skipping = reader.skip_until is not None
        self.skipped = 0

    def feed(self, raw):
        r = self.r
        n = len(next(iter(raw.values())))
        block = dict(raw)
        for q in ("voltage", "time"):
            named = r.named_units.get(q)
            if q in block and named is not None:
                unit, factor, _ = named
                block[q] = self._scaled(block[q], q, factor, f"{factor:g} ({unit} to "
                                        f"{'V' if q == 'voltage' else 's'})")
        if "voltage" in block and r.voltage_gain != 1.0:
            block["voltage"] = self._scaled(block["voltage"], "voltage", r.voltage_gain,
                                            f"the voltage gain {r.voltage_gain:g}")
        if "displacement" in block and r.displacement_gain != 1.0:
            block["displacement"] = self._scaled(
                block["displacement"], "displacement", r.displacement_gain,
                f"the displacement gain {r.displacement_gain:g}")
        if "displacement" in block and r.unit != "um":
            block["displacement"] = self._scaled(
                block["displacement"], "displacement", UNIT_FACTORS[r.unit],
                f"{UNIT_FACTORS[r.unit]:g} ({display_unit(r.unit)} to µm)")
        if "time" not in block and r.rate is not None:
            with np.errstate(over="ignore"):
                t = (self.raw_rows + np.arange(n)) / r.rate
            if n and not np.isfinite(t[-1]):       # increasing: the last overflows first
                k = self.raw_rows + int(np.flatnonzero(~np.isfinite(t))[0])
                raise RecordError(r.path, f"sample {k}: its time {k} / --rate {r.rate:g} Hz "
                                  "is too large for a double")
            block["time"] = t
        self.raw_rows += n
        if r.lag:
            block = self._pair(block)
        if self.skipping and block:
            t = block["time"]
            keep = np.flatnonzero(t >= r.skip_until)
            first = keep[0] if keep.size else len(t)
            self.skipped += int(first)
            if keep.size:
                self.skipping = False
            block = {q: a[first:] for q, a in block.items()}
        return {q: block.get(q) for q in QUANTITIES} if block else {}

    def _scaled(self, values, quantity, factor, what):
        """``values * factor``; a product too large for a double is an error at its
        line and column (not an overflow warning and an infinite sample)."""
        with np.errstate(over="ignore"):
            out = values * factor
        bad = np.flatnonzero(np.isinf(out))
        if bad.size:
            i, src, ref = int(bad[0]), self.r.source, self.r.refs[quantity]
            column = f"column {src.label(ref)}: " if isinstance(src, TextSource) else ""
            raise src.error(self.raw_rows + i, ref, f"{column}{values[i]:g} times {what} is "
                            "too large for a double")
        return out

    def _pair(self, block):
        d = block.pop("displacement")
        if self.to_drop:
            k = min(self.to_drop, len(d))
            d, self.to_drop = d[k:], self.to_drop - k
        for q, a in [("displacement", d), *block.items()]:
            self.queue[q] = np.concatenate([self.queue[q], a]) if q in self.queue else a
        n = min(len(a) for a in self.queue.values())
        out = {q: a[:n] for q, a in self.queue.items()}
        self.queue = {q: a[n:] for q, a in self.queue.items()}
        return out


def _likely(columns, quantity):
    """A hint naming the one column whose name looks like ``quantity`` (the lab files'
    guesses, GUESSES), as the option that selects it; "" if none or several. A CSV's
    columns are never guessed: a wrong guess would fit, or drive, the wrong signal."""
    others = [GUESSES[q] for q in GUESSES if q != quantity]
    hits = [c for c in columns if GUESSES[quantity].search(c)
            and not any(g.search(c) for g in others)]
    if len(hits) != 1:
        return ""
    return f" (is it {hits[0]!r}? --{quantity} {shlex.quote(hits[0])})"


def _text_column(src, quantity, spec, needed):
    """0-based field of a text record for a quantity (None if optional and absent)."""
    d = src.dialect
    if spec is None:
        name = DEFAULT_NAMES[quantity]
        if not src.columns:
            if not needed:
                return None
            raise CSVError(src.path, d.first_line, 0,
                           f"no header line: name the columns by position, e.g. --voltage 1 "
                           f"--displacement 2 ({d.describe()})")
        if name not in src.columns:
            if not needed:
                return None
            raise CSVError(src.path, d.header_line, 0, f"missing column {name!r} in header "
                           f"({', '.join(src.columns)}); name the {quantity} column with "
                           f"--{quantity} NAME or --{quantity} NUMBER"
                           + (", or give the sample rate, --rate HZ" if quantity == "time"
                              else "") + _likely(src.columns, quantity))
        spec = name
    text = str(spec).strip()
    if text.isdigit():
        k = int(text)
        if not 1 <= k <= d.n_fields:
            raise CSVError(src.path, d.header_line or d.first_line, 0,
                           f"--{quantity} {k}: the file has columns 1 to {d.n_fields}")
        return k - 1
    if not src.columns:
        raise CSVError(src.path, d.first_line, 0, f"--{quantity} {text!r}: the file has no "
                       f"header line, so name the column by its number (1 to {d.n_fields})")
    hits = [i for i, c in enumerate(src.columns) if c == text]
    if not hits:
        raise CSVError(src.path, d.header_line, 0, f"missing column {text!r} in header "
                       f"({', '.join(src.columns)})")
    if len(hits) > 1:
        raise CSVError(src.path, d.header_line, hits[1] + 1,
                       f"column {text!r} appears {len(hits)} times in the header (columns "
                       f"{', '.join(str(i + 1) for i in hits)}): name the {quantity} by its "
                       f"number, e.g. --{quantity} {hits[0] + 1}")
    return hits[0]


def _open_source(path, reader, separator, decimal_comma, sheet=None, units_row=None):
    if units_row is not None and (reader is not None or
                                  EXTENSIONS.get(os.path.splitext(path)[1].lower()) or
                                  os.path.splitext(path)[1].lower() in LAB_EXTENSIONS):
        raise InvalidArgumentError("--units-row and --no-units-row are for delimited text "
                                   "files")
    if reader is not None:
        return function_source(path, _call_reader(reader, path))
    kind = kind_of(path)
    if kind is not None:
        raise RecordError(path, f"{kind}, not a regular file: a record is read in several "
                          "passes, which a stream cannot give; write it to a file first")
    ext = os.path.splitext(path)[1].lower()
    kind = EXTENSIONS.get(ext)
    if sheet is not None and LAB_EXTENSIONS.get(ext) != "xlsx":
        raise InvalidArgumentError("--sheet is for Excel workbooks (.xlsx)")
    if ext in LAB_EXTENSIONS:
        if ext != ".lvm" and (separator is not None or decimal_comma is not None):
            raise InvalidArgumentError(f"--separator and --decimal-comma are for text "
                                       f"files, not {LAB_EXTENSIONS[ext]}")
        return open_lab_source(path, LAB_EXTENSIONS[ext], sheet)
    if kind is None:
        return TextSource(path, separator=separator, decimal_comma=decimal_comma,
                          units_row=units_row)
    if separator is not None or decimal_comma is not None:
        raise InvalidArgumentError(f"--separator and --decimal-comma are for text files, not "
                                   f"{kind}")
    return open_array_source(path, kind)


def _call_reader(reader, path):
    """Call a reader given as a function, 'module:function' or 'file.py:function'.
    Whatever the user's code raises (on loading or on the call) is a RecordError naming
    the reader: it is the user's code, not pihyst's."""
    if callable(reader):
        func = reader
        name = getattr(reader, "__qualname__", None) or getattr(reader, "__name__", "reader")
    else:
        name = str(reader)
        module, sep, attr = name.rpartition(":")
        if not sep or not module or not attr:
            raise InvalidArgumentError(f"--reader {reader!r}: expected MODULE:FUNCTION or "
                                       "FILE.py:FUNCTION")
        try:
            loaded = _load_reader_module(module)
        except ImportError as err:
            raise InvalidArgumentError(f"--reader {reader}: cannot load it ({err})") from None
        except (Exception, SystemExit) as err:  # noqa: BLE001 - the user's module failed
            raise InvalidArgumentError(f"--reader {reader}: cannot load it "
                                       f"({_what(err)})") from err
        func = getattr(loaded, attr, None)
        if func is None:
            raise InvalidArgumentError(f"--reader {reader}: {module} has no function {attr!r}")
        if not callable(func):
            raise InvalidArgumentError(f"--reader {reader}: {attr!r} in {module} is not a "
                                       f"function but {type(func).__name__}")
    try:
        return func(path)
    except (Exception, SystemExit) as err:  # noqa: BLE001 - the user's function failed
        raise RecordError(path, f"the reader {name} failed: {_what(err)}") from err


def _load_reader_module(module):
    if module.endswith(".py"):
        spec = importlib.util.spec_from_file_location("_pihyst_reader", module)
        if spec is None or not os.path.isfile(module):
            raise ImportError(f"no file {module}")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        return mod
    sys.path.insert(0, os.getcwd())
    try:
        return importlib.import_module(module)
    finally:
        sys.path.remove(os.getcwd())


def _what(err):
    """An exception raised by the user's code, in one line."""
    if isinstance(err, SystemExit):
        return f"it called sys.exit({err.code!r})"
    text = " ".join(str(err).split())
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def _positive(value, option):
    if value is None:
        return None
    value = _finite(value, option)
    if value <= 0:
        raise InvalidArgumentError(f"{option} must be positive, got {value:g}")
    return value


def _finite(value, option):
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"{option} must be a number, got {value!r}") from None
    if not np.isfinite(value):
        raise InvalidArgumentError(f"{option} must be a finite number, got {value!r}")
    return value


def open_record(path: str | os.PathLike[str], **options: Any) -> RecordReader:
    """A :class:`RecordReader` for ``path`` (see :func:`read_record` for the options).

    Parameters
    ----------
    path : str or os.PathLike
        The record.
    **options
        The reading options of :class:`RecordReader`.

    Returns
    -------
    RecordReader
        The opened record, to read whole or block by block.

    Raises
    ------
    RecordError
        A file that cannot be read or lacks a needed column.
    InvalidArgumentError
        Options that are not valid.

    Examples
    --------
    >>> import os, tempfile
    >>> from pihyst.io import open_record
    >>> path = os.path.join(tempfile.mkdtemp(), "loop.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("time_s,voltage_V,displacement_um\\n0,0,0\\n0.1,5,1.2\\n0.2,10,2.6\\n")
    >>> with open_record(path) as reader:
    ...     sorted(reader.metadata()["columns"])
    ['displacement', 'time', 'voltage']
    """
    return RecordReader(path, **options)


def read_record(path: str | os.PathLike[str], **options: Any) -> Record:
    """Read a record as it comes.

    ``path``: delimited text (any separator, header or not), ``.npy``, ``.npz``, ``.mat``
    (v5 and v7.3), ``.h5``/``.hdf5``, ``.parquet``; or anything, with ``reader=``.

    Options (all optional): ``voltage``, ``displacement``, ``time`` (column name or
    1-based number; a variable, ``NAME:K`` or ``K`` in array files; ``"none"`` to ignore
    a time column); ``rate`` (Hz, when there is no time column); ``displacement_unit``
    (m, mm, um, nm; else from the column name, else um); ``voltage_gain`` (the voltage
    column times this is the actuator's voltage); ``displacement_gain`` (the
    displacement column times this is the displacement: -1 for a sensor counting the
    other way); ``lag`` (the sensor answers this many
    samples late: displacement[k + lag] goes with voltage[k]); ``skip_until`` (seconds:
    drop the samples before); ``separator``, ``decimal_comma`` (text, when not found
    right); ``units_row`` (text: True, the line under the header holds the units; False,
    there is none; default: detected when every field of that line is a unit); ``reader``
    (a function, ``module:function`` or ``file.py:function`` called with ``path``,
    returning a dict of arrays ``voltage``, ``displacement``, ``time`` and ``metadata``);
    ``need`` (the quantities that must be there).

    Parameters
    ----------
    path : str or os.PathLike
        The record.
    **options
        The reading options above (those of :class:`RecordReader`).

    Returns
    -------
    Record
        Every sample, with the metadata of what was found and applied.

    Raises
    ------
    RecordError
        Bad data (:class:`CSVError` for text, with file, line and column).
    InvalidArgumentError
        Bad options.

    Examples
    --------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "loop.txt")
    >>> with open(path, "w") as f:
    ...     _ = f.write("0\\t0,0\\t12\\n1\\t0,5\\t13\\n2\\t1,0\\t15\\n")
    >>> rec = read_record(path, voltage=2, displacement=3, time=1, displacement_unit="nm")
    >>> rec.voltage.tolist(), rec.displacement.round(9).tolist()
    ([0.0, 0.5, 1.0], [0.012, 0.013, 0.015])
    """
    with open_record(path, **options) as reader:
        return reader.read()
