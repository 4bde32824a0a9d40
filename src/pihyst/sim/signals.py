"""Test signals: the paper's triangle, sines, decaying triangles, random ramps, staircases,
growing sines.

Every function returns ``(t, u)``: sample times (s, from 0, step ``dt``) and values. The
values are generic: volts when the signal drives a beam, micrometres when it is a desired
displacement to track. ``u_min`` and ``u_max`` are the signal's lowest and highest level;
every signal starts at ``u_min`` (a beam at rest at 0 V).

Invalid arguments raise :class:`~pihyst.exceptions.InvalidArgumentError`; a signal of
more than :data:`MAX_SAMPLES` samples raises :class:`~pihyst.exceptions.ResourceLimitError`
before anything is allocated.
"""

import numbers

import numpy as np
from numpy.typing import NDArray

from pihyst import paper
from pihyst.exceptions import InvalidArgumentError, ResourceLimitError
from pihyst.sim._runs import checked_seed

__all__ = ["DEFAULT_DT", "MAX_SAMPLES", "band_limited_triangle", "decaying_triangles",
           "growing_sine", "random_ramps", "sine", "staircase", "triangle"]

#: (times in s, voltages in V): what every signal function returns
Signal = tuple[NDArray[np.float64], NDArray[np.float64]]
PAPER_PERIOD_S = paper.DRIVE_PERIOD_S
PAPER_U_MAX = paper.DRIVE_U_MAX_V
DEFAULT_DT = 0.1
#: Longest signal made (samples): about 100 MB of CSV and 1 GB of memory once simulated.
MAX_SAMPLES = 2_000_000


def _real(value, name):
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise InvalidArgumentError(f"{name} must be a number, got {value!r:.40}")
    return float(value)


def _check_common(u_min, u_max, dt):
    for v, name in ((u_min, "u_min"), (u_max, "u_max"), (dt, "dt")):
        if not np.isfinite(_real(v, name)):
            raise InvalidArgumentError(f"{name} must be a finite number, got {v}")
    if not u_max > u_min:
        raise InvalidArgumentError(f"u_max must be above u_min, got u_min={u_min:g}, "
                                   f"u_max={u_max:g}")
    if not np.isfinite(u_max - u_min):
        raise InvalidArgumentError(f"u_min={u_min:g} and u_max={u_max:g}: the span overflows")
    if not dt > 0:
        raise InvalidArgumentError(f"dt must be positive, got {dt:g}")


def _positive(value, name):
    if not (np.isfinite(_real(value, name)) and value > 0):
        raise InvalidArgumentError(f"{name} must be a positive number, got {value}")


def _count(value, name):
    if (isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real)
            or not np.isfinite(value) or int(value) != value or value < 1):
        raise InvalidArgumentError(f"{name} must be a whole number >= 1, got {value!r:.40}")
    return int(value)


def _check_samples(n, what):
    """ResourceLimitError unless ``n`` (a float: it may be huge or inf) samples are few
    enough to make."""
    if not n <= MAX_SAMPLES:
        size = f"{n:.3g}" if np.isfinite(n) else "infinitely many"
        raise ResourceLimitError(f"{what} makes {size} samples, more than the {MAX_SAMPLES:,} "
                                 f"pihyst makes at once: use a larger dt or a shorter signal")


def _check_period(period_s, dt):
    if dt > period_s / 2:
        raise InvalidArgumentError(f"dt = {dt:g} s is more than half the period "
                                   f"{period_s:g} s: the peaks would not be sampled")


def _times(n, dt):
    """t_i = i dt for i < n; InvalidArgumentError if the last time overflows."""
    if not np.isfinite(float(max(n - 1, 0)) * dt):
        raise InvalidArgumentError(f"dt = {dt:g} s: the time of sample {n - 1} overflows")
    return np.arange(n) * dt


