"""The layout of a delimited text record, found from its first lines: separator (comma,
semicolon, tab or runs of whitespace), decimal mark, header, comment lines, line endings
(LF, CRLF or CR alone).

Rules (docs/records.md):

- a line whose first non-blank character is ``#`` is a comment; blank lines are ignored;
- the separator is the first of tab, semicolon, comma that splits every sampled line
  into the same number (> 1) of fields, else runs of whitespace; a file with no
  consistent split takes the first separator that splits its first line;
- the decimal mark is a comma only when the separator is not, and the numbers are written
  ``1,5`` (none with a point);
- the first line is a header when one of its non-empty fields is not a number.
"""

import re
from dataclasses import dataclass

from pihyst.io._numbers import is_number, looks_decimal_comma

BOM = b"\xef\xbb\xbf"
HEAD_BYTES = 1 << 20
SAMPLE_LINES = 200
SEPARATOR_NAMES = {",": ",", "comma": ",", ";": ";", "semicolon": ";", "tab": "\t", "\t": "\t",
                   "whitespace": None, "space": None, " ": None}
AUTO = "auto"
_LINE = re.compile(rb"([^\r\n]*)(\r\n|\r|\n)")


class FieldError(ValueError):
    """A line that cannot be split into fields; ``column`` is the 1-based field."""

    def __init__(self, column, message):
        super().__init__(message)
        self.column = column


def split_fields(line, separator):
    """The fields of one line (quotes removed; ``""`` inside quotes is a quote).
    ``separator`` None splits at runs of whitespace."""
    if separator is None:
        return line.split()
    if '"' not in line:
        return line.split(separator)
    fields, i, n = [], 0, len(line)
    while True:
        j = i
        while j < n and line[j] in " \t" and line[j] != separator:
            j += 1
        if j < n and line[j] == '"':
            parts, k = [], j + 1
            while True:
                q = line.find('"', k)
                if q < 0:
                    raise FieldError(len(fields) + 1, "unterminated quote (a quoted field "
                                     "that goes on past the end of the line)")
                parts.append(line[k:q])
                if line.startswith('"', q + 1):
                    parts.append('"')
                    k = q + 2
                    continue
                break
            end = line.find(separator, q + 1)
            rest = line[q + 1:] if end < 0 else line[q + 1:end]
            if rest.strip():
                raise FieldError(len(fields) + 1, f"text {rest.strip()!r:.30} after a "
                                 "closing quote")
            fields.append("".join(parts))
        else:
            end = line.find(separator, i)
            fields.append(line[i:] if end < 0 else line[i:end])
        if end < 0:
            return fields
        i = end + 1


def decode_line(raw):
    """A line's text: UTF-8, else Windows-1252 (instrument software writes 'µm' so)."""
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("cp1252", errors="replace")


def is_skipped(text):
    """Blank lines and comment lines carry no data."""
    stripped = text.lstrip()
    return not stripped or stripped.startswith("#")


@dataclass(frozen=True)
class Dialect:
    separator: object      # ",", ";", "\t", or None for runs of whitespace
    decimal: str           # "." or ","
    header: tuple          # column names, () when the file has no header
    header_line: int       # 1-based line of the header, 0 when none
    n_fields: int          # fields per data line
    data_offset: int       # byte offset where the data lines start
    data_line: int         # 1-based line number at data_offset
    first_line: int        # 1-based line of the first meaningful line (header or data)

    def describe(self):
        sep = {",": "comma", ";": "semicolon", "\t": "tab", None: "whitespace"}[self.separator]
        dec = ", decimal comma" if self.decimal == "," else ""
        head = (f"header on line {self.header_line}" if self.header_line else "no header")
        columns = "1 column" if self.n_fields == 1 else f"{self.n_fields} columns"
        return f"{sep}-separated{dec}, {head}, {columns}"

    def where(self):
        """What data lines are compared with, for messages."""
        return "the header" if self.header_line else f"line {self.first_line}"


def head_lines(head, at_eof, limit=SAMPLE_LINES):
    """(line number, byte offset after the line, text) of the complete lines of ``head``,
    up to the ``limit``-th meaningful one."""
    start = len(BOM) if head.startswith(BOM) else 0
    out, number, pos, meaningful = [], 1, start, 0
    # complete lines only: on a partial last line (a line longer than the head) the
    # pattern would be tried at each of its bytes, to its end each time (quadratic)
    complete = max(head.rfind(b"\n"), head.rfind(b"\r")) + 1
    for m in _LINE.finditer(head, start, max(complete, start)):
        text = decode_line(m.group(1))
        out.append((number, m.end(), text))
        number += 1
        pos = m.end()
        meaningful += not is_skipped(text)
        if meaningful >= limit:
            return start, out
    if at_eof and pos < len(head):
        out.append((number, len(head), decode_line(head[pos:])))
    return start, out


def _consistent(lines, separator):
    try:
        counts = {len(split_fields(t, separator)) for t in lines}
    except FieldError:
        return 0
    return counts.pop() if len(counts) == 1 else 0


def _first_count(line, separator):
    try:
        return len(split_fields(line, separator))
    except FieldError:
        return 0


def _numeric(lines, separator):
    """Whether every non-empty field of ``lines`` is a number (either decimal mark unless
    the separator is the comma)."""
    for text in lines:
        try:
            fields = split_fields(text, separator)
        except FieldError:
            return False
        for f in fields:
            if f.strip() and not (is_number(f) or (separator != "," and is_number(f, ","))):
                return False
    return True


def choose_separator(lines, decimal=None):
    """The separator of a list of meaningful lines (see the module's rules): of the
    separators that split every line alike, the first that leaves only numbers below the
    first line, else the first of them."""
    candidates = ("\t", ";", None) if decimal == "," else ("\t", ";", ",", None)
    consistent = [sep for sep in candidates if _consistent(lines, sep) > 1]
    data = lines[1:] or lines
    for sep in consistent:
        if _numeric(data, sep):
            return sep
    if consistent:
        return consistent[0]
    for sep in candidates:
        if sep is not None and _first_count(lines[0], sep) > 1:
            return sep
    return None if len(lines[0].split()) > 1 else ","


def choose_decimal(lines, separator):
    if separator == ",":
        return "."
    comma = point = False
    for text in lines:
        try:
            fields = split_fields(text, separator)
        except FieldError:
            continue
        for f in fields:
            comma = comma or looks_decimal_comma(f)
            point = point or ("." in f and is_number(f, "."))
    return "," if comma and not point else "."


def sniff(head, at_eof, *, separator=AUTO, decimal=None):
    """The :class:`Dialect` of a file whose first bytes are ``head`` (``at_eof``: the
    whole file); ``separator`` (None: runs of whitespace) and ``decimal`` as found unless
    given. Returns None when the file has no meaningful line."""
    start, lines = head_lines(head, at_eof)
    meaningful = [(n, end, t) for n, end, t in lines if not is_skipped(t)][:SAMPLE_LINES]
    if not meaningful:
        return None
    texts = [t for _, _, t in meaningful]
    sep = choose_separator(texts, decimal) if separator == AUTO else separator
    data_texts = texts[1:] or texts
    dec = decimal or choose_decimal(data_texts, sep)
    first_number, first_end, first = meaningful[0]
    try:
        fields = split_fields(first, sep)
    except FieldError:
        fields = [first]
    has_header = any(f.strip() and not is_number(f, dec) for f in fields)
    if has_header:
        return Dialect(sep, dec, tuple(f.strip() for f in fields), first_number, len(fields),
                       first_end, first_number + 1, first_number)
    return Dialect(sep, dec, (), 0, len(fields), start, 1, first_number)
