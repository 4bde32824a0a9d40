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
from dataclasses import astuple, dataclass

import numpy as np

from pihyst.exceptions import CSVError, RecordError

COLUMNS = ("tick", "time_s", "phase", "reference", "command_V", "voltage_V", "readback_V",
           "displacement_um", "sensor_status", "supply_status", "overrun", "late_s",
           "busy_s")


@dataclass
class TickRecord:
    """One tick of the loop (the columns of the log)."""

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
    def valid(self):
        return math.isfinite(self.displacement_um) and math.isfinite(self.voltage_V)


def _text(value):
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
    """

    def __init__(self, path, metadata=(), fsync=False):
        self.path = os.fspath(path)
        self.fsync = fsync
        self._file = open(self.path, "w", encoding="utf-8", newline="")
        self._metadata = [part for line in metadata for part in str(line).splitlines()]
        self._notes = []
        self.rows = 0
        self._file.write(",".join(COLUMNS) + "\n")
        self._flush()
        self._sidecar()

    def _sidecar(self):
        from pihyst.io._csv import write_sidecar
        write_sidecar(self.path, COLUMNS, self.rows, self._metadata,
                      {"kind": "pihyst rig run log", "notes": list(self._notes)})

    def _flush(self):
        self._file.flush()
        if self.fsync:
            os.fsync(self._file.fileno())

    def write(self, record):
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

    def note(self, text):
        """A line about the run (why it stopped), kept in the sidecar."""
        self._notes.extend(str(text).splitlines())
        self._sidecar()

    def close(self):
        if not self._file.closed:
            self._file.close()
            self._sidecar()


def read_run_log(path):
    """Every tick of a run log as a dict column -> array (numbers as float, statuses
    and phase as str), and the notes (the sidecar's metadata and stop lines; ``#`` lines
    of older logs) as a list of lines."""
    from pihyst.io._csv import read_sidecar
    with open(path, encoding="utf-8-sig", newline="") as f:
        text = f.read()
    side = read_sidecar(path) or {}
    notes = list(side.get("comments", [])) + list(side.get("notes", []))
    rows, lines, header = [], [], None
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
        raise RecordError(path, "no header row: not a pihyst run log")
    out = {}
    for j, name in enumerate(header):
        values = [r[j] if j < len(r) else "" for r in rows]
        if name in ("phase", "sensor_status", "supply_status"):
            out[name] = np.array(values, dtype=object)
            continue
        try:
            out[name] = np.array([float(v) if v else math.nan for v in values])
        except ValueError:
            i = next(i for i, v in enumerate(values) if v and not _is_number(v))
            raise CSVError(path, lines[i], j + 1, f"column {name!r}: {values[i]!r} is not a "
                           "number") from None
    return out, notes


def _is_number(text):
    try:
        float(text)
    except ValueError:
        return False
    return True
