"""Records as lab software writes them: LabVIEW Measurement Files (``.lvm``), NI TDMS
(``.tdms``, through npTDMS), Excel workbooks (``.xlsx``, through openpyxl).

Each is read whole into a :class:`TableSource`: named columns of floats, each sample
located for messages (``FILE:LINE:COLUMN`` for ``.lvm``, the sheet's row and column for
``.xlsx``, ``group/channel`` and sample for ``.tdms``), and what the format says about
the time axis (LabVIEW's ``X0``/``Delta_X``, TDMS's ``wf_start_offset``/``wf_increment``)
turned into a time column whose name says where it came from. docs/records.md.
"""

import datetime
import os
import re

import numpy as np

from pihyst.exceptions import CSVError, InvalidArgumentError, RecordError
from pihyst.io._array_sources import ArraySource, need
from pihyst.io._numbers import parse_number

# what a column's name says it holds, for files whose columns are named by lab software
# (a guess, always said in the read line)
GUESSES = {
    "time": re.compile(r"^(x_value|time|zeit|t|timestamp|seconds|sec)\b|^(time|zeit)[_ \[(]",
                       re.IGNORECASE),
    "voltage": re.compile(r"volt|spannung|^u$|^u[_ \[(]|^v$|^v[_ \[(]|drive|piezo.*(v|out)",
                          re.IGNORECASE),
    "displacement": re.compile(r"displac|position|^pos|^weg|^y$|^y[_ \[(]|^x$|^x[_ \[(]|"
                               r"sensor|stroke|auslenkung", re.IGNORECASE),
}
PREFERRED = re.compile(r"actual|measured|sensor|ist", re.IGNORECASE)


class TableSource(ArraySource):
    """Named columns read whole from a lab file. ``locate(row, column)`` returns the
    exception for a message about sample ``row`` of column ``column`` (0-based);
    ``time_column`` is the name of the column that is the file's own time axis (and
    ``time_why`` says why), ``units`` the unit each column's file gives."""

    def __init__(self, path, kind, names, arrays, locate, *, layout, time_column=None,
                 time_why=None, units=None, notes=(), fields=None):
        super().__init__(path, kind, dict(zip(names, arrays)), {"layout": layout})
        self.names = tuple(names)
        self.fields = fields or {}      # name -> 1-based column of the file, if not its rank
        self.locate = locate
        self.time_column, self.time_why = time_column, time_why
        self.units = dict(units or {})
        self.notes = list(notes)

    def resolve(self, spec, quantity):
        text = str(spec).strip()
        if text.isdigit():
            k = int(text)
            if self.fields:
                hits = [n for n in self.names if self.fields.get(n) == k]
                if hits:
                    return hits[0], None
            elif 1 <= k <= len(self.names):
                return self.names[k - 1], None
            raise RecordError(self.path, f"--{quantity} {k}: no column {k} ({self.inventory()})")
        if text in getattr(self, "unreadable", {}):
            raise self.unreadable[text]
        if text not in self.variables:
            raise RecordError(self.path, f"no column {text!r} for the {quantity} "
                              f"({self.inventory()})")
        return text, None

    def guess(self, quantity):
        """(ref, why) of the column the file's own layout or names say holds
        ``quantity``, or None; refuses to choose between several."""
        if quantity == "time" and self.time_column is not None:
            return (self.time_column, None), self.time_why
        hits = [n for n in self.names if GUESSES[quantity].search(n)
                and n != self.time_column]
        if quantity != "time":
            hits = [n for n in hits if not GUESSES["time"].search(n)]
        if quantity == "displacement":
            hits = [n for n in hits if not GUESSES["voltage"].search(n)]
        if len(hits) > 1:
            preferred = [n for n in hits if PREFERRED.search(n)]
            if len(preferred) == 1:
                return (preferred[0], None), (f"guessed from its name, the measured one of "
                                              f"{', '.join(map(repr, hits))}")
            raise RecordError(self.path, f"several columns may hold the {quantity} "
                              f"({', '.join(map(repr, hits))}): name one with --{quantity}")
        if hits:
            return (hits[0], None), "guessed from its name"
        return None

    def inventory(self):
        return "columns: " + ", ".join(
            f"{self.fields.get(n, i + 1)} {n!r}" if self.fields.get(n, i + 1) else repr(n)
            for i, n in enumerate(self.names))

    def label(self, ref):
        name = ref[0]
        if name not in self.names:
            return repr(name)
        k = self.fields.get(name, self.names.index(name) + 1)
        return f"column {k} {name!r}" if k else repr(name)

    def error(self, row, ref, message):
        return self.locate(row, self.names.index(ref[0]), message)

    def blocks(self, refs, block_rows, progress=None):
        # the values were checked as they were read: only the lengths remain to check
        n = self.common_length(refs)
        for start in range(0, n, block_rows):
            stop = min(n, start + block_rows)
            if progress is not None:
                progress(stop, n)
            yield np.column_stack([self.read(r, start, stop) for r in refs])


