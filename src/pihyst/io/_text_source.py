"""A delimited text record read block by block: the fast engine on each block, the
careful reader where the engine refuses one, and exact line numbers for any sample."""

import dataclasses
import math
import os
import re

from pihyst.exceptions import CSVError, InvalidArgumentError
from pihyst.io._numbers import is_number, parse_number
from pihyst.io._text_check import check_block, data_line_of
from pihyst.io._text_engines import engine_name, read_block
from pihyst.io._text_format import (
    AUTO,
    HEAD_BYTES,
    SEPARATOR_NAMES,
    FieldError,
    head_lines,
    is_skipped,
    sniff,
    split_fields,
)

BLOCK_BYTES = 1 << 23
# a PI data recorder's GCSArray header: '# KEY = value' lines ending with '# END_HEADER'
_GCS_LINE = re.compile(r"^\s*#\s*([A-Za-z_][A-Za-z_0-9]*)\s*=\s*(.*?)\s*$")
_GCS_END = re.compile(r"^\s*#\s*END_HEADER\s*$", re.IGNORECASE)
NUL_MESSAGE = ("not a text file (it holds NUL bytes) from this line on: the data end before "
               "it (a file cut off, or padded with zeros?)")
_GCS_SEPARATORS = {32: None, 9: "\t", 44: ",", 59: ";"}


