"""The log of a run: a plain CSV that ``pihyst fit`` reads as it is.

One header row, then one row per tick, every tick, written and flushed as the loop goes
(a crash or a kill loses at most the tick being written). A tick without a valid
reading (over-range, invalid, no reply, nothing sent) is a row like the others, with
``nan`` where there is no value and its status columns (``sensor_status``,
``supply_status``) saying what failed: NumPy's and pandas' default readers see every
tick. ``pihyst fit`` (any record reader) skips the ticks without a valid reading and
says how many. The metadata (pihyst version, configuration, model, limits, rate, start
time) and the lines saying why the run stopped are in the sidecar ``PATH.json``.
:func:`read_run_log` reads every tick back, and the notes.
"""

import csv
import io
import math
import os
from collections.abc import Iterable
from dataclasses import astuple, dataclass

import numpy as np

from pihyst.exceptions import CSVError, RecordError

COLUMNS = ("tick", "time_s", "phase", "reference", "command_V", "voltage_V", "readback_V",
           "displacement_um", "sensor_status", "supply_status", "overrun", "late_s",
           "busy_s")


@dataclass
class TickRecord:
    """One tick of the loop (the columns of the log, :data:`COLUMNS`).

    Parameters
    ----------
    tick : int
        The tick's number, from 0.
    time_s : float
        The tick's start, s since the run started.
    phase : str
        ``"ramp-up"``, ``"run"`` or ``"shutdown"``.
    reference : float
        The signal's voltage (record, V) or the desired displacement (track, µm).
    command_V : float
        The voltage asked for, before the limits and the slew limit.
    voltage_V : float
        The voltage sent (NaN if nothing was sent).
    readback_V : float
        The supply's readback (NaN if not read).
    displacement_um : float
        The measured displacement (NaN without a valid reading).
    sensor_status : str
        ``"ok"``, ``"over-range+"``, ``"over-range-"``, ``"invalid"`` or
        ``"error: ..."``.
    supply_status : str
        ``"ok"`` or ``"error: ..."``.
    overrun : int
        1 if the tick ended after the next tick's deadline.
    late_s : float
        The tick's start minus its deadline (s).
    busy_s : float
        The time the tick's work took (s).

    Examples
    --------
    >>> from pihyst.rig import TickRecord
    >>> tick = TickRecord(0, 0.0, "run", 10.0, 10.0, 10.0, float("nan"), 1.2, "ok", "ok",
    ...                   0, 0.0, 0.003)
    >>> tick.valid
    True
    """

    tick: int
    time_s: float            # tick start, s since the run started
    phase: str               # ramp-up, run, shutdown
    reference: float         # the signal's voltage (record) or desired displacement (track)
    command_V: float         # the voltage asked for, before limits and slew
    voltage_V: float         # the voltage sent (NaN if nothing was sent)
    readback_V: float        # the supply's readback (NaN if not read)
    displacement_um: float   # measured (NaN if no valid reading)
    sensor_status: str       # ok, over-range+, over-range-, invalid, error: ...
    supply_status: str       # ok, error: ...
    overrun: int             # 1 if the tick ended after the next tick's deadline
    late_s: float            # tick start minus its deadline
    busy_s: float            # time the tick's work took

    @property
    def valid(self) -> bool:
        """True if the tick has a displacement and a voltage sent."""
        return math.isfinite(self.displacement_um) and math.isfinite(self.voltage_V)


def _text(value: object) -> str:
    if isinstance(value, float):
        return "nan" if math.isnan(value) else f"{value:.10g}"
    return str(value)