def unique_names(names):
    """Column names made unique (a repeated name gets ' (2)', ' (3)', ...)."""
    out, seen = [], {}
    for n in names:
        n = n.strip() or "unnamed"
        seen[n] = seen.get(n, 0) + 1
        out.append(n if seen[n] == 1 else f"{n} ({seen[n]})")
    return out


# ------------------------------------------------------------------------ LabVIEW .lvm
END_OF_HEADER = "***End_of_Header***"
_LVM_SEPARATORS = {"tab": "\t", "comma": ",", "semicolon": ";", "space": " "}
_SEP_NAMES = {v: k for k, v in _LVM_SEPARATORS.items()}


def open_lvm(path):
    """A LabVIEW Measurement File (the published text layout: a file header from
    ``LabVIEW Measurement`` to ``***End_of_Header***``, then segments, each a channel
    header to ``***End_of_Header***``, a line of column names, and data lines)."""
    try:
        with open(path, "rb") as f:
            raw = f.read()
    except OSError as err:
        raise RecordError(path, f"cannot read file: {err.strerror or err}") from None
    # LabVIEW writes the system code page (cp1252 on Western Windows); five bytes are
    # undefined there, and a damaged file may hold them: replaced, the line then fails
    # as a number where it should
    text = (raw.decode("cp1252", errors="replace") if _cp1252(raw) else
            raw.decode("utf-8", errors="replace"))
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    if not lines[0].lstrip("\ufeff").startswith("LabVIEW Measurement"):
        raise CSVError(path, 1, 0, "not a LabVIEW Measurement File (its first line is not "
                       "'LabVIEW Measurement')")
    i, header = 1, {}
    sep = "\t"
    while True:
        if i >= len(lines):
            raise CSVError(path, i, 0, f"no {END_OF_HEADER} after the file header")
        line = lines[i]
        i += 1
        if line.strip().startswith(END_OF_HEADER):
            break
        key, _, value = line.partition("\t") if "\t" in line else line.partition(",")
        if key.strip() == "Decimal_Separator":
            header["Decimal_Separator"] = value.strip()[:1]
        elif key.strip():
            header[key.strip()] = value.strip().strip("\t,;").strip()
        if key.strip() == "Separator":
            sep = _LVM_SEPARATORS.get(header["Separator"].lower(), "\t")
    decimal = header.get("Decimal_Separator", ".") or "."
    if decimal not in ".,":
        raise CSVError(path, i - 1, 0, f"Decimal_Separator {decimal!r}: expected '.' or ','")
    x_columns = header.get("X_Columns", "One")
    segments = []
    while True:
        while i < len(lines) and not lines[i].strip(sep + " "):
            i += 1
        if i >= len(lines):
            break
        seg, i = _lvm_segment(path, lines, i, sep, decimal, x_columns, len(segments) + 1)
        segments.append(seg)
    if not segments:
        raise CSVError(path, i, 0, "no data segments after the file header")
    return _lvm_table(path, segments, header, sep, decimal, x_columns)


