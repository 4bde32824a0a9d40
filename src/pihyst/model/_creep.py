"""Creep of a PI model: first-order lags driven by its hysteresis output.

The hysteresis output H[t] = offset + sum_k w_k f_k[t] of a PI model is the settled
displacement; n lags with log-spaced time constants tau_i and gains g_i give the approach
to it (docs/theory/creep.md, csrc/pihyst_creep.h):

    alpha_i[t] = 1 - exp(-dt[t] / tau_i)
    z_i[t]     = z_i[t-1] + alpha_i[t] (H[t] - z_i[t-1])
    y[t]       = H[t] - sum_i g_i (H[t] - z_i[t])

with g_i >= 0 and sum_i g_i < 1, so that y[t] = (1 - beta[t]) H[t] + (lag terms) with
1 - beta[t] >= 1 - sum_i g_i > 0: the output stays non-decreasing in the voltage at each
sample, and the exact inverse stays exact (each sample solves for H[t], then the voltage).
"""

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst import _core
from pihyst._frozen import frozen_array
from pihyst.exceptions import InvalidArgumentError, InvalidModelError

__all__ = ["Creep", "creep_twin_run", "creep_twin_step", "creep_twin_target",
           "default_time_constants", "sample_intervals"]

#: Largest sum of the creep gains: the output's slope in H is at least 1 - this.
MAX_TOTAL_GAIN = 0.9


