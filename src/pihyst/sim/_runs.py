"""Shared by the hysteresis parts: input checks and splitting a signal into monotone runs."""

import numpy as np


def checked_input(u, u_max):
    """``u`` as a float array, one-dimensional and within [0, u_max] (volts)."""
    u = np.asarray(u, dtype=float)
    if u.ndim != 1:
        raise ValueError("input must be one-dimensional")
    if u.size and not np.all((u >= 0) & (u <= u_max)):
        bad = np.flatnonzero(~((u >= 0) & (u <= u_max)))[0]
        raise ValueError(f"sample {bad}: input {u[bad]:g} V is outside [0, {u_max:g}] V")
    return u


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