def _cp1252(raw):
    try:
        raw.decode("utf-8")
        return False
    except UnicodeDecodeError:
        return True


def _fields(line, sep):
    return line.split() if sep == " " else line.split(sep)


def _lvm_segment(path, lines, i, sep, decimal, x_columns, number):
    """(segment, next line index): the channel header, names and data of one segment."""
    start = i
    channel = {}
    while True:
        if i >= len(lines):
            raise CSVError(path, start + 1, 0, f"segment {number}: no {END_OF_HEADER} after "
                           "its channel header")
        line = lines[i]
        i += 1
        if line.strip().startswith(END_OF_HEADER):
            break
        fields = _fields(line, sep)
        if fields and fields[0].strip():
            channel[fields[0].strip()] = ([f.strip() for f in fields[1:]], i)
    while i < len(lines) and not lines[i].strip(sep + " "):
        i += 1
    if i >= len(lines):
        raise CSVError(path, i, 0, f"segment {number}: no line of column names")
    names_line = i + 1
    names = [f.strip() for f in _fields(lines[i], sep)]
    while names and not names[-1]:
        names.pop()
    comment = bool(names) and names[-1].lower() == "comment"
    if comment:
        names.pop()
    i += 1
    rows, numbers = [], []
    width = len(names)
    while i < len(lines):
        line = lines[i]
        if not line.strip(sep + " "):
            i += 1
            continue
        fields = _fields(line, sep)
        first = fields[0].strip()
        if not _is_value(first, decimal):
            break           # the next segment's channel header
        if len(fields) < width or (len(fields) > width + 1 and any(
                f.strip() for f in fields[width + 1:])):
            raise CSVError(path, i + 1, min(len(fields), width) + 1,
                           f"{len(fields)} fields where the column names (line {names_line}) "
                           f"have {width}")
        row = []
        for j in range(width):
            try:
                row.append(parse_number(fields[j], decimal))
            except ValueError as err:
                reason = str(err)
                what = (f"missing value for column {names[j]!r}" if reason == "missing value"
                        else f"column {names[j]!r}: {reason}")
                raise CSVError(path, i + 1, j + 1, what) from None
        rows.append(row)
        numbers.append(i + 1)
        i += 1
    if not rows:
        raise CSVError(path, names_line, 0, f"segment {number}: no data lines")
    values = np.array(rows, dtype=float)
    return {"names": names, "names_line": names_line, "channel": channel, "values": values,
            "lines": np.array(numbers), "number": number}, i


def _is_value(field, decimal):
    try:
        parse_number(field, decimal)
    except ValueError as err:
        return "finite" in str(err) or "large" in str(err)   # a number, but refused later
    return True


def _per_channel(channel, key, n, path):
    values, line = channel.get(key, ([], 0))
    out = []
    for v in values[:n] if values else []:
        try:
            out.append(parse_number(v))
        except ValueError as err:
            raise CSVError(path, line, 0, f"{key}: {err}") from None
    return out, line