def _grid(duration, dt):
    # t_i = i dt for i = 0..n, n = round(duration / dt): the end point is included
    _check_samples(duration / dt + 1, f"a duration of {duration:g} s at dt = {dt:g} s")
    n = int(round(duration / dt))
    return _times(n + 1, dt)


def _piecewise_linear(times, levels, dt):
    """Samples every dt of the polyline through (times, levels) (times on the dt grid)."""
    t = _grid(times[-1], dt)
    return t, np.interp(t, times, levels)


def triangle(u_min: float = 0.0, u_max: float = PAPER_U_MAX, period_s: float = PAPER_PERIOD_S,
             n_cycles: int = 1, dt: float = DEFAULT_DT) -> Signal:
    """Triangle wave u_min -> u_max -> u_min, ``n_cycles`` times (the paper's drive:
    0-150 V, 300 s period).

    The peaks are sampled exactly when period_s / 2 is a multiple of dt.

    Parameters
    ----------
    u_min, u_max : float
        The signal's range (V), u_min < u_max; default 0-150 V.
    period_s : float
        Period (s); default the paper's 300 s.
    n_cycles : int
        Number of periods.
    dt : float
        Sample interval (s); default 0.1 s.

    Returns
    -------
    t, u : numpy.ndarray
        Sample times (s, from 0, every ``dt``) and the signal (V).

    Raises
    ------
    InvalidArgumentError
        If an argument is not valid (the message names it).
    ResourceLimitError
        If the signal would have more than :data:`MAX_SAMPLES` samples.

    Examples
    --------
    >>> t, u = triangle(dt=1.0)
    >>> float(t[-1]), float(u[150]), float(u[-1]), t.size
    (300.0, 150.0, 0.0, 301)
    """
    _check_common(u_min, u_max, dt)
    _positive(period_s, "period_s")
    _check_period(period_s, dt)
    n_cycles = _count(n_cycles, "n_cycles")
    t = _grid(n_cycles * period_s, dt)
    # u = u_min + (u_max - u_min) (1 - |2 frac(t / P) - 1|)
    phase = np.mod(t / period_s, 1.0)
    u = u_min + (u_max - u_min) * (1.0 - np.abs(2.0 * phase - 1.0))
    return t, np.clip(np.round(u, 12), u_min, u_max)


def sine(u_min: float = 0.0, u_max: float = PAPER_U_MAX, period_s: float = PAPER_PERIOD_S,
         n_cycles: int = 1, dt: float = DEFAULT_DT) -> Signal:
    """Sine between u_min and u_max starting at its minimum:
    u = (u_min + u_max)/2 - (u_max - u_min)/2 cos(2 pi t / P).

    Parameters
    ----------
    u_min, u_max : float
        The signal's range (V), u_min < u_max; default 0-150 V.
    period_s : float
        Period (s); default the paper's 300 s.
    n_cycles : int
        Number of periods.
    dt : float
        Sample interval (s); default 0.1 s.

    Returns
    -------
    t, u : numpy.ndarray
        Sample times (s, from 0, every ``dt``) and the signal (V).

    Raises
    ------
    InvalidArgumentError
        If an argument is not valid (the message names it).
    ResourceLimitError
        If the signal would have more than :data:`MAX_SAMPLES` samples.

    Examples
    --------
    >>> t, u = sine(period_s=10.0, dt=1.0)
    >>> float(u[0]), float(u[5])
    (0.0, 150.0)
    """
    _check_common(u_min, u_max, dt)
    _positive(period_s, "period_s")
    _check_period(period_s, dt)
    n_cycles = _count(n_cycles, "n_cycles")
    t = _grid(n_cycles * period_s, dt)
    u = 0.5 * (u_min + u_max) - 0.5 * (u_max - u_min) * np.cos(2 * np.pi * t / period_s)
    return t, np.clip(u, u_min, u_max)


