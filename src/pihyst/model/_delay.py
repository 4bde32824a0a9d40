"""The input-output delay of a model: a dead time of d whole samples on its input.

A measured actuator answers late: the sensor's filter, the amplifier and the logging add
a dead time between the voltage and the displacement recorded with it. A model with
``delay = d`` runs its hysteresis on the input delayed by d samples,

    y[k] = P[u_d](k),   u_d[k] = u[k - d] for k >= d,   u_d[k] = u_pending[k] for k < d,

where the d pending inputs are, by default, u[0] held: the first d outputs are those of
the initial state at u[0] (y[k] = P[u](0) for a rate-independent model; with creep the
lags run on through those samples). A delay is a number of samples, so it holds
at one sample period: a model records the period it was identified at
(``sample_period``, s) when that was known, and a run at another period is converted
when d T is a whole number of the new samples, refused otherwise.
"""

import numbers
from collections import deque

import numpy as np

from pihyst.exceptions import InvalidArgumentError, InvalidModelError, ResourceLimitError

__all__ = ["MAX_DELAY_SAMPLES", "checked_delay", "checked_sample_period", "delay_at",
           "delayed_input", "pending_after", "DelayLine"]

#: relative tolerance of "a whole number of samples" and of a uniform sample period
EXACT = 1e-6
UNIFORM = 0.01
#: the longest delay pihyst holds (its d pending inputs are allocated): 10 s at 100 kHz
MAX_DELAY_SAMPLES = 1_000_000


def checked_delay(delay, name="delay"):
    """``delay`` as an int in [0, MAX_DELAY_SAMPLES]; InvalidModelError naming ``name``
    otherwise (a float is accepted only when it is a whole number; a boolean is not a
    number)."""
    if isinstance(delay, (bool, np.bool_)) or not isinstance(delay, numbers.Real):
        raise InvalidModelError(f"{name} must be a whole number of samples >= 0, got "
                                f"{delay!r:.40}")
    if not (np.isfinite(delay) and delay >= 0 and int(delay) == delay):
        raise InvalidModelError(f"{name} must be a whole number of samples >= 0, got "
                                f"{delay!r:.40}")
    if delay > MAX_DELAY_SAMPLES:
        raise InvalidModelError(f"{name} = {delay:.6g} is more than the {MAX_DELAY_SAMPLES:,} "
                                f"samples pihyst holds as an input delay")
    return int(delay)


def checked_sample_period(period, name="sample_period"):
    """``period`` as a float > 0 (s), or None (unknown); InvalidModelError otherwise."""
    if period is None:
        return None
    if isinstance(period, (bool, np.bool_)) or not isinstance(period, numbers.Real):
        raise InvalidModelError(f"{name} must be a number of seconds > 0, got "
                                f"{period!r:.40}")
    period = float(period)
    if not (np.isfinite(period) and period > 0):
        raise InvalidModelError(f"{name} must be a finite number of seconds > 0, "
                                f"got {period}")
    return period


def delay_at(delay, sample_period, period=None, t=None):
    """The delay in samples of a run at the sample period ``period`` (s), or at the
    uniform sample times ``t`` (s): ``delay`` when no period is known on either side,
    d T / period when that is a whole number; InvalidArgumentError otherwise."""
    if delay == 0 or sample_period is None or (period is None and t is None):
        return delay
    if period is None:
        steps = np.diff(np.asarray(t, dtype=np.float64))
        if steps.size == 0:
            return delay
        period = float(np.median(steps))
        if not (period > 0 and np.all(np.abs(steps - period) <= UNIFORM * period)):
            raise InvalidArgumentError(f"the sample times are not uniform (median interval "
                                       f"{period:g} s): a delay of {delay} samples needs "
                                       f"a fixed sample period")
    ratio = delay * sample_period / period
    if not ratio <= MAX_DELAY_SAMPLES:      # (inf and NaN too: a period of a denormal)
        raise ResourceLimitError(
            f"the model's delay of {delay} samples at {sample_period:g} s "
            f"({delay * sample_period:g} s) is {ratio:.4g} samples at {period:g} s: more "
            f"than the {MAX_DELAY_SAMPLES:,} pihyst holds as an input delay")
    n = round(ratio)
    if abs(ratio - n) > EXACT * max(1.0, ratio):
        raise InvalidArgumentError(
            f"the model's delay of {delay} samples at {sample_period:g} s "
            f"({delay * sample_period:g} s) is not a whole number of samples at "
            f"{period:g} s: run it at {sample_period:g} s or resample")
    return int(n)


def _pending(pending, d, first):
    """The d inputs before the first sample: ``pending`` as given, or ``first`` held."""
    if pending is None:
        return np.full(d, first)
    try:
        p = np.asarray(pending, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise InvalidArgumentError("pending_input must be a sequence of numbers") from None
    if p.size != d:
        raise InvalidArgumentError(f"pending_input must have {d} values (the model's "
                                   f"delay in samples), got {p.size}")
    return p


def delayed_input(u, d, pending=None):
    """u_d: ``u`` delayed by ``d`` samples, the first d from ``pending`` (default u[0]
    held). ``pending`` is checked by the caller to lie in the input range."""
    if d == 0 or u.size == 0:
        return u
    return np.concatenate([_pending(pending, d, u[0]), u])[:u.size]


def pending_after(u, d, pending=None):
    """The d inputs a run of ``u`` leaves for the next one (its last d, preceded by the
    pending ones when ``u`` is shorter than d)."""
    if d == 0:
        return np.empty(0)
    if u.size == 0:
        return None if pending is None else _pending(pending, d, 0.0)
    return np.concatenate([_pending(pending, d, u[0]), u])[-d:]


class DelayLine:
    """A FIFO of d inputs for a stepper: ``push(u)`` returns the input d samples back (u
    itself when d = 0). Before the first push it holds ``pending`` (default: the first
    input, d times)."""

    def __init__(self, d, pending=None):
        self.d = d
        self._pending = None if pending is None else _pending(pending, d, 0.0)
        self.reset()

    def reset(self):
        self._buf = None if self._pending is None else deque(self._pending.tolist())

    @property
    def contents(self):
        """The inputs not yet applied, oldest first (None before the first push)."""
        return None if self._buf is None else np.array(self._buf)

    def push(self, u):
        if self.d == 0:
            return u
        if self._buf is None:
            self._buf = deque([u] * self.d)
        self._buf.append(u)
        return self._buf.popleft()
