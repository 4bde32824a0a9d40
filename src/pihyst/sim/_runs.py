"""Shared by the hysteresis parts: input checks and splitting a signal into monotone runs."""

import numbers

import numpy as np

from pihyst.exceptions import InvalidArgumentError


def checked_input(u, u_max):
    """``u`` as a float array, one-dimensional and within [0, u_max] (volts)."""
    u = np.asarray(u, dtype=float)
    if u.ndim != 1:
        raise InvalidArgumentError("input must be one-dimensional")
    if u.size and not np.all((u >= 0) & (u <= u_max)):
        bad = np.flatnonzero(~((u >= 0) & (u <= u_max)))[0]
        raise InvalidArgumentError(f"sample {bad}: input {u[bad]:g} V is outside [0, {u_max:g}] V")
    return u


def checked_seed(seed):
    """A noise seed: a whole number >= 0 (numpy's generators take no negative seed)."""
    if (isinstance(seed, (bool, np.bool_)) or not isinstance(seed, numbers.Integral)
            or seed < 0):
        raise InvalidArgumentError(f"seed must be a whole number >= 0, got {seed!r:.40}")
    return int(seed)


def monotone_runs(x, x_prev, dir_prev):
    """Split ``x`` into runs of one direction, continuing from the previous sample.

    Returns ``(i0, i1, s)`` triples: x[i0:i1] moves in direction s (+1 up, -1 down);
    a sample equal to its predecessor keeps the last direction. The first run has
    direction ``dir_prev`` when x starts without a change.
    """
    n = x.size
    step = np.sign(np.diff(np.concatenate(([x_prev], x))))
    signs = np.concatenate(([dir_prev], step))
    idx = np.where(signs != 0, np.arange(n + 1), 0)
    direction = signs[np.maximum.accumulate(idx)][1:]
    starts = np.flatnonzero(np.diff(np.concatenate(([dir_prev], direction))))
    bounds = np.concatenate(([0], starts, [n]))
    return [(int(i0), int(i1), int(direction[i0]))
            for i0, i1 in zip(bounds[:-1], bounds[1:]) if i1 > i0]