def decaying_triangles(u_min: float = 0.0, u_max: float = PAPER_U_MAX,
                       period_s: float = PAPER_PERIOD_S, n_triangles: int = 5,
                       ratio: float = 0.7, dt: float = DEFAULT_DT) -> Signal:
    """One full triangle u_min -> u_max -> u_min, then triangles back to u_min whose peaks
    decay geometrically: peak_k = u_min + (u_max - u_min) ratio^k, k = 0..n_triangles-1
    (minor loops inside the major one). All ramps have the full triangle's slope
    2 (u_max - u_min) / period_s; each turning point lies on the dt grid.

    Parameters
    ----------
    u_min, u_max : float
        The signal's range (V), u_min < u_max; default 0-150 V.
    period_s : float
        Period (s); default the paper's 300 s.
    n_triangles : int
        Number of triangles, the full one included.
    ratio : float
        Ratio of each peak's height to the one before, 0 < ratio < 1.
    dt : float
        Sample interval (s); default 0.1 s.

    Returns
    -------
    t, u : numpy.ndarray
        Sample times (s, from 0, every ``dt``) and the signal (V).

    Raises
    ------
    InvalidArgumentError
        If an argument is not valid (the message names it).
    ResourceLimitError
        If the signal would have more than :data:`MAX_SAMPLES` samples.

    Examples
    --------
    >>> t, u = decaying_triangles(n_triangles=3, ratio=0.5, period_s=40.0, dt=1.0)
    >>> [float(v) for v in u[[20, 40, 50, 60, 65, 70]]]
    [150.0, 0.0, 75.0, 0.0, 37.5, 0.0]
    """
    _check_common(u_min, u_max, dt)
    _positive(period_s, "period_s")
    _check_period(period_s, dt)
    n_triangles = _count(n_triangles, "n_triangles")
    if not 0 < _real(ratio, "ratio") < 1:
        raise InvalidArgumentError(f"ratio must be between 0 and 1, got {ratio:g}")
    # every triangle takes at least two samples: bound the count before the arrays
    _check_samples(2.0 * n_triangles + 1, f"{n_triangles} triangles")
    span = u_max - u_min
    peaks = span * ratio ** np.arange(n_triangles)
    with np.errstate(over="ignore"):     # a huge count is refused just below
        halves = np.maximum(dt, dt * np.round(peaks / span * period_s / 2 / dt))
    _check_samples(2 * halves.sum() / dt + 1, f"{n_triangles} triangles of period "
                   f"{period_s:g} s at dt = {dt:g} s")
    ends = np.cumsum(np.repeat(halves, 2))
    times = np.concatenate(([0.0], ends))
    levels = np.concatenate(([u_min], np.ravel(np.column_stack((u_min + peaks,
                                                                np.full(n_triangles, u_min))))))
    return _piecewise_linear(times, levels, dt)


def random_ramps(u_min: float = 0.0, u_max: float = PAPER_U_MAX, n_ramps: int = 20,
                 rate: float | None = None, dt: float = DEFAULT_DT, seed: int = 0) -> Signal:
    """Ramps at constant rate between random levels (uniform in [u_min, u_max]),
    starting at u_min: reversals inside the range, for judging models on minor loops.

    ``rate`` (units per second) defaults to the paper's triangle slope,
    2 (u_max - u_min) / 300 s. Each ramp's duration is rounded up to whole samples, so
    every level is sampled exactly.

    Parameters
    ----------
    u_min, u_max : float
        The signal's range (V), u_min < u_max; default 0-150 V.
    n_ramps : int
        Number of ramps.
    rate : float, optional
        Ramp rate (V/s); default the paper's triangle slope.
    dt : float
        Sample interval (s); default 0.1 s.
    seed : int
        Seed of the random levels.

    Returns
    -------
    t, u : numpy.ndarray
        Sample times (s, from 0, every ``dt``) and the signal (V).

    Raises
    ------
    InvalidArgumentError
        If an argument is not valid (the message names it).
    ResourceLimitError
        If the signal would have more than :data:`MAX_SAMPLES` samples.

    Examples
    --------
    >>> t, u = random_ramps(n_ramps=4, seed=3)
    >>> float(u[0]), bool(u.min() >= 0 and u.max() <= 150)
    (0.0, True)
    """
    _check_common(u_min, u_max, dt)
    n_ramps = _count(n_ramps, "n_ramps")
    if rate is None:
        rate = 2 * (u_max - u_min) / PAPER_PERIOD_S
    _positive(rate, "rate")
    _check_samples(n_ramps + 1.0, f"{n_ramps} ramps")
    rng = np.random.default_rng(checked_seed(seed))
    levels = np.concatenate(([u_min], rng.uniform(u_min, u_max, n_ramps)))
    with np.errstate(over="ignore"):   # a huge count is refused just below
        steps = np.maximum(1, np.ceil(np.abs(np.diff(levels)) / rate / dt - 1e-9))
        times = np.concatenate(([0.0], np.cumsum(steps) * dt))
    _check_samples(steps.sum() + 1, f"{n_ramps} ramps at {rate:g} per second, dt = {dt:g} s")
    if not np.isfinite(times[-1]):
        raise InvalidArgumentError(f"dt = {dt:g} s: the signal's duration overflows")
    return _piecewise_linear(times, levels, dt)


