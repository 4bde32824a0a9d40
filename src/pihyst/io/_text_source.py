"""A delimited text record read block by block: the fast engine on each block, the
careful reader where the engine refuses one, and exact line numbers for any sample."""

import os

from pihyst.exceptions import CSVError, InvalidArgumentError
from pihyst.io._text_check import check_block, data_line_of
from pihyst.io._text_engines import engine_name, read_block
from pihyst.io._text_format import AUTO, HEAD_BYTES, SEPARATOR_NAMES, sniff

BLOCK_BYTES = 1 << 23


class TextSource:
    """A delimited text file. ``columns`` are the header's names (``()`` without one)."""

    kind = "text"

    def __init__(self, path, *, separator=None, decimal_comma=None, block_bytes=None):
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
        if b"\0" in head:
            raise CSVError(self.path, 1, 0, "not a text file (it holds NUL bytes); "
                           "binary records: .npy, .npz, .mat, .h5, .parquet")
        self.dialect = sniff(head, at_eof, separator=sep, decimal=decimal)
        if self.dialect is None and not at_eof:
            # nothing but blank or comment lines, then a line longer than the head
            line = head.count(b"\n") + 1
            raise CSVError(self.path, line, 0, f"a line longer than {len(head):,} bytes "
                           "before any data line: not a record")
        if self.dialect is None:
            raise CSVError(self.path, 1, 0, "empty file: no data lines")
        self.columns = self.dialect.header

    # ---------------------------------------------------------------- describing
    def metadata(self):
        d = self.dialect
        return {"format": "text", "layout": d.describe(), "engine": engine_name()}

    def label(self, index):
        """How messages name the field ``index`` (0-based)."""
        if self.columns:
            return repr(self.columns[index])
        return f"{index + 1}"

    # ---------------------------------------------------------------- reading
    def _blocks(self):
        """(first line, block, bytes read so far) of the data part: whole lines with LF
        line ends."""
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
        for first_line, block, done in self._blocks():
            values = read_block(block, self.dialect, wanted)
            if values is None:
                values = check_block(self.path, block, first_line, self.dialect, wanted,
                                     labels)
            rows += len(values)
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
        line = data_line_of(((first, block) for first, block, _ in self._blocks()),
                            self.dialect, row)
        return (line or 0), index + 1

    def error(self, row, index, message):
        line, column = self.location(row, index)
        return CSVError(self.path, line, column, message)


def _lf(data):
    if b"\r" in data:
        data = data.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    return data
