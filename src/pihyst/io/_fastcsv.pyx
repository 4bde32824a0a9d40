# cython: boundscheck=False, wraparound=False, cdivision=True, language_level=3
"""The default install's fast path for numeric text: a parser of blocks of delimited
numbers and a writer of float columns, in C over the bytes (no pyarrow needed).

:func:`parse_block` takes a block (bytes, LF line ends, whole lines) only when every line
has the dialect's number of fields and every wanted field is a decimal number of the
grammar of :mod:`pihyst.io._numbers` (``1.5``, ``-1.5e-3``, ``+2``, ``.5``, ``1.``),
finite; else it returns None and the careful reader reads the block or names the fault.
Values are those of ``float(text)`` bit for bit (see :func:`_decimal_to_double`).

:func:`format_rows` writes float columns as CSV rows, each value exactly as Python's
``repr`` writes it: the shortest decimal that reads back to the same float (see
:func:`_shortest_digits`). Its plain twin is ``pihyst.io._csv.format_rows(...,
engine="numpy")``; the tests compare them.

Both use the one fact that makes decimal <-> binary conversion cheap: an integer of up
to 64 bits times an exact power of ten, rounded once, is within half a unit in the last
place of the exact result. With 64-bit ``long double`` (x86) that is close enough to
decide almost every case; the few too close to call, and every case on platforms
without 64-bit ``long double``, go to Python's own correctly rounded conversions
(``PyOS_string_to_double``, ``PyOS_double_to_string``).
"""

import numpy as np

from cpython.bytes cimport PyBytes_FromStringAndSize
from cpython.mem cimport PyMem_Free
from cpython.ref cimport PyObject
from libc.math cimport fabsl, isfinite, signbit
from libc.stdint cimport uint64_t
from libc.stdlib cimport free, malloc
from libc.string cimport memcpy


cdef extern from "Python.h":
    double PyOS_string_to_double(const char *s, char **endptr,
                                 PyObject *overflow_exception) except? -1.0
    char *PyOS_double_to_string(double val, char format_code, int precision, int flags,
                                int *ptype) except NULL


cdef extern from "math.h" nogil:
    long double frexpl(long double x, int *exp)
    long double ldexpl(long double x, int exp)


cdef extern from "float.h":
    int LDBL_MANT_DIG
    int FLT_EVAL_METHOD
    double DBL_MIN


# exact powers of ten: in double up to 10^22 (5^22 < 2^53), in long double up to 10^27
# (5^27 < 2^64)
cdef double P10[23]
cdef long double P10L[28]
cdef int _i
P10[0] = 1.0
P10L[0] = 1.0
for _i in range(1, 23):
    P10[_i] = P10[_i - 1] * 10.0
for _i in range(1, 28):
    P10L[_i] = P10L[_i - 1] * 10.0
# the shortcuts need one rounding per operation: doubles evaluated as doubles, and a
# long double with a 64-bit significand
cdef bint DOUBLE_EXACT = FLT_EVAL_METHOD == 0


cdef bint _long_double_has_64_bits(double one):
    """Whether long double is an IEEE-style binary type of at least 64 significant bits
    (x87's 64, or a 113-bit quad) that keeps them at run time (the x87's precision
    control can be set lower than the type's); not the double-double of some PowerPC
    systems."""
    cdef long double a = one
    return (LDBL_MANT_DIG == 64 or LDBL_MANT_DIG == 113) and \
        (a + 1.0842021724855044e-19) - a != 0                                # 1 + 2^-63


cdef bint LONG_EXACT = DOUBLE_EXACT and _long_double_has_64_bits(float("1"))
cdef long double TWO_M63 = 1.0842021724855044e-19    # 2^-63
# adding this rounds a long double below half of it to an integer (2^63 on x87)
cdef long double ROUNDER = ldexpl(1.0, LDBL_MANT_DIG - 1)
cdef uint64_t MANTISSA = 0xFFFFFFFFFFFFF
cdef uint64_t TWO_53 = 9007199254740992


def has_long_double_path():
    """Whether this build decides conversions with 64-bit long double (else every value
    beyond the double shortcuts takes Python's conversion)."""
    return LONG_EXACT


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


