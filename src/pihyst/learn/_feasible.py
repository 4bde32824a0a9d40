"""Voltages a periodic drive may send: within the limits and, around the whole cycle
(the last sample followed by the first of the next period), within the slew limit.

For limits [lo, hi] and a step limit s (volts per sample; slew rate times sample
period) the periodic drive u[0..N-1] is feasible when

    lo <= u[n] <= hi   and   |u[n] - u[(n - 1) mod N]| <= s   for every n.

:func:`feasible_periodic` makes any drive feasible: clipped to the limits (a NaN counts
as lo), then through a rate limiter v[n] = v[n-1] + clip(u[n] - v[n-1], -s, s) run round
the cycle until it repeats (it settles once it meets the drive, and the drive is
periodic); if a cycle
still does not close within s, the drive is shrunk towards its mean,
v = m + a (v - m) with a = s / max_n |v[n] - v[n-1]|, which keeps it within the limits
(a convex combination of values within them) and closes every step within s.
"""

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: margin kept below the step limit against rounding in the caller's own check
STEP_MARGIN = 1e-9


def cyclic_steps(u: ArrayLike) -> NDArray[np.float64]:
    """|u[n] - u[n - 1]| for every n, u[-1] being the last sample (the cycle's wrap).

    Parameters
    ----------
    u : array_like
        One period of a periodic drive.

    Returns
    -------
    ndarray
        The absolute step into every sample, the first one from the last sample.

    Examples
    --------
    >>> from pihyst.learn import cyclic_steps
    >>> cyclic_steps([0.0, 1.0, 3.0])
    array([3., 1., 2.])
    """
    u = np.asarray(u, dtype=float)
    return np.abs(u - np.roll(u, 1))


def _rate_limited(u, step, start):
    out = np.empty(u.size)
    v = start
    for n, target in enumerate(u):
        v += min(max(target - v, -step), step)
        out[n] = v
    return out


def feasible_periodic(u: ArrayLike, lo: float, hi: float,
                      max_step: float | None = None) -> NDArray[np.float64]:
    """The periodic drive ``u`` within [lo, hi] and, if ``max_step`` (V per sample) is
    given, within it on every step of the cycle (module notes).

    Parameters
    ----------
    u : array_like
        One period of voltages; a NaN counts as ``lo``.
    lo, hi : float
        Voltage limits.
    max_step : float or None
        Largest step between consecutive samples (V per sample), round the cycle (the
        last sample to the first included). None: no step limit.

    Returns
    -------
    ndarray
        The feasible period, as many samples as ``u``.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.learn import cyclic_steps, feasible_periodic
    >>> v = feasible_periodic([0.0, 200.0, -5.0, np.nan], 0.0, 150.0)
    >>> v
    array([  0., 150.,   0.,   0.])
    >>> w = feasible_periodic(v, 0.0, 150.0, max_step=50.0)
    >>> bool(np.all(cyclic_steps(w) <= 50.0))
    True
    """
    clipped = np.clip(np.nan_to_num(np.asarray(u, dtype=float), nan=lo), lo, hi)
    if max_step is None or clipped.size < 2:
        return clipped
    step = max_step * (1 - STEP_MARGIN)
    if np.all(cyclic_steps(clipped) <= step):
        return clipped
    # settled within the cycles the largest possible excursion needs, plus two
    cycles = min(2 + math.ceil((hi - lo) / max(step * clipped.size, 1e-300)), 50)
    v = _rate_limited(clipped, step, float(clipped[-1]))
    for _ in range(cycles):
        v_next = _rate_limited(clipped, step, float(v[-1]))
        if np.array_equal(v_next, v):
            break
        v = v_next
    worst = float(np.max(cyclic_steps(v)))
    if worst > step:
        mean = float(np.mean(v))
        v = mean + (step / worst) * (v - mean)
    return np.clip(v, lo, hi)