def staircase(u_min: float = 0.0, u_max: float = PAPER_U_MAX, n_steps: int = 10,
              step_s: float = 10.0, down: bool = True, dt: float = DEFAULT_DT) -> Signal:
    """Steps of (u_max - u_min) / n_steps from u_min up to u_max (and back down if
    ``down``), each level held for ``step_s`` seconds (rounded to whole samples; at
    least ``dt``): creep shows within each step.

    Parameters
    ----------
    u_min, u_max : float
        The signal's range (V), u_min < u_max; default 0-150 V.
    n_steps : int
        Number of steps from u_min to u_max.
    step_s : float
        How long each level is held (s).
    down : bool
        Step back down to u_min too.
    dt : float
        Sample interval (s); default 0.1 s.

    Returns
    -------
    t, u : numpy.ndarray
        Sample times (s, from 0, every ``dt``) and the signal (V).

    Raises
    ------
    InvalidArgumentError
        If an argument is not valid (the message names it).
    ResourceLimitError
        If the signal would have more than :data:`MAX_SAMPLES` samples.

    Examples
    --------
    >>> t, u = staircase(n_steps=2, step_s=2.0, dt=1.0)
    >>> u.tolist()
    [0.0, 0.0, 75.0, 75.0, 150.0, 150.0, 75.0, 75.0, 0.0, 0.0]
    """
    _check_common(u_min, u_max, dt)
    n_steps = _count(n_steps, "n_steps")
    _positive(step_s, "step_s")
    if step_s < dt:
        raise InvalidArgumentError(f"a step of {step_s:g} s is shorter than dt = {dt:g} s: "
                                   "a step must last at least one sample")
    per_step = max(1.0, round(step_s / dt)) if np.isfinite(step_s / dt) else np.inf
    levels_count = 2 * n_steps + 1 if down else n_steps + 1
    _check_samples(float(levels_count) * per_step, f"{n_steps} steps of {step_s:g} s at "
                   f"dt = {dt:g} s")
    per_step = int(per_step)
    k = np.arange(n_steps + 1)
    if down:
        k = np.concatenate((k, k[-2::-1]))
    # clip: u_min + span * k / n can round one ulp past u_max
    levels = np.minimum(u_min + (u_max - u_min) * k / n_steps, u_max)
    u = np.repeat(levels, per_step)
    return _times(u.size, dt), u


