"""A measured record cut into cycles: which samples settle the operators, which are
fitted and which are held back to judge the fit.

- Turning points: where the input reverses by more than ``REVERSAL_TOLERANCE`` of its
  span (smaller wiggles are noise).
- Cycles: from one input minimum (valley) to the next. A cycle is *major* if it spans
  the whole range (within ``MAJOR_TOLERANCE``), *minor* if it reverses inside the range.
- Settling: a record that does not start at rest has unknown operator states; after the
  input has swept from one end of its range to the other every operator's state is
  fixed by the data (a classical operator with r < S/2 after any excursion wider than
  2r), so the samples up to the first valley after both ends were reached only run the
  operators.
- Held back: ``"alternate"`` holds back every other major cycle (the 2nd, 4th, ...) and
  every other minor one (the 1st, 3rd, ..., so that a record with minor loops always has
  one to judge on); a fraction f holds back the last f of the record, cut at a cycle
  boundary.
"""

import numbers
from dataclasses import dataclass

import numpy as np

from pihyst.exceptions import FitError
from pihyst.identify._constants import MAJOR_TOLERANCE, REST_TOLERANCE, REVERSAL_TOLERANCE
from pihyst.identify._turning import turning_points as _one_pass

MIN_SAMPLES = 20


def checked_signals(u, y):
    """u and y as finite float arrays of equal length; FitError naming the sample."""
    out = []
    for name, a in (("input", u), ("output", y)):
        try:
            a = np.array(a, dtype=float)
        except (TypeError, ValueError):
            raise FitError(f"{name} must be a sequence of numbers", column=name) from None
        if a.ndim != 1:
            raise FitError(f"{name} must be one-dimensional, got shape {a.shape}", column=name)
        bad = np.flatnonzero(~np.isfinite(a))
        if bad.size:
            raise FitError(f"{name} sample {bad[0]} is {a[bad[0]]}, not a finite number",
                           index=int(bad[0]), column=name)
        out.append(a)
    u, y = out
    if u.size != y.size:
        raise FitError(f"input has {u.size} samples but output has {y.size}")
    if u.size < MIN_SAMPLES:
        raise FitError(f"too few samples to fit: {u.size} (at least {MIN_SAMPLES} needed, "
                       f"and a full cycle of the input)", index=max(u.size - 1, 0))
    if np.ptp(u) == 0:
        raise FitError(f"the input is constant ({u[0]:g}): it never moves the operators",
                       index=0, column="input")
    if np.ptp(y) == 0:
        raise FitError(f"the output is constant ({y[0]:g}): there is nothing to fit",
                       index=0, column="output")
    return u, y


def turning_points(v, tolerance):
    """Indices where v reverses by more than ``tolerance``, with +1 (maximum) or -1
    (minimum), in time order.

    A phase rising from sample s ends at the first t where the running maximum
    max v[s..t] exceeds v[t] by more than the tolerance; its maximum (the first sample
    reaching it) is a turning point, and a falling phase starts at t (and the other way
    round). Before the first reversal both running extremes are watched from sample 0
    (a maximum first if both trip at once); a turning point at sample 0 is not reported.
    One pass over the samples in C (identify/_turning.pyx; its plain twin, the same
    loop in Python, is ``pihyst._reference.turning_points_loop``).
    """
    return _one_pass(np.ascontiguousarray(v, dtype=np.float64), float(tolerance))


@dataclass
class Layout:
    """How a record is used: segments (start, stop, role) covering it in order, with role
    "settle", "fit" or "held_back", the kind of each ("settle", "major" or "minor"
    cycle), and a description for the report."""

    segments: list
    n_cycles: int
    n_minor: int
    settle_end: int
    holdout: str
    kinds: list | None = None
    points: list | None = None      # the turning points the cycles were cut at

    def _chosen(self, role, kind):
        kinds = self.kinds or [None] * len(self.segments)
        return [(a, z) for (a, z, r), k in zip(self.segments, kinds)
                if r == role and (kind is None or k == kind)]

    def indices(self, role, kind=None):
        """Sample indices of the segments with this role (and kind of cycle)."""
        return np.concatenate([np.arange(a, z) for a, z in self._chosen(role, kind)]
                              or [np.zeros(0, dtype=int)])

    def count(self, role, kind=None):
        return int(sum(z - a for a, z in self._chosen(role, kind)))

    def cycles(self, role, kind=None):
        return len(self._chosen(role, kind))


def starts_at_rest(v, span):
    """Whether the record starts at the bottom of its range (docs/interfaces.md records
    start at rest at 0 V after a full 0 -> max -> 0 cycle)."""
    return v[0] <= REST_TOLERANCE * span