cdef bint _decimal_to_double(const char *s, Py_ssize_t i, Py_ssize_t end,
                             double *out) noexcept nogil:
    """The number s[i:end] (of the grammar, checked before) as the correctly rounded
    double, when the shortcuts decide it; False for Python's conversion to do it.

    The number is M x 10^E with M the (at most 19) significant digits. With M <= 2^53
    and |E| <= 22 both are exact doubles and one multiplication or division rounds
    correctly. Else with M < 2^64 and |E| <= 27, r = M x 10^E in long double is within
    half a unit of its 64-bit significand of the exact value; rounding r to double is
    then correct unless r lies within a unit of a midpoint between two doubles (the
    low 11 of its 64 bits near 0x400), which goes to Python."""
    cdef bint negative = False
    cdef uint64_t m = 0
    cdef int digits = 0, e = 0, exp_sign = 1, exp = 0
    cdef long double r, frac
    cdef uint64_t bits
    cdef int ex, low
    if s[i] == 43 or s[i] == 45:
        negative = s[i] == 45
        i += 1
    while i < end and _is_digit(s[i]):
        if digits < 19:
            m = m * 10 + <uint64_t>(s[i] - 48)
            if m:
                digits += 1
        else:
            if s[i] != 48:
                return False          # more than 19 significant digits
            e += 1
        i += 1
    if i < end and s[i] == 46:
        i += 1
        while i < end and _is_digit(s[i]):
            if digits < 19:
                m = m * 10 + <uint64_t>(s[i] - 48)
                if m:
                    digits += 1
                e -= 1
            elif s[i] != 48:
                return False
            i += 1
    if i < end and (s[i] == 101 or s[i] == 69):
        i += 1
        if s[i] == 43 or s[i] == 45:
            exp_sign = -1 if s[i] == 45 else 1
            i += 1
        while i < end:
            if exp > 10000:
                return False
            exp = exp * 10 + (s[i] - 48)
            i += 1
        e += exp_sign * exp
    if m == 0:
        out[0] = -0.0 if negative else 0.0
        return True
    if not DOUBLE_EXACT:
        return False
    if m <= TWO_53 and -22 <= e <= 22:
        out[0] = <double>m * P10[e] if e >= 0 else <double>m / P10[-e]
    elif LONG_EXACT and -27 <= e <= 27:
        r = <long double>m * P10L[e] if e >= 0 else <long double>m / P10L[-e]
        frac = frexpl(r, &ex)                       # r = frac 2^ex, frac in [0.5, 1)
        bits = <uint64_t>ldexpl(frac, 64)           # the 64-bit significand, exactly
        low = <int>(bits & 0x7FF)
        if 0x3FF <= low <= 0x401:
            return False
        out[0] = <double>r
    else:
        return False
    if negative:
        out[0] = -out[0]
    return True


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
                if not _decimal_to_double(s, a, stop, &v):
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


cdef inline long double _scaled(double x, int k) noexcept nogil:
    """x 10^k rounded once to long double (|k| <= 27)."""
    return <long double>x * P10L[k] if k >= 0 else <long double>x / P10L[-k]


cdef inline long double _unscaled(uint64_t n, int k) noexcept nogil:
    """n 10^-k rounded once to long double (|k| <= 27)."""
    return <long double>n / P10L[k] if k >= 0 else <long double>n * P10L[-k]


cdef int _shortest_digits(double x, uint64_t *digits, int *decpt) noexcept nogil:
    """The shortest decimal that reads back to x > 0 (finite), nearest to x among those:
    x ~ 0.D x 10^decpt with D the returned number of digits of ``digits``; 0 when the
    shortcut cannot decide (Python's repr then writes x).

    For p = 15, 16, 17 significant digits: N = round(x 10^k) (k puts N in
    [10^(p-1), 10^p)), the nearest p-digit decimal, and whether N 10^-k lies inside the
    interval of reals that round to x, (x - gap / 2, x + gap / 2); the first p for which
    it does gives the answer. Why the nearest is the one: two 15-digit decimals are
    further apart than x's interval is wide, so a round-tripping decimal of 15 digits or
    fewer (padded with zeros) is the nearest 15-digit one; at 16 and 17 digits repr takes
    the nearest that round-trips, and when the nearest does not, no other does (the
    interval is symmetric around x; powers of two, where it is not, are left to Python).
    The nearest 17-digit decimal is within half a 17th digit < gap / 2 of x: it always
    round-trips. Each step is one long double rounding (relative error <= 2^-64); a
    rounding of N, or a comparison with the interval, that this error could change is
    left to Python."""
    cdef uint64_t bits, value, ten_p
    cdef int biased, e10, k, p, kp, n
    cdef double half_gap
    cdef long double q, r, d, margin, y, lo, hi, tol
    memcpy(&bits, &x, 8)
    biased = <int>((bits >> 52) & 0x7FF)
    if not LONG_EXACT or biased < 60 or (bits & MANTISSA) == 0:
        return 0       # tiny (its gap is not a normal double) or a power of two
    bits = (<uint64_t>(biased - 53)) << 52
    memcpy(&half_gap, &bits, 8)            # 2^(exponent - 53): half of x's gap
    # the interval's ends, exact in long double (54 significant bits)
    lo = <long double>x - half_gap
    hi = <long double>x + half_gap
    # floor(log10(2^b)) = floor(b x 0.30103) = (b x 78913) >> 18 for |b| < 1600: the
    # exponent of x's leading digit or one less
    e10 = ((biased - 1023) * 78913) >> 18
    k = 16 - e10
    if k < -26 or k > 26:
        return 0
    q = _scaled(x, k)
    if q >= 1e17:
        e10 += 1
        k -= 1
        q = _scaled(x, k)
    if q < 1e16 or q >= 1e17 or k - 2 < -27:
        return 0
    ten_p = 100000000000000      # 10^14, times 10 before each p
    for p in range(15, 18):
        ten_p *= 10
        kp = k - (17 - p)
        if p < 17:
            q = _scaled(x, kp)
        else:
            q = _scaled(x, k)
        # round to the nearest integer: q + 2^63 has no fraction bits left (q < 2^62)
        r = (q + ROUNDER) - ROUNDER
        d = q - r                        # exactly; in [-1/2, 1/2]
        margin = q * TWO_M63
        if 0.5 - fabsl(d) <= margin:
            return 0
        value = <uint64_t>r
        if p < 17:
            y = _unscaled(value, kp)
            tol = y * TWO_M63
            if not (lo + tol < y < hi - tol):
                if lo - tol < y < hi + tol:
                    return 0             # too close to an end to tell
                continue
        n = p
        decpt[0] = e10 + 1
        if value == ten_p:               # rounded up to 10^p: one digit, one place up
            value = 1
            n = 1
            decpt[0] += 1
        while value % 10 == 0:
            value //= 10
            n -= 1
        digits[0] = value
        return n
    return 0