class CsvRunLog:
    """Writes a run log as the loop goes (see the module notes).

    Parameters
    ----------
    path : str
        The CSV file (created or replaced).
    metadata : list of str
        Lines written as ``# line`` before the header.
    fsync : bool
        Also force every row to the disk (survives a power cut, costs a disk write per
        tick); by default rows are flushed to the operating system, which survives a crash
        or kill of the process.

    Examples
    --------
    >>> import os, tempfile
    >>> from pihyst.rig import CsvRunLog, TickRecord, read_run_log
    >>> path = os.path.join(tempfile.mkdtemp(), "run.csv")
    >>> log = CsvRunLog(path, metadata=["rate 20 Hz"])
    >>> log.write(TickRecord(0, 0.0, "run", 5.0, 5.0, 5.0, float("nan"), 0.9, "ok", "ok",
    ...                      0, 0.0, 0.002))
    >>> log.note("end of the program"); log.close()
    >>> columns, notes = read_run_log(path)
    >>> columns["voltage_V"], notes
    (array([5.]), ['rate 20 Hz', 'end of the program'])
    """

    def __init__(self, path: str | os.PathLike[str], metadata: Iterable[object] = (),
                 fsync: bool = False) -> None:
        self.path = os.fspath(path)
        self.fsync = fsync
        self._file = open(self.path, "w", encoding="utf-8", newline="")
        self._metadata = [part for line in metadata for part in str(line).splitlines()]
        self._notes: list[str] = []
        self.rows = 0
        self._file.write(",".join(COLUMNS) + "\n")
        self._flush()
        self._sidecar()

    def _sidecar(self) -> None:
        from pihyst.io._csv import write_sidecar
        write_sidecar(self.path, COLUMNS, self.rows, self._metadata,
                      {"kind": "pihyst rig run log", "notes": list(self._notes)})

    def _flush(self) -> None:
        self._file.flush()
        if self.fsync:
            os.fsync(self._file.fileno())

    def write(self, record: TickRecord) -> None:
        """Append one tick's row and flush it (to the disk too with ``fsync``).

        Parameters
        ----------
        record : TickRecord
            The tick.

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.rig import CsvRunLog, TickRecord
        >>> log = CsvRunLog(os.path.join(tempfile.mkdtemp(), "run.csv"))
        >>> log.write(TickRecord(0, 0.0, "run", 5.0, 5.0, 5.0, float("nan"), 0.9, "ok",
        ...                      "ok", 0, 0.0, 0.002))
        >>> log.rows
        1
        >>> log.close()
        """
        fields = []
        for value in astuple(record):
            text = _text(value)
            # a status may hold commas or quotes: quote it as CSV does
            if any(c in text for c in ',"\n\r'):
                text = '"' + text.replace('"', '""').replace("\n", " ").replace("\r", " ") + '"'
            fields.append(text)
        line = ",".join(fields)
        self._file.write(line + "\n")
        self.rows += 1
        self._flush()

    def note(self, text: object) -> None:
        """Keep a line about the run (why it stopped) in the sidecar ``PATH.json``.

        Parameters
        ----------
        text : str
            The line (several lines are kept as several).

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.rig import CsvRunLog, TickRecord
        >>> log = CsvRunLog(os.path.join(tempfile.mkdtemp(), "run.csv"))
        >>> log.note("stopped: sensor over-range\\nafter 12 ticks")
        >>> log.close()
        >>> import json
        >>> with open(log.path + ".json") as f:
        ...     json.load(f)["notes"]
        ['stopped: sensor over-range', 'after 12 ticks']
        """
        self._notes.extend(str(text).splitlines())
        self._sidecar()

    def close(self) -> None:
        """Close the file and write the sidecar a last time (a second close does nothing).

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.rig import CsvRunLog, TickRecord
        >>> log = CsvRunLog(os.path.join(tempfile.mkdtemp(), "run.csv"))
        >>> log.close(); log.close()
        >>> with open(log.path) as f:
        ...     f.read().startswith("tick,time_s,phase")
        True
        """
        if not self._file.closed:
            self._file.close()
            self._sidecar()


def read_run_log(path: str | os.PathLike[str]) -> tuple[dict[str, np.ndarray], list[str]]:
    """Every tick of a run log, and its notes.

    Parameters
    ----------
    path : str or os.PathLike
        The log a run wrote (``pihyst rig record``, :meth:`Rig.run`).

    Returns
    -------
    columns : dict of str to ndarray
        Column name to values: numbers as float (NaN where empty), the phase and the
        statuses as str (object arrays).
    notes : list of str
        The sidecar's metadata and stop lines (and the ``#`` lines of older logs).

    Raises
    ------
    RecordError
        The file has no header row.
    CSVError
        A number column holds something that is not a number (file, line, column).

    Examples
    --------
    >>> import os, tempfile
    >>> from pihyst.rig import read_run_log
    >>> path = os.path.join(tempfile.mkdtemp(), "run.csv")
    >>> with open(path, "w") as f:
    ...     _ = f.write("tick,phase,voltage_V\\n0,run,1.5\\n1,run,\\n")
    >>> columns, notes = read_run_log(path)
    >>> columns["voltage_V"], list(columns["phase"])
    (array([1.5, nan]), ['run', 'run'])
    """
    from pihyst.io._csv import read_sidecar
    with open(path, encoding="utf-8-sig", newline="") as f:
        text = f.read()
    side = read_sidecar(path) or {}
    notes = list(side.get("comments", [])) + list(side.get("notes", []))
    rows: list[list[str]] = []
    lines: list[int] = []
    header: list[str] | None = None
    reader = csv.reader(io.StringIO(text))
    for row in reader:
        if not row:
            continue
        first = row[0].lstrip()
        if header is None:
            if first.startswith("#"):
                notes.append(",".join(row).lstrip("# ").rstrip())
                continue
            header = [h.strip() for h in row]
            continue
        if first.startswith("#"):
            if len(row) == len(header) and first[1:].strip().lstrip("-").isdigit():
                row = [first[1:]] + row[1:]
            else:
                notes.append(",".join(row).lstrip("# ").rstrip())
                continue
        rows.append(row)
        lines.append(reader.line_num)
    if header is None:
        raise RecordError(os.fspath(path), "no header row: not a pihyst run log")
    out: dict[str, np.ndarray] = {}
    for j, name in enumerate(header):
        values = [r[j] if j < len(r) else "" for r in rows]
        if name in ("phase", "sensor_status", "supply_status"):
            out[name] = np.array(values, dtype=object)
            continue
        try:
            out[name] = np.array([float(v) if v else math.nan for v in values])
        except ValueError:
            i = next(i for i, v in enumerate(values) if v and not _is_number(v))
            raise CSVError(os.fspath(path), lines[i], j + 1, f"column {name!r}: "
                           f"{values[i]!r} is not a number") from None
    return out, notes


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