class Creep:
    """Creep lags of a model: time constants ``tau`` (s), gains ``gain`` (g_i >= 0, sum
    below 1) and the fixed sample interval ``dt`` (s) used when no sample times are given
    (the C core's and the firmware's path).

    A value like the models: immutable, ``==`` compares the parameters.

    Parameters
    ----------
    tau : array_like
        Time constant tau_i of each lag (s), > 0.
    gain : array_like
        Gain g_i of each lag, >= 0, summing to less than 1.
    dt : float
        The fixed sample interval (s), > 0.

    Raises
    ------
    InvalidModelError
        If a parameter is not valid (the message names it).

    Examples
    --------
    >>> c = Creep([1.0, 10.0], [0.02, 0.03], dt=0.1)
    >>> c
    Creep(tau=[1.0, 10.0], gain=[0.02, 0.03], dt=0.1)
    >>> c.to_dict()
    {'tau_s': [1.0, 10.0], 'gain': [0.02, 0.03], 'dt_s': 0.1}
    """

    __slots__ = ("tau", "gain", "dt")
    tau: NDArray[np.float64]
    gain: NDArray[np.float64]
    dt: float

    def __init__(self, tau: ArrayLike, gain: ArrayLike, dt: float) -> None:
        set_ = object.__setattr__
        set_(self, "tau", _vector(tau, "creep tau_s"))
        set_(self, "gain", _vector(gain, "creep gain", self.tau.size))
        if self.tau.size == 0:
            raise InvalidModelError("creep needs at least one time constant")
        if np.any(self.tau <= 0):
            raise InvalidModelError(f"creep time constants must be > 0 s, got "
                                    f"{self.tau.min():g}")
        if np.any(self.gain < 0):
            i = int(np.argmin(self.gain))
            raise InvalidModelError(f"creep gain[{i}] = {self.gain[i]:g} is negative: the "
                                    f"gains must be >= 0")
        if not self.gain.sum() < 1:
            raise InvalidModelError(f"creep gains sum to {self.gain.sum():g}; they must sum "
                                    f"to less than 1 (the output must rise with the input)")
        try:
            dt = float(dt)
        except (TypeError, ValueError):
            raise InvalidModelError(f"creep dt_s must be a number, got {dt!r:.40}") from None
        if not (np.isfinite(dt) and dt > 0):
            raise InvalidModelError(f"creep dt_s must be a finite interval > 0 s, got {dt}")
        set_(self, "dt", dt)

    def __setattr__(self, name, value):
        raise AttributeError("Creep is immutable: make a new one")

    def __reduce__(self):          # pickle and copy through the constructor
        return (Creep, (self.tau, self.gain, self.dt))

    @property
    def n_lags(self) -> int:
        """The number of lags."""
        return self.tau.size

    def _key(self):
        return (tuple(self.tau.tolist()), tuple(self.gain.tolist()), self.dt)

    def __eq__(self, other):
        if not isinstance(other, Creep):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def __repr__(self):
        return (f"Creep(tau={[float(x) for x in self.tau]}, "
                f"gain={[float(x) for x in self.gain]}, dt={self.dt:g})")

    def to_dict(self) -> dict[str, Any]:
        """The JSON form: ``{"tau_s": [...], "gain": [...], "dt_s": dt}``.

        Returns
        -------
        dict
            Plain JSON types; :meth:`from_dict` reads it back.

        Examples
        --------
        >>> Creep([1.0], [0.02], dt=0.1).to_dict()
        {'tau_s': [1.0], 'gain': [0.02], 'dt_s': 0.1}
        """
        return {"tau_s": self.tau.tolist(), "gain": self.gain.tolist(), "dt_s": self.dt}

    @classmethod
    def from_dict(cls, d: "Creep | Mapping[str, Any]") -> "Creep":
        """Creep lags from their JSON form (or a :class:`Creep`, returned as it is).

        Parameters
        ----------
        d : dict or Creep
            ``{"tau_s": [...], "gain": [...], "dt_s": dt}``.

        Returns
        -------
        Creep
            The lags ``d`` describes.

        Raises
        ------
        InvalidModelError
            If ``d`` is not that object, or its values are not valid.

        Examples
        --------
        >>> Creep.from_dict({"tau_s": [1.0], "gain": [0.02], "dt_s": 0.1})
        Creep(tau=[1.0], gain=[0.02], dt=0.1)
        """
        if isinstance(d, Creep):
            return d
        if not isinstance(d, dict):
            raise InvalidModelError(f"creep must be an object with tau_s, gain and dt_s, got "
                                    f"{type(d).__name__}")
        missing = [k for k in ("tau_s", "gain", "dt_s") if k not in d]
        if missing:
            raise InvalidModelError(f"creep: missing key {missing[0]!r}")
        unknown = sorted(set(d) - {"tau_s", "gain", "dt_s"})
        if unknown:
            raise InvalidModelError(f"creep: unknown key {unknown[0]!r} (allowed: dt_s, "
                                    f"gain, tau_s)")
        return cls(d["tau_s"], d["gain"], d["dt_s"])

    def lags(self, initial_state: ArrayLike) -> _core.Creep:
        """The C lags (``pihyst._core.Creep``) from the lag state z_i[t-1].

        Parameters
        ----------
        initial_state : array_like
            The lag states z_i before the first sample, one per lag.

        Returns
        -------
        pihyst._core.Creep
            The lags, with their own running state.

        Examples
        --------
        >>> lags = Creep([1.0], [0.02], dt=0.1).lags([5.0])
        >>> lags.state.tolist()
        [5.0]
        """
        return _core.Creep(self.tau, self.gain, self.dt, initial_state)

    def steady_slope(self) -> float:
        """The smallest slope dy/dH at a sample, 1 - sum_i g_i (> 0).

        Returns
        -------
        float
            1 - sum_i g_i.

        Examples
        --------
        >>> Creep([1.0, 10.0], [0.25, 0.25], dt=0.1).steady_slope()
        0.5
        """
        return 1.0 - float(self.gain.sum())


def _vector(values, name, length=None):
    try:
        a = np.array(values, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise InvalidModelError(f"{name} must be a list of numbers") from None
    if a.ndim != 1:
        raise InvalidModelError(f"{name} must be a flat list of numbers")
    if length is not None and a.size != length:
        raise InvalidModelError(f"{name} must have {length} values (one per time constant), "
                                f"got {a.size}")
    if not np.all(np.isfinite(a)):
        raise InvalidModelError(f"{name} must be finite numbers")
    return frozen_array(a)       # read-only, and cannot be made writable again


#: The slowest creep lag's time constant is at least this (s): holds of minutes
#: (staircases of 10-60 s steps, a stage parked between scans) are where creep shows.
CREEP_HORIZON_S = 1000.0


def default_time_constants(dt, duration, horizon=CREEP_HORIZON_S):
    """Half-decade time constants from max(0.1 s, 3 dt) up to max(duration, ``horizon``).

    Lags much faster than the sampling cannot be seen. Lags slower than the record are
    not determined by it: the fit ties their gains to the slowest lag within the record
    (identify._creep.log_t_basis), so creep goes on past the record at the last measured
    rate per decade (the log-t law of piezo creep) until ``horizon``. Stopping the lags
    at the record's duration instead stopped the model's creep there: measured on random
    actuators fitted on 2-20 s records (benchmarks/bench_population.py) and judged on
    10-60 s holds, the staircase error was 0.12-0.62 % of range against 0.02-0.12 % with
    the lags up to 1000 s. At least one lag is returned.
    """
    lo = max(0.1, 3.0 * float(dt))
    hi = max(float(duration), float(horizon), lo)
    n = int(np.floor(2 * np.log10(hi / lo) + 1e-9)) + 1
    return lo * 10.0 ** (0.5 * np.arange(n))


def first_interval(creep, t, t_previous):
    """The interval before the first of the sample times ``t`` (s): ``t[0] - t_previous``
    when the previous sample's time is given (a following chunk of a record), else the
    lags' own ``creep.dt``."""
    if t_previous is None or t is None or np.size(t) == 0:
        return creep.dt
    try:
        first = float(np.asarray(t, dtype=np.float64).ravel()[0]) - float(t_previous)
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"t_previous must be a time (s), got "
                                   f"{t_previous!r:.40}") from None
    if not (np.isfinite(first) and first >= 0):
        raise InvalidArgumentError(f"the first sample time {np.ravel(t)[0]!r} comes before "
                                   f"t_previous {t_previous!r}")
    return first