def _lvm_table(path, segments, header, sep, decimal, x_columns):
    first = segments[0]
    for seg in segments[1:]:
        if seg["names"] != first["names"]:
            raise CSVError(path, seg["names_line"], 0, f"segment {seg['number']} has the "
                           f"columns ({', '.join(seg['names'])}), segment 1 "
                           f"({', '.join(first['names'])}): pihyst reads segments that "
                           "continue one record")
    raw_names = first["names"]
    x_index = [j for j, n in enumerate(raw_names) if n.lower() == "x_value"]
    channels = [j for j in range(len(raw_names)) if j not in x_index]
    names = unique_names([raw_names[j] for j in channels])
    notes = []
    columns = {n: np.concatenate([s["values"][:, j] for s in segments])
               for n, j in zip(names, channels)}
    lines = np.concatenate([s["lines"] for s in segments])
    field_of = {n: j for n, j in zip(names, channels)}
    time_name = time_why = None
    if x_index:
        time_name = "X_Value"
        times = [s["values"][:, x_index[0]] for s in segments]
        field_of[time_name] = x_index[0]
        time_why = "the file's X column"
        if len(x_index) > 1:
            notes.append(f"{len(x_index)} X columns (X_Columns {x_columns}): the first is "
                         "the time")
    else:
        times = []
        for s in segments:
            n = len(s["values"])
            x0, _ = _per_channel(s["channel"], "X0", len(channels), path)
            dx, dx_line = _per_channel(s["channel"], "Delta_X", len(channels), path)
            if not dx:
                raise CSVError(path, s["names_line"], 0, f"segment {s['number']}: no X "
                               "column and no Delta_X in its channel header: give --rate HZ "
                               "or --time none")
            if len(set(dx)) > 1:
                raise CSVError(path, dx_line, 0, f"Delta_X differs between the channels "
                               f"({', '.join(f'{d:g}' for d in dx)})")
            if dx[0] <= 0:
                raise CSVError(path, dx_line, 0, f"Delta_X {dx[0]:g} is not positive")
            times.append((x0[0] if x0 else 0.0) + np.arange(n) * dx[0])
        time_name = "time (X0 + k Delta_X)"
        time_why = "from X0 and Delta_X in the channel header"
    for k in range(1, len(times)):
        if times[k][0] <= times[k - 1][-1]:
            step = (times[k - 1][-1] - times[k - 1][0]) / max(len(times[k - 1]) - 1, 1)
            shift = times[k - 1][-1] + step - times[k][0]
            times[k] = times[k] + shift
            notes.append(f"segment {segments[k]['number']}'s time starts again: it "
                         f"continues segment {segments[k - 1]['number']}'s")
    columns[time_name] = np.concatenate(times)
    order = [*names, time_name]

    def locate(row, column, message):
        name = order[column]
        line = int(lines[row]) if 0 <= row < len(lines) else 0
        field = field_of.get(name)
        return CSVError(path, line, 0 if field is None else field + 1, message)

    layout = (f"LabVIEW Measurement File, {len(segments)} segment(s), "
              f"{_SEP_NAMES[sep]}-separated"
              + (", decimal comma" if decimal == "," else "") + f", X_Columns {x_columns}")
    units = {}
    for n, j in zip(names, channels):
        unit = _lvm_unit(first["channel"], j, channels)
        if unit:
            units[n] = unit
    return TableSource(path, "lvm", order, [columns[n] for n in order], locate,
                       layout=layout, time_column=time_name, time_why=time_why, units=units,
                       notes=notes, fields={n: (field_of[n] + 1 if n in field_of else 0)
                                            for n in order})


def _lvm_unit(channel, j, channels):
    values, _ = channel.get("Y_Unit_Label", ([], 0))
    k = channels.index(j)
    return values[k] if k < len(values) and values[k] else None


