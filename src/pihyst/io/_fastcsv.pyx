# cython: boundscheck=False, wraparound=False, language_level=3
"""The default install's fast path for numeric text blocks: a parser of delimited
numbers in C over the bytes (no pyarrow needed).

:func:`parse_block` takes a block (bytes, LF line ends, whole lines) only when every line
has the dialect's number of fields and every wanted field is a decimal number of the
grammar of :mod:`pihyst.io._numbers` (``1.5``, ``-1.5e-3``, ``+2``, ``.5``, ``1.``),
finite; else it returns None and the careful reader reads the block or names the fault.
Conversion is Python's own correctly rounded one (``PyOS_string_to_double``), so the
values are those of ``float(text)`` bit for bit.
"""

import numpy as np

from cpython.ref cimport PyObject
from libc.math cimport isfinite
from libc.string cimport memcpy


cdef extern from "Python.h":
    double PyOS_string_to_double(const char *s, char **endptr,
                                 PyObject *overflow_exception) except? -1.0


cdef inline bint _is_digit(char c) noexcept nogil:
    return c >= 48 and c <= 57


cdef inline bint _blank(char c) noexcept nogil:
    return c == 32 or c == 9 or c == 13


cdef Py_ssize_t _number_end(const char *s, Py_ssize_t i, Py_ssize_t end) noexcept nogil:
    """The end of a number of the grammar starting at s[i] (within end), or -1."""
    cdef Py_ssize_t digits = 0
    if i < end and (s[i] == 43 or s[i] == 45):        # + -
        i += 1
    while i < end and _is_digit(s[i]):
        i += 1
        digits += 1
    if i < end and s[i] == 46:                        # .
        i += 1
        while i < end and _is_digit(s[i]):
            i += 1
            digits += 1
    if digits == 0:
        return -1
    if i < end and (s[i] == 101 or s[i] == 69):       # e E
        i += 1
        if i < end and (s[i] == 43 or s[i] == 45):
            i += 1
        digits = 0
        while i < end and _is_digit(s[i]):
            i += 1
            digits += 1
        if digits == 0:
            return -1
    return i


def parse_block(bytes block, separator, Py_ssize_t n_fields, wanted):
    """The wanted fields (0-based) of every non-blank line of ``block`` as an (n, k)
    float array, or None when the block is not plain numbers (see the module)."""
    cdef const char *s = block
    cdef Py_ssize_t size = len(block)
    cdef int sep = -1 if separator is None else ord(separator)
    cdef Py_ssize_t k = len(wanted)
    cdef Py_ssize_t n_lines = block.count(b"\n") + 1
    cdef Py_ssize_t i = 0, line_end, a, b, field, row = 0, j, stop
    cdef char buf[80]
    cdef char *endp
    cdef double v
    slot = np.full(n_fields, -1, dtype=np.intp)
    for j in range(k):
        slot[wanted[j]] = j
    cdef Py_ssize_t[:] where = slot
    out = np.empty((n_lines, k))
    cdef double[:, :] o = out
    if b'"' in block or b"#" in block:
        return None
    while i < size:
        line_end = i
        while line_end < size and s[line_end] != 10:
            line_end += 1
        # a blank line (spaces only) carries no data
        a = i
        while a < line_end and _blank(s[a]):
            a += 1
        if a == line_end:
            i = line_end + 1
            continue
        field = 0
        a = i
        while True:
            if sep < 0:
                while a < line_end and _blank(s[a]):
                    a += 1
                if a >= line_end:
                    break
                b = a
                while b < line_end and not _blank(s[b]):
                    b += 1
                stop = b
            else:
                b = a
                while b < line_end and s[b] != sep:
                    b += 1
                stop = b
            if field >= n_fields:
                return None
            j = where[field]
            if j >= 0:
                while a < stop and _blank(s[a]):
                    a += 1
                while stop > a and _blank(s[stop - 1]):
                    stop -= 1
                if stop - a == 0 or stop - a >= 79 or _number_end(s, a, stop) != stop:
                    return None
                memcpy(buf, s + a, stop - a)
                buf[stop - a] = 0
                try:
                    v = PyOS_string_to_double(buf, &endp, NULL)
                except ValueError:
                    return None
                if not isfinite(v):
                    return None
                o[row, j] = v
            field += 1
            if sep < 0:
                a = b
            else:
                if b >= line_end:
                    break
                a = b + 1
        if field != n_fields:
            return None
        row += 1
        i = line_end + 1
    return out[:row]