class TextSource:
    """A delimited text file. ``columns`` are the header's names (``()`` without one)."""

    kind = "text"

    def __init__(self, path, *, separator=None, decimal_comma=None, block_bytes=None,
                 units_row=None):
        self.path = os.fspath(path)
        self.block_bytes = block_bytes or BLOCK_BYTES
        if separator is not None and separator not in SEPARATOR_NAMES:
            raise InvalidArgumentError(f"unknown separator {separator!r}: use one of "
                                       "',', ';', 'tab', 'whitespace'")
        sep = AUTO if separator is None else SEPARATOR_NAMES[separator]
        decimal = None if decimal_comma is None else ("," if decimal_comma else ".")
        if sep == "," and decimal == ",":
            raise InvalidArgumentError("a decimal comma needs a separator other than the comma")
        try:
            with open(self.path, "rb") as f:
                head = f.read(HEAD_BYTES)
                at_eof = not f.read(1)
            self.size = os.path.getsize(self.path)
        except OSError as err:
            raise CSVError(self.path, 0, 0, f"cannot read file: {err.strerror}") from None
        nul = head.find(b"\0")
        if nul >= 0:
            line = head.count(b"\n", 0, nul) + 1
            if line == 1 or not head[:nul].strip(b"\r\n\0"):
                raise CSVError(self.path, 1, 0, "not a text file (it holds NUL bytes); "
                               "binary records: .npy, .npz, .mat, .h5, .parquet, .tdms, "
                               ".xlsx")
            raise _nul_error(self.path, head, nul)
        self.gcs = _gcs_header(head, at_eof)
        if self.gcs is not None and sep == AUTO and "SEPARATOR" in self.gcs[0]:
            sep = _GCS_SEPARATORS.get(_int(self.gcs[0]["SEPARATOR"]), AUTO)
        self.dialect = sniff(head, at_eof, separator=sep, decimal=decimal)
        if self.dialect is None and not at_eof:
            # nothing but blank or comment lines, then a line longer than the head
            line = head.count(b"\n") + 1
            raise CSVError(self.path, line, 0, f"a line longer than {len(head):,} bytes "
                           "before any data line: not a record")
        if self.dialect is None:
            raise CSVError(self.path, 1, 0, "empty file: no data lines")
        self.columns = self.dialect.header
        self._check_first_row()
        self._check_last_line()
        # what the file says about its columns: units (a units row, or a GCSArray header)
        # and a sample period
        self.units, self.found, self.notes = {}, {}, []
        self.units_line = 0
        # a pihyst rig run log: its ticks without a valid reading are skipped, and counted
        self.rig_log = self.columns == RIG_LOG_COLUMNS
        self.skipped_ticks = None
        self._units_row_option = units_row
        if units_row and not self.columns:
            raise CSVError(self.path, self.dialect.first_line, 0, "--units-row: the file has "
                           "no header line for a units row to be under")
        if self.columns and units_row is not False:
            self._units_row(head, at_eof, forced=bool(units_row))
        elif self.gcs is not None:
            self._gcs_columns()

    def _check_first_row(self):
        """A first line of numbers with a value that is not a valid sample (NaN,
        infinity, a hex number) is a data line at fault, not a header."""
        d = self.dialect
        if not d.header:
            return
        fields = [f for f in d.header if f.strip()]
        if not fields or not all(_number_like(f, d.decimal) for f in fields):
            return
        for k, f in enumerate(d.header):
            try:
                parse_number(f, d.decimal)
            except ValueError as err:
                if str(err) == "missing value":
                    continue
                raise CSVError(self.path, d.header_line, k + 1, f"{err}: the first line holds "
                               "numbers, so it is a sample, not a header") from None

    def _check_last_line(self):
        """A last line without its line end whose last number is cut short (``4.``,
        ``1e``, ``-``) is an error at that line: the file was cut off."""
        if self.size == 0:
            return
        with open(self.path, "rb") as f:
            f.seek(max(0, self.size - 4096))
            tail = f.read()
        if tail.endswith((b"\n", b"\r")):
            return
        cut = max(tail.rfind(b"\n"), tail.rfind(b"\r"))
        last = tail[cut + 1:].decode("utf-8", errors="replace")
        if is_skipped(last):
            return
        try:
            fields = split_fields(last, self.dialect.separator)
        except FieldError:
            return
        end = fields[-1].strip() if fields else ""
        if end and (end.endswith((".", "e", "E", "+", "-")) or end in (".", "-", "+")):
            with open(self.path, "rb") as f:
                data = f.read()
            text = data.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
            line = text.count(b"\n") + 1
            raise CSVError(self.path, line, len(fields), f"the last line ends without a line "
                           f"end and its last number {end!r} is cut short: the file was cut "
                           "off (truncated)?")

    def _units_row(self, head, at_eof, forced=False):
        """A line of units under the header (``s, V, um``): its units are the columns',
        and the data start below it. Detected when every field looks like a unit; with
        ``forced`` (``--units-row``) the line under the header is one, whatever it holds
        (a field that is not a unit pihyst knows is kept as written, and named where the
        unit is used)."""
        from pihyst.io._lab_formats import looks_unit
        d = self.dialect
        _, lines = head_lines(head, at_eof)
        below = [(n, end, t) for n, end, t in lines if n > d.header_line and not is_skipped(t)]
        if not below:
            if forced:
                raise CSVError(self.path, d.header_line + 1, 0, "--units-row: no line under "
                               "the header")
            return
        number, end, text = below[0]
        try:
            fields = split_fields(text, d.separator)
        except FieldError as err:
            if forced:
                raise CSVError(self.path, number, 0, f"--units-row: {err}") from None
            return
        if forced and len(fields) != d.n_fields:
            raise CSVError(self.path, number, 0, f"--units-row: the line under the header "
                           f"has {len(fields)} fields, the header {d.n_fields}")
        if not forced and (len(fields) != d.n_fields or not any(f.strip() for f in fields)):
            return
        if not forced and not all(not f.strip() or looks_unit(f) for f in fields):
            return
        self.units = {i: f.strip().strip("[]()").strip() for i, f in enumerate(fields)
                      if f.strip()}
        self.units_line = number
        self.dialect = dataclasses.replace(d, data_offset=end, data_line=number + 1)

    def _units_hint(self, err):
        """``err`` with a hint when it is a word in the line under the header that was
        not taken for a units row (a unit pihyst does not know, a name...)."""
        if (self._units_row_option is None and not self.units_line and self.columns
                and err.line == self.dialect.data_line and "is not a number" in err.message):
            return CSVError(self.path, err.line, err.column, err.message + " (the line "
                            "under the header: if it holds units, pass --units-row)")
        return err

    def _gcs_columns(self):
        """Column names from a GCSArray header's NAME0, NAME1, ...; the sample period
        from its SAMPLE_TIME."""
        keys, end_line = self.gcs
        names = []
        for k in range(self.dialect.n_fields):
            name = keys.get(f"NAME{k}")
            names.append(name.strip() if name and name.strip() else f"column {k + 1}")
        if any(f"NAME{k}" in keys for k in range(self.dialect.n_fields)):
            self.columns = tuple(names)
            self.gcs_names = True
        if "SAMPLE_TIME" in keys:
            try:
                period = float(keys["SAMPLE_TIME"])
            except ValueError:
                period = float("nan")
            if not (period > 0 and period < float("inf")):
                raise CSVError(self.path, end_line, 0, f"SAMPLE_TIME = {keys['SAMPLE_TIME']}"
                               " in the GCSArray header is not a positive time")
            self.found["rate"] = 1.0 / period
            self.found["rate_why"] = f"SAMPLE_TIME = {keys['SAMPLE_TIME']} s in the header"

    # ---------------------------------------------------------------- describing
    def metadata(self):
        d = self.dialect
        layout = d.describe()
        if self.gcs is not None:
            layout = "PI GCSArray (data recorder) header, " + layout
        if self.units_line:
            layout += f", units on line {self.units_line}"
        return {"format": "text", "layout": layout, "engine": engine_name()}

    def label(self, index):
        """How messages name the field ``index`` (0-based)."""
        if self.columns and getattr(self, "gcs_names", False):
            return f"{index + 1} {self.columns[index]!r}"
        if self.columns:
            return repr(self.columns[index])
        return f"{index + 1}"

    # ---------------------------------------------------------------- reading
    def _blocks(self):
        """(first line, block, bytes read so far) of the data part: whole lines with LF
        line ends (in a rig log, the ticks without a valid reading made comments)."""
        for first, block, done in self._raw_blocks():
            if self.rig_log:
                block, n = _without_invalid_ticks(block)
                self._dropped += n
            yield first, block, done

    def _raw_blocks(self):
        d = self.dialect
        line, carry = d.data_line, b""
        with open(self.path, "rb") as f:
            f.seek(d.data_offset)
            while True:
                chunk = f.read(self.block_bytes)
                data = carry + chunk
                if not chunk:
                    if data:
                        yield line, _lf(data), f.tell()
                    return
                # a CR at the very end may be the first half of a CRLF: keep it for later
                end = len(data) - 1 if data.endswith(b"\r") else len(data)
                cut = max(data.rfind(b"\n", 0, end), data.rfind(b"\r", 0, end))
                if cut < 0:
                    carry = data
                    continue
                block, carry = _lf(data[:cut + 1]), data[cut + 1:]
                yield line, block, f.tell() - len(carry)
                line += block.count(b"\n")

    def blocks(self, wanted, progress=None):
        """Arrays (n, len(wanted)) of the fields ``wanted`` (0-based), block by block."""
        labels = [self.label(i) for i in wanted]
        rows = 0
        self._dropped = 0
        for first_line, block, done in self._blocks():
            nul = block.find(b"\0")
            if nul >= 0:        # a tail of NULs (a file cut off, a sparse file): it ends here
                k = block.count(b"\n", 0, nul)
                raise CSVError(self.path, first_line + k, 0, NUL_MESSAGE)
            values = read_block(block, self.dialect, wanted)
            if values is None:
                try:
                    values = check_block(self.path, block, first_line, self.dialect, wanted,
                                         labels)
                except CSVError as err:
                    raise self._units_hint(err) from None
            rows += len(values)
            if self.rig_log:
                self.skipped_ticks = self._dropped
            if progress is not None:
                progress(done, self.size)
            if len(values):
                yield values
        if rows == 0:
            where = self.dialect.header_line or self.dialect.first_line
            raise CSVError(self.path, where, 0, "no data rows"
                           + (" after the header" if self.dialect.header_line else ""))

    def location(self, row, index):
        """(line, column) of field ``index`` of data row ``row`` (both 0-based)."""
        self._dropped = 0
        line = data_line_of(((first, block) for first, block, _ in self._blocks()),
                            self.dialect, row)
        return (line or 0), index + 1

    def error(self, row, index, message):
        line, column = self.location(row, index)
        return CSVError(self.path, line, column, message)