# ------------------------------------------------------------------------ NI TDMS
def open_tdms(path):
    """A TDMS file through npTDMS: every channel of numbers as ``group/channel`` (and by
    its channel name alone when no other group has one so named); a waveform channel's
    ``wf_start_offset`` and ``wf_increment`` give the time."""
    need("nptdms", "tdms", path)
    from nptdms import TdmsFile
    # whatever npTDMS raises while parsing is the file's fault (truncated, corrupt, a
    # data type it does not read): one line, never its traceback
    try:
        tdms = TdmsFile.read(path)
    except Exception as err:  # noqa: BLE001
        raise RecordError(path, f"cannot read TDMS file: {_one_line(err)}") from None
    names, arrays, full, units = [], [], [], {}
    channel_names = {}
    for group in tdms.groups():
        for ch in group.channels():
            channel_names.setdefault(ch.name, []).append(group.name)
    wave = None
    for group in tdms.groups():
        for ch in group.channels():
            try:
                data = ch[:]
            except Exception as err:  # noqa: BLE001 - the file's fault, as above
                raise RecordError(path, f"{group.name}/{ch.name}: cannot read: "
                                  f"{_one_line(err)}") from None
            data = np.asarray(data)
            if data.ndim != 1 or data.dtype.kind not in "fiub":
                continue
            name = ch.name if len(channel_names[ch.name]) == 1 else f"{group.name}/{ch.name}"
            names.append(name)
            full.append(f"{group.name}/{ch.name}")
            arrays.append(data.astype(np.float64))
            props = ch.properties
            if str(props.get("unit_string", "")).strip():
                units[name] = str(props["unit_string"]).strip()
            if wave is None and "wf_increment" in props:
                wave = (name, float(props["wf_increment"]),
                        float(props.get("wf_start_offset", 0.0)), len(data))
    if not names:
        raise RecordError(path, "no channel of numbers in the TDMS file")
    for name, a in zip(names, arrays):
        bad = np.flatnonzero(~np.isfinite(a))
        if bad.size:
            raise RecordError(path, f"{name!r} sample {int(bad[0])}: {a[bad[0]]} is not a "
                              "finite number")
    time_name = time_why = None
    if wave is not None:
        ch, dx, x0, n = wave
        if not (np.isfinite(dx) and dx > 0):
            raise RecordError(path, f"{ch!r}: wf_increment {dx:g} is not a positive time")
        time_name = "time (wf_start_offset + k wf_increment)"
        time_why = f"from {ch!r}'s wf_start_offset and wf_increment"
        names.append(time_name)
        arrays.append(x0 + np.arange(n) * dx)
    order = list(names)

    def locate(row, column, message):
        return RecordError(path, f"{order[column]!r} sample {row}: {message}")

    groups = ", ".join(repr(g.name) for g in tdms.groups())
    return TableSource(path, "tdms", names, arrays, locate,
                       layout=f"TDMS, groups {groups}, {len(full)} channels",
                       time_column=time_name, time_why=time_why, units=units)


def _one_line(err):
    text = " ".join(str(err).split())
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


# ------------------------------------------------------------------------ Excel .xlsx
def open_xlsx(path, sheet=None):
    """A sheet of an Excel workbook through openpyxl (the first sheet unless ``sheet``
    names one or gives its 1-based number): a header row, an optional row of units under
    it, then numbers (or dates and times, read as seconds from the first)."""
    need("openpyxl", "xlsx", path)
    import openpyxl
    from openpyxl.utils import get_column_letter
    # whatever openpyxl (or zipfile, zlib, its XML parser) raises while parsing is the
    # file's fault: one line, never its traceback
    try:
        book = openpyxl.load_workbook(path, read_only=True, data_only=True)
    except Exception as err:  # noqa: BLE001
        raise RecordError(path, f"cannot read Excel workbook: {_one_line(err)}") from None
    try:
        ws, title = _sheet(book, sheet, path)
        rows = [(k, row) for k, row in enumerate(ws.iter_rows(values_only=True), start=1)
                if any(c is not None and str(c).strip() for c in row)]
    except RecordError:
        raise
    except Exception as err:  # noqa: BLE001
        raise RecordError(path, f"cannot read Excel workbook: {_one_line(err)}") from None
    finally:
        book.close()
    if not rows:
        raise RecordError(path, f"sheet {title!r} is empty")

    def cell(row, col):
        return f"sheet {title!r} cell {get_column_letter(col + 1)}{row}"
    head_row, head = rows[0]
    width = max(len(r) for _, r in rows)
    is_header = any(isinstance(c, str) and not _is_number_text(c) for c in head)
    if is_header:
        names = unique_names([("" if c is None else str(c)) or f"column {j + 1}"
                              for j, c in enumerate(list(head) + [None] * (width - len(head)))])
        rows = rows[1:]
    else:
        names = [f"column {j + 1}" for j in range(width)]
    units = {}
    if is_header and rows and all(c is None or (isinstance(c, str) and _looks_unit(c))
                                  for c in rows[0][1]) and any(rows[0][1]):
        units = {names[j]: c.strip() for j, c in enumerate(rows[0][1]) if c}
        rows = rows[1:]
    if not rows:
        raise CSVError(path, head_row, 0, f"sheet {title!r}: no data rows")
    used = [j for j in range(width) if any(j < len(r) and r[j] is not None for _, r in rows)]
    numbers = np.array([k for k, _ in rows])
    columns, notes, bad_columns = {}, [], {}
    for j in used:
        values = np.empty(len(rows))
        first_time = None
        for i, (k, r) in enumerate(rows):
            c = r[j] if j < len(r) else None
            try:
                if isinstance(c, (datetime.datetime, datetime.time, datetime.timedelta)):
                    s = _seconds(c)
                    first_time = s if first_time is None else first_time
                    values[i] = s - first_time
                    continue
                if isinstance(c, bool) or c is None:
                    raise _CellError("missing value" if c is None else f"{c!r} is not a number")
                if isinstance(c, (int, float)):
                    if not np.isfinite(c):
                        raise _CellError(f"{c!r} is not a finite number")
                    values[i] = float(c)
                else:
                    values[i] = parse_number(str(c))
            except ValueError as err:
                bad_columns[names[j]] = CSVError(path, k, j + 1, f"{cell(k, j)}: column "
                                                 f"{names[j]!r}: {err}")
                break
        else:
            columns[names[j]] = values
            if first_time is not None:
                notes.append(f"{names[j]!r} holds dates or times: read as seconds from "
                             "the first")
    order = [n for n in names if n in columns]
    if not order:
        raise next(iter(bad_columns.values()))

    def locate(row, column, message):
        k = int(numbers[row]) if 0 <= row < len(numbers) else 0
        j = names.index(order[column])
        return CSVError(path, k, j + 1, f"{cell(k, j)}: {message}")

    source = TableSource(path, "xlsx", order, [columns[n] for n in order], locate,
                         fields={n: names.index(n) + 1 for n in order},
                         layout=f"Excel workbook, sheet {title!r}, header on row "
                                f"{head_row}" + (", a row of units" if units else "")
                         if is_header else f"Excel workbook, sheet {title!r}, no header",
                         units=units, notes=notes)
    source.unreadable = bad_columns
    return source