def settling_end(v, span, points=None):
    """The index after the sweep that settles the operators of a record that does not
    start at rest (v shifted to [0, span]; ``points``: its turning points, found if not
    given): up to the first valley after both ends of the range were reached (within
    REST_TOLERANCE of the span), or just past the second end if the record never turns up
    again; the record's length if it never reaches an end of the range. The one rule of
    fit(initial_state="settle") and of the command line's --initial-state settle
    (:func:`record_settling_end`)."""
    if points is None:
        points = turning_points(v, REVERSAL_TOLERANCE * span)
    lo_hit = np.flatnonzero(v <= REST_TOLERANCE * span)
    hi_hit = np.flatnonzero(v >= (1 - REST_TOLERANCE) * span)
    if lo_hit.size == 0 or hi_hit.size == 0:
        # an input range wider than the record: the record never sweeps it
        return int(v.size)
    swept = max(lo_hit[0], hi_hit[0])
    valleys = [i for i, kind in points if kind < 0 and i >= swept]
    return int(valleys[0] if valleys else swept) + 1


def record_settling_end(u):
    """:func:`settling_end` of the input ``u`` over its own range, as :func:`pihyst.fit`
    judges a record (without ``input_range``); 0 for a constant input (nothing sweeps)."""
    u = np.asarray(u, dtype=float)
    if u.size == 0:
        return 0
    lo, span = float(u.min()), float(np.ptp(u))
    if not span > 0:
        return 0
    return settling_end(u - lo, span)


def layout(v, span, *, settle, holdout):
    """Cut the record v (shifted to [0, span]) into settle/fit/held-back segments.

    ``settle``: whether the first full sweep only settles the operators.
    ``holdout``: "alternate", a fraction in (0, 1), or None/0 (nothing held back).
    """
    n = v.size
    tol = REVERSAL_TOLERANCE * span
    points = turning_points(v, tol)
    settle_end = 0
    if settle:
        settle_end = settling_end(v, span, points)
        if n - settle_end < MIN_SAMPLES:
            raise FitError(f"the record does not start at rest, and after its first full "
                           f"sweep of the input range, which settles the operator states, "
                           f"only {n - settle_end} samples remain (at least {MIN_SAMPLES} "
                           f"needed): record more cycles, or give the initial state "
                           f"(initial_state= in Python, --initial-state on the command line)",
                           index=n - 1)
    cuts = [settle_end] + [i + 1 for i, kind in points
                           if kind < 0 and settle_end < i + 1 < n] + [n]
    pieces = []
    for a, z in zip(cuts[:-1], cuts[1:]):
        # a piece in which the input hardly moves (a turning point right at a cut) is
        # merged into the one before it
        if pieces and np.ptp(v[a:z]) < 2 * tol:
            pieces[-1] = (pieces[-1][0], z)
        elif z > a:
            pieces.append((a, z))
    major = [np.ptp(v[a:z]) >= (1 - MAJOR_TOLERANCE) * span for a, z in pieces]
    roles = ["fit"] * len(pieces)
    if holdout == "alternate":
        n_major = n_minor = 0
        for k, is_major in enumerate(major):
            if is_major:
                roles[k] = "held_back" if n_major % 2 else "fit"
                n_major += 1
            else:
                roles[k] = "held_back" if n_minor % 2 == 0 else "fit"
                n_minor += 1
        if "fit" not in roles:           # a single minor piece: fit it
            roles = ["fit"] * len(pieces)
        description = "alternate cycles"
    elif holdout:
        f = _holdout_fraction(holdout)
        target = settle_end + (1 - f) * (n - settle_end)
        bounds = [a for a, _ in pieces[1:]]
        if bounds:
            cut = min(bounds, key=lambda b: abs(b - target))
            roles = ["fit" if a < cut else "held_back" for a, _ in pieces]
        description = f"last {f:g} of the record"
    else:
        description = "none"
    segments = ([(0, settle_end, "settle")] if settle_end else []) + \
        [(a, z, role) for (a, z), role in zip(pieces, roles)]
    kinds = (["settle"] if settle_end else []) + ["major" if m else "minor" for m in major]
    return Layout(segments=segments, n_cycles=len(pieces),
                  n_minor=int(len(major) - sum(major)), settle_end=settle_end,
                  holdout=description if "held_back" in roles else "none", kinds=kinds,
                  points=points)


def _holdout_fraction(holdout):
    """``holdout`` as a fraction in (0, 1); a FitError naming it otherwise."""
    if isinstance(holdout, (str, bytes, bool, np.bool_)) or \
            not isinstance(holdout, numbers.Real) or not 0 < holdout < 1:
        raise FitError(f"holdout must be 'alternate', a fraction in (0, 1) or None, got "
                       f"{holdout!r:.40}")
    return float(holdout)
