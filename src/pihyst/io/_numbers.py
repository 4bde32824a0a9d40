"""Decimal numbers as lab instruments write them, and nothing else.

Accepted: ``1.5``, ``-1.5e-3``, ``+2``, ``.5``, ``1.`` (and ``1,5`` when the decimal mark
is a comma). Refused: Python-only syntax (``1_5``, ``0x10``), NaN and infinity in any
spelling, empty fields. :func:`parse_number` says why a field is refused.
"""

import math
import re

_PATTERNS = {
    mark: re.compile(r"[+-]?(?:[0-9]+(?:%s[0-9]*)?|%s[0-9]+)(?:[eE][+-]?[0-9]+)?\Z"
                     % (re.escape(mark), re.escape(mark)))
    for mark in ".,"
}
_NON_FINITE = re.compile(r"[+-]?(?:nan|inf|infinity)\Z", re.IGNORECASE)


def parse_number(text, decimal="."):
    """The float written in ``text`` (surrounding spaces ignored), or raise ``ValueError``
    with a reason that fits after the quoted field: ``'abc' is not a number``."""
    field = text.strip()
    shown = repr(field) if len(field) <= 40 else repr(field[:37] + "...")
    if _PATTERNS[decimal].match(field):
        value = float(field.replace(",", ".") if decimal == "," else field)
        if math.isinf(value):
            raise ValueError(f"{shown} is too large to be a finite number")
        return value
    if not field:
        raise ValueError("missing value")
    if _NON_FINITE.match(field):
        raise ValueError(f"{shown} is not a finite number")
    if decimal == "." and _PATTERNS[","].match(field):
        raise ValueError(f"{shown} is not a number (a decimal comma? this file's numbers "
                         "use '.'; pass --decimal-comma if they use ',')")
    if decimal == "," and _PATTERNS["."].match(field):
        raise ValueError(f"{shown} is not a number (this file's numbers use a decimal comma)")
    return _refuse(shown)


def _refuse(shown):
    raise ValueError(f"{shown} is not a number")


def is_number(text, decimal="."):
    """Whether ``text`` is a number :func:`parse_number` accepts."""
    return bool(_PATTERNS[decimal].match(text.strip()))


def looks_decimal_comma(text):
    """Whether ``text`` is a number written with a decimal comma (``1,5``, ``-0,25e3``)."""
    field = text.strip()
    return "," in field and bool(_PATTERNS[","].match(field))