class _CellError(ValueError):
    """A cell that is not a number (turned into a CSVError at its row and column)."""


def _sheet(book, sheet, path):
    titles = book.sheetnames
    if sheet is None:
        return book[titles[0]], titles[0]
    text = str(sheet).strip()
    if text in titles:
        return book[text], text
    if text.isdigit() and 1 <= int(text) <= len(titles):
        return book[titles[int(text) - 1]], titles[int(text) - 1]
    raise RecordError(path, f"--sheet {text}: no such sheet (sheets: "
                      f"{', '.join(f'{i + 1} {t!r}' for i, t in enumerate(titles))})")


def _seconds(c):
    if isinstance(c, datetime.timedelta):
        return c.total_seconds()
    if isinstance(c, datetime.time):
        return c.hour * 3600 + c.minute * 60 + c.second + c.microsecond * 1e-6
    return c.timestamp() if c.tzinfo else (c - datetime.datetime(1970, 1, 1)).total_seconds()


def _is_number_text(c):
    try:
        parse_number(c)
    except ValueError:
        return False
    return True


UNIT_WORDS = {"s", "ms", "us", "µs", "ns", "min", "h", "v", "mv", "kv", "m", "mm", "um",
              "µm", "nm", "sec", "volt", "volts", "hz", "a", "ma", "n", "°c", "%", "au",
              "a.u.", "counts"}


def _looks_unit(text):
    """Whether a field of the line under a header reads as a unit (``s``, ``[V]``,
    ``(µm)``)."""
    t = text.strip().strip("[]()").strip().lower().replace("μ", "µ")
    return t in UNIT_WORDS and not _is_number_text(t)


def looks_unit(text):
    return _looks_unit(text)


def open_lab_source(path, kind, sheet=None):
    path = os.fspath(path)
    if kind == "lvm":
        return open_lvm(path)
    if kind == "tdms":
        return open_tdms(path)
    if kind == "xlsx":
        return open_xlsx(path, sheet)
    raise InvalidArgumentError(f"unknown lab format {kind!r}")