# the header of a pihyst rig run log (pihyst.rig._log.COLUMNS)
RIG_LOG_COLUMNS = ("tick", "time_s", "phase", "reference", "command_V", "voltage_V",
                   "readback_V", "displacement_um", "sensor_status", "supply_status",
                   "overrun", "late_s", "busy_s")
_VOLTAGE_FIELD, _DISPLACEMENT_FIELD = 5, 7


def _without_invalid_ticks(block):
    """The block with each tick that has no valid reading (no finite voltage sent or
    displacement read) turned into a comment line (so that line numbers stay), and how
    many."""
    lines = block.split(b"\n")
    dropped = 0
    for k, line in enumerate(lines):
        if not line or line.lstrip().startswith(b"#"):
            continue
        fields = line.split(b",", _DISPLACEMENT_FIELD + 1)
        try:
            ok = all(math.isfinite(float(fields[j]))
                     for j in (_VOLTAGE_FIELD, _DISPLACEMENT_FIELD))
        except (ValueError, IndexError):
            ok = True           # not a number: the careful reader names it
        if not ok:
            lines[k] = b"#" + line
            dropped += 1
    return b"\n".join(lines), dropped


def _nul_error(path, head, nul):
    line = head[:nul].replace(b"\r\n", b"\n").replace(b"\r", b"\n").count(b"\n") + 1
    return CSVError(path, line, 0, NUL_MESSAGE)


_NUMBER_LIKE = re.compile(r"[+-]?(nan|inf|infinity|0[xX][0-9a-fA-F]+|[0-9][0-9_]*(\.[0-9_]*)?"
                          r"([eE][+-]?[0-9_]+)?)\Z", re.IGNORECASE)


def _number_like(field, decimal):
    """Whether a field is written as a number, valid or not (``nan``, ``inf``,
    ``0x10``, ``1_5``)."""
    f = field.strip()
    return is_number(f, decimal) or bool(_NUMBER_LIKE.match(f))


def _int(text):
    try:
        return int(float(text))
    except ValueError:
        return None


def _gcs_header(head, at_eof):
    """({KEY: value}, line of END_HEADER) of a GCSArray header at the top of the file,
    else None."""
    _, lines = head_lines(head, at_eof)
    keys = {}
    for number, _, text in lines:
        if _GCS_END.match(text):
            return (keys, number) if keys else None
        m = _GCS_LINE.match(text)
        if m:
            keys[m.group(1).upper()] = m.group(2)
        elif text.strip() and not text.lstrip().startswith(("#", "[GCS_ARRAY")):
            return None
    return None


def _lf(data):
    if b"\r" in data:
        data = data.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    return data
