"""Checks of the Python API's array and size arguments, shared by the models, the
compensators, ``pihyst.fit`` and the command line (one rule, one message):

- :func:`real_array`: a signal must hold real numbers: a complex array (whose imaginary
  part NumPy would drop with only a warning), dates and durations (``datetime64``,
  ``timedelta64``, which NumPy turns into counts of an unstated unit) and object arrays
  are refused with :class:`~pihyst.exceptions.InvalidArgumentError`;
- :func:`check_fit_sizes`: the fit's candidate grid and threshold lists are limited to
  :data:`MAX_CANDIDATES` (the subset search's cost grows fast with them), refused with
  :class:`~pihyst.exceptions.ResourceLimitError` before anything is allocated.
"""

import numpy as np

from pihyst.exceptions import InvalidArgumentError, ResourceLimitError

#: the most candidate thresholds (``n_candidates``, ``candidates``), operators
#: (``n_operators``) or ``thresholds`` a fit takes: ``fit --candidates``,
#: ``--n-operators`` and ``--thresholds`` of the command line, and ``pihyst.fit``
MAX_CANDIDATES = 128

_KINDS = {"c": "complex numbers", "M": "dates", "m": "durations", "O": "Python objects",
          "V": "records (a structured array)"}


def real_array(values, name="input"):
    """``values`` unchanged, after checking that they are not an array of complex
    numbers, dates, durations or objects (InvalidArgumentError naming ``name``)."""
    dtype = getattr(values, "dtype", None)
    if dtype is None and isinstance(values, (list, tuple)):
        dtype = _list_dtype(values)
    kind = getattr(dtype, "kind", None)
    if kind in _KINDS:
        hint = {"c": "; give the real part (np.real) if that is what is meant",
                "M": "; give times in seconds as floats",
                "m": "; give durations in seconds as floats"}.get(kind, "; give floats")
        raise InvalidArgumentError(f"{name} must be real numbers, got {_KINDS[kind]} "
                                   f"({dtype}){hint}")
    return values


def _list_dtype(values):
    """The dtype NumPy would give a short list, for the check (a long list is looked at
    by its first items: mixing kinds after them fails in the float conversion)."""
    head = values[:64]
    if any(isinstance(v, (complex, np.complexfloating)) for v in head):
        return np.dtype(complex)
    if any(isinstance(v, (np.datetime64, np.timedelta64)) for v in head):
        return np.asarray(head).dtype
    return None


def check_fit_sizes(*, n_candidates=None, n_operators=None, thresholds=None,
                    candidates=None):
    """ResourceLimitError, before anything is allocated, if a fit's size argument is
    beyond :data:`MAX_CANDIDATES` (the message names the argument)."""
    for key, value in (("n_candidates", n_candidates), ("n_operators", n_operators)):
        if value is None or isinstance(value, bool):
            continue
        try:
            too_many = value > MAX_CANDIDATES
        except TypeError:
            continue          # not a number: the fit's own check says so
        if too_many:
            raise ResourceLimitError(f"{key}: must be at most "
                                     f"{MAX_CANDIDATES:,}, got {value}")
    for key, value in (("thresholds", thresholds), ("candidates", candidates)):
        try:
            n = len(value)
        except TypeError:
            continue
        if n > MAX_CANDIDATES:
            raise ResourceLimitError(f"{key}: {n:,} values, at most "
                                     f"{MAX_CANDIDATES:,}")