def growing_sine(u_min: float = 0.0, u_max: float = PAPER_U_MAX,
                 period_s: float = PAPER_PERIOD_S, n_cycles: int = 5,
                 dt: float = DEFAULT_DT) -> Signal:
    """A sine from ``u_min`` whose amplitude grows linearly until the last cycle's peak
    reaches ``u_max``, then falls back to ``u_min``: nested loops growing outward.

        u(t) = u_min + (u_max - u_min) min(t / T_p, 1) (1 - cos(2 pi t / period_s)) / 2,
        T_p = (n_cycles - 1/2) period_s   (the last peak)

    Parameters
    ----------
    u_min, u_max : float
        The signal's range (V), u_min < u_max; default 0-150 V.
    period_s : float
        Period (s); default the paper's 300 s.
    n_cycles : int
        Number of periods.
    dt : float
        Sample interval (s); default 0.1 s.

    Returns
    -------
    t, u : numpy.ndarray
        Sample times (s, from 0, every ``dt``) and the signal (V).

    Raises
    ------
    InvalidArgumentError
        If an argument is not valid (the message names it).
    ResourceLimitError
        If the signal would have more than :data:`MAX_SAMPLES` samples.

    Examples
    --------
    >>> t, u = growing_sine(n_cycles=2, period_s=4.0, dt=1.0)
    >>> [round(float(x), 1) for x in u]
    [0.0, 12.5, 50.0, 37.5, 0.0, 62.5, 150.0, 75.0, 0.0]
    """
    _check_common(u_min, u_max, dt)
    _positive(period_s, "period_s")
    n_cycles = _count(n_cycles, "n_cycles")
    total = n_cycles * period_s
    t = _grid(total, dt)
    envelope = np.minimum(t / (total - period_s / 2), 1.0)
    u = u_min + (u_max - u_min) * envelope * (1 - np.cos(2 * np.pi * t / period_s)) / 2
    return t, np.clip(u, u_min, u_max)


def band_limited_triangle(u_min: float = 0.0, u_max: float = PAPER_U_MAX,
                          period_s: float = PAPER_PERIOD_S, max_hz: float | None = None,
                          dt: float = DEFAULT_DT) -> Signal:
    """One period of a triangle with only its harmonics below ``max_hz``: a scan line
    without the corners a stage's modes would ring on.

        x(t) = -sum_{odd k, k / T < max_hz} cos(2 pi k t / T) / k^2,

    scaled so that its lowest value is ``u_min`` (at t = 0) and its highest ``u_max``;
    ``max_hz`` None keeps every harmonic below the Nyquist frequency 1 / (2 dt).

    Parameters
    ----------
    u_min, u_max : float
        The signal's range (V), u_min < u_max; default 0-150 V.
    period_s : float
        Period (s); default the paper's 300 s.
    max_hz : float, optional
        The highest frequency kept (Hz); default the Nyquist frequency.
    dt : float
        Sample interval (s); default 0.1 s.

    Returns
    -------
    t, u : numpy.ndarray
        Sample times (s, from 0, every ``dt``) and the signal (V).

    Raises
    ------
    InvalidArgumentError
        If an argument is not valid (the message names it).
    ResourceLimitError
        If the signal would have more than :data:`MAX_SAMPLES` samples.

    Examples
    --------
    >>> t, u = band_limited_triangle(period_s=10.0, max_hz=0.5, dt=1.0)
    >>> float(u[0]), float(u.max()), u.size
    (0.0, 150.0, 10)
    """
    _check_common(u_min, u_max, dt)
    _positive(period_s, "period_s")
    _check_period(period_s, dt)
    _check_samples(period_s / dt, "band_limited_triangle")
    n = int(round(period_s / dt))
    limit = 0.5 / dt if max_hz is None else float(max_hz)
    if not 1.0 / period_s < limit:
        raise InvalidArgumentError(f"max_hz {limit:g} must be above the scan rate "
                                   f"{1.0 / period_s:g} Hz")
    t = _times(n, dt)
    k = np.arange(1, int(np.ceil(limit * period_s)), 2)
    k = k[(k / period_s < limit) & (k / period_s < 0.5 / dt)]
    x = -np.cos(2 * np.pi * np.outer(t, k) / period_s) @ (1.0 / k ** 2)
    x = (x - x.min()) / np.ptp(x)
    return t, u_min + (u_max - u_min) * x