cdef inline Py_ssize_t _put_int(char *out, uint64_t value, int n) noexcept nogil:
    """The n decimal digits of value at out."""
    cdef int i
    for i in range(n - 1, -1, -1):
        out[i] = <char>(48 + value % 10)
        value //= 10
    return n


cdef Py_ssize_t _format_repr(double x, char *out) except -1:
    """x written at out exactly as Python's repr writes it; the number of bytes (<= 25)."""
    cdef uint64_t digits
    cdef int decpt, n, e, i
    cdef Py_ssize_t at = 0
    cdef char tmp[20]
    cdef char *text
    cdef Py_ssize_t length
    if isfinite(x) and x != 0.0:
        n = _shortest_digits(-x if x < 0 else x, &digits, &decpt)
    else:
        n = 0
    if n == 0:
        if x == 0.0:
            if signbit(x):
                memcpy(out, b"-0.0", 4)
                return 4
            memcpy(out, b"0.0", 3)
            return 3
        text = PyOS_double_to_string(x, b"r", 0, 2, NULL)   # Py_DTSF_ADD_DOT_0
        length = 0
        while text[length]:
            out[length] = text[length]
            length += 1
        PyMem_Free(text)
        return length
    if x < 0:
        out[0] = 45
        at = 1
    _put_int(tmp, digits, n)
    # the layout of repr (Python/pystrtod.c, format_float_short, mode 'r')
    if decpt <= -4 or decpt > 16:
        out[at] = tmp[0]
        at += 1
        if n > 1:
            out[at] = 46
            memcpy(out + at + 1, tmp + 1, n - 1)
            at += n
        e = decpt - 1
        out[at] = 101
        out[at + 1] = 45 if e < 0 else 43
        at += 2
        if e < 0:
            e = -e
        if e >= 100:
            at += _put_int(out + at, e, 3)
        else:
            at += _put_int(out + at, e, 2)
    elif decpt <= 0:
        out[at] = 48
        out[at + 1] = 46
        at += 2
        for i in range(-decpt):
            out[at] = 48
            at += 1
        memcpy(out + at, tmp, n)
        at += n
    elif decpt >= n:
        memcpy(out + at, tmp, n)
        at += n
        for i in range(decpt - n):
            out[at] = 48
            at += 1
        out[at] = 46
        out[at + 1] = 48
        at += 2
    else:
        memcpy(out + at, tmp, decpt)
        out[at + decpt] = 46
        memcpy(out + at + decpt + 1, tmp + decpt, n - decpt)
        at += n + 1
    return at


def format_rows(columns):
    """CSV rows (bytes, LF line ends, no header) of equal-length float64 columns, each
    value as ``repr`` writes it (``nan``, ``inf`` included)."""
    cdef Py_ssize_t k = len(columns), n, row, j, at = 0
    if k == 0:
        return b""
    arrays = [np.ascontiguousarray(c, dtype=np.float64) for c in columns]
    n = len(arrays[0])
    for a in arrays:
        if a.ndim != 1 or len(a) != n:
            raise ValueError("format_rows takes 1-d columns of one length")
    cdef double **data = <double **>malloc(k * sizeof(double *))
    cdef char *out = <char *>malloc(n * k * 26 + 1)
    cdef const double[::1] view
    if data == NULL or out == NULL:
        free(data)
        free(out)
        raise MemoryError
    try:
        for j in range(k):
            view = arrays[j]
            data[j] = <double *>&view[0] if n else NULL
        for row in range(n):
            for j in range(k):
                at += _format_repr(data[j][row], out + at)
                out[at] = 44 if j < k - 1 else 10
                at += 1
        return PyBytes_FromStringAndSize(out, at)
    finally:
        free(data)
        free(out)

