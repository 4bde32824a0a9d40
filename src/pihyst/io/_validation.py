"""A model judged on a record: its prediction of the record's voltage against the
measured displacement, overall and cycle by cycle (docs/records.md)."""

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from pihyst.exceptions import InvalidArgumentError

SCHMITT_BAND = 0.1


@dataclass(frozen=True)
class Errors:
    """Errors (measured - predicted) of a set of samples, in µm and % of ``span``."""

    samples: int
    mean_abs: float
    rms: float
    max_abs: float
    at: int          # index of the largest error
    span: float      # the measured range the percentages refer to

    @classmethod
    def of(cls, e, span, offset=0):
        a = np.abs(e)
        i = int(np.argmax(a))
        return cls(int(e.size), float(a.mean()), float(np.sqrt(np.mean(e * e))),
                   float(a[i]), int(offset + i), float(span))

    def pct(self, value):
        return 100.0 * value / self.span if self.span > 0 else float("nan")

    def to_dict(self):
        return {"samples": self.samples, "mean_abs_um": self.mean_abs, "rms_um": self.rms,
                "max_abs_um": self.max_abs, "max_at_sample": self.at,
                "mean_abs_pct": self.pct(self.mean_abs), "rms_pct": self.pct(self.rms),
                "max_abs_pct": self.pct(self.max_abs)}


@dataclass(frozen=True)
class Validation:
    """The result of :func:`validate_model`.

    Errors are measured - predicted, in µm and in % of the measured range of the judged
    samples.

    Parameters
    ----------
    errors : Errors
        Over the judged samples: ``samples``, ``mean_abs``, ``rms``, ``max_abs`` (µm),
        ``at`` (the sample of the largest) and ``span``.
    shifted : Errors
        The same with the output offset re-fitted to this record's sensor zero.
    shift : float
        That offset (µm).
    cycles : list of (int, int, Errors)
        ``(start, stop, errors)`` per cycle of the input.
    predicted : ndarray
        The model's prediction of every sample.
    first : int
        The first judged sample.

    Examples
    --------
    >>> import pihyst
    >>> from pihyst.io import validate_model
    >>> v = validate_model(pihyst.ClassicalPI([0], [0.5]), [0, 10, 0], [0.0, 5.5, 0.0])
    >>> v.errors.max_abs, v.errors.at, round(v.shift, 6)
    (0.5, 1, 0.166667)
    """

    errors: Errors
    shifted: Errors
    shift: float
    cycles: list
    predicted: np.ndarray = field(repr=False)
    first: int = 0

    def to_dict(self) -> dict[str, Any]:
        """The result as plain JSON values (µm and %), as the command line writes it.

        Returns
        -------
        dict
            ``errors``, ``offset_refitted`` (with ``shift_um``), ``first_judged_sample``
            and ``cycles`` (``start``, ``stop`` and the errors of each).

        Examples
        --------
        >>> import pihyst
        >>> from pihyst.io import validate_model
        >>> v = validate_model(pihyst.ClassicalPI([0], [0.5]), [0, 10, 0], [0.0, 5.5, 0.0])
        >>> d = v.to_dict()
        >>> d["errors"]["max_abs_um"], d["errors"]["max_abs_pct"], len(d["cycles"])
        (0.5, 9.090909090909092, 1)
        """
        return {"errors": self.errors.to_dict(), "offset_refitted": {
            "shift_um": self.shift, **self.shifted.to_dict()},
            "first_judged_sample": self.first,
            "cycles": [{"start": a, "stop": b, **e.to_dict()} for a, b, e in self.cycles]}


def cycle_starts(u, band=SCHMITT_BAND):
    """Indices where a cycle of the input starts: the valley before each upward crossing
    of the middle of its range (crossings with a band of ``band`` x the range against
    noise, a Schmitt trigger); 0 first."""
    lo, hi = float(u.min()), float(u.max())
    mid, half = (lo + hi) / 2, band * (hi - lo) / 2
    level = np.where(u > mid + half, 1, np.where(u < mid - half, -1, 0))
    idx = np.flatnonzero(level)
    if idx.size == 0:
        return np.array([0])
    held = level[idx]
    ups = idx[1:][(held[1:] == 1) & (held[:-1] == -1)]
    if held[0] == 1 and idx[0] > 0:
        # the record starts inside the band and rises: the valley before that rise
        # starts a cycle too (a record that starts high has no valley before its fall)
        ups = np.r_[idx[0], ups]
    starts, previous = [0], 0
    for up in ups:
        valley = previous + int(np.argmin(u[previous:up]))
        if valley > starts[-1]:
            starts.append(valley)
        previous = up
    return np.array(starts)


def validate_model(model: Any, voltage: ArrayLike, displacement: ArrayLike, *,
                   initial_state: ArrayLike | None = None, first: int = 0,
                   t: ArrayLike | None = None) -> Validation:
    """Predict ``voltage`` with ``model`` and compare with ``displacement`` from sample
    ``first`` on, overall and cycle by cycle.

    Parameters
    ----------
    model : PIModel or BoucWenModel
        The model judged (anything with ``predict(u, initial_state=...)``).
    voltage : array_like
        The record's voltage (V).
    displacement : array_like
        The measured displacement (µm), as many samples.
    initial_state : array_like, optional
        The model's state before the first sample (default: the model's own).
    first : int
        The first sample judged (the ones before only set the model's state).
    t : array_like, optional
        Sample times (s), for a model with creep (default: every ``creep.dt``).

    Returns
    -------
    Validation
        The errors overall, with the offset re-fitted, and per cycle.

    Raises
    ------
    InvalidArgumentError
        ``first`` is not the index of a sample.

    Examples
    --------
    >>> import pihyst
    >>> from pihyst.io import validate_model
    >>> v = validate_model(pihyst.ClassicalPI([0], [0.5]), [0, 10, 0], [0.0, 5.5, 0.0])
    >>> v.predicted.tolist(), v.errors.max_abs
    ([0.0, 5.0, 0.0], 0.5)
    """
    u = np.asarray(voltage, dtype=float)
    y = np.asarray(displacement, dtype=float)
    if not 0 <= first < u.size:
        raise InvalidArgumentError(f"first = {first}: no sample of the {u.size} to judge "
                                   f"from there")
    predicted = model.predict(u, initial_state=initial_state, **({} if t is None else {"t": t}))
    e = y - predicted
    judged = slice(first, None)
    span = float(np.ptp(y[judged])) if y[judged].size else 0.0
    errors = Errors.of(e[judged], span, first)
    shift = float(np.mean(e[judged]))
    shifted = Errors.of(e[judged] - shift, span, first)
    starts = [int(s) for s in cycle_starts(u[judged]) + first]
    bounds = list(zip(starts, starts[1:] + [u.size]))
    cycles = [(int(a), int(b), Errors.of(e[a:b], span, a)) for a, b in bounds if b > a]
    return Validation(errors, shifted, shift, cycles, predicted, first)