def sample_intervals(t, n, first):
    """Per-sample intervals dt[i] = t[i] - t[i-1] (dt[0] = ``first``) of the sample times
    ``t`` (s) of n samples; they must be finite and non-decreasing."""
    t = np.ascontiguousarray(t, dtype=np.float64)
    if t.ndim != 1 or t.size != n:
        raise InvalidArgumentError(f"t must be one sample time per input sample ({n}), got shape "
                                   f"{t.shape}")
    if not np.all(np.isfinite(t)):
        raise InvalidArgumentError("t must be finite sample times (s)")
    dt = np.empty(n)
    if n:
        dt[0] = first
        dt[1:] = np.diff(t)
    back = np.flatnonzero(dt < 0)
    if back.size:
        raise InvalidArgumentError(f"t must be non-decreasing: t[{back[0]}] = {t[back[0]]:g} comes"
                                   f" after {t[back[0] - 1]:g}")
    return dt


# The plain-Python twin of the lags' C arithmetic (csrc/pihyst_creep.c), operation for
# operation, for the Python twins of the C paths that use the lags (the Bouc-Wen model
# and compensator with creep); ``state`` is the lag vector z_i[t-1], a float list or array.

def creep_twin_target(creep, state, y_desired, dt=None):
    """(C5): the hysteresis output H* that gives ``y_desired`` at the next sample,
    H* = (y_d - sum_i g_i (1 - alpha_i) z_i) / (1 - beta), as pihyst_creep_target(_dt)."""
    carry = beta = 0.0
    if dt is None or dt == creep.dt:
        for g, tau, z in zip(creep.gain.tolist(), creep.tau.tolist(), state):
            keep = 1.0 - -math.expm1(-creep.dt / tau)
            carry += g * keep * z
            beta += g * keep
        return (y_desired - carry) / (1.0 - beta)
    for g, tau, z in zip(creep.gain.tolist(), creep.tau.tolist(), state):
        keep = g * math.exp(-dt / tau)                  # g_i (1 - alpha_i)
        carry += keep * z
        beta += keep
    return (y_desired - carry) / (1.0 - beta)


def creep_twin_step(creep, state, h, dt=None):
    """(C2)-(C3): advance the lags ``state`` (a list, changed in place) by the hysteresis
    output ``h``; return y, as pihyst_creep_step(_dt)."""
    lag = 0.0
    step = creep.dt if dt is None else dt
    for i, (g, tau) in enumerate(zip(creep.gain.tolist(), creep.tau.tolist())):
        state[i] += -math.expm1(-step / tau) * (h - state[i])
        lag += g * (h - state[i])
    return h - lag


def creep_twin_run(creep, state, h, dt=None):
    """y[t] for the hysteresis outputs ``h`` (intervals ``dt``, None: the fixed one),
    advancing the lag array ``state`` in place: the twin of pihyst_creep_run."""
    z = [float(v) for v in state]
    y = np.array([creep_twin_step(creep, z, float(v), None if dt is None else float(d))
                  for v, d in zip(np.asarray(h, dtype=float).tolist(),
                                  [None] * len(h) if dt is None else dt)])
    state[:] = z
    return y
