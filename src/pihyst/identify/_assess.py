"""How well a fitted model generalizes: its error on each kind of held-back data, and
what the data cannot tell.

Users' trajectories differ from an identification record by their amplitudes and by
reversals inside the range (minor loops). A fitted family is therefore judged on every
kind of held-back data there is:

- the record's held-back **major cycles** (the same loop as the fitted ones: noise,
  drift, the fit's variance);
- its held-back **minor cycles** (other amplitudes, interior reversals);
- a **validation record** (``fit(..., validate=(u2, y2))``): another trajectory, maybe
  another day. Its sensor zero is arbitrary, so the mean error is removed; the operator
  states are unknown until its input has swept its own range once, so the samples
  before are run but not judged.

The judged error of a family is the worst RMS over the record's held-back cycles and
the validation record. A record **determines the minor loops** if both its fitted and
its held-back parts reverse inside the range (or a validation record does); otherwise
only families whose structure fixes the minor loops from the major loop (PI-type:
``family.minor_loops_fixed``) are trusted there.
"""

from dataclasses import dataclass

import numpy as np

from pihyst.exceptions import FitError
from pihyst.identify._cycles import MAJOR_TOLERANCE, REVERSAL_TOLERANCE, turning_points
from pihyst.metrics import error_summary

KINDS = {"major": "held-back major cycles", "minor": "held-back minor cycles",
         "validation": "validation record"}


def interior_reversals(v, S, indices=None, points=None):
    """Number of turning points of v (on [0, S]) inside the range by more than
    MAJOR_TOLERANCE of the span: the reversals that make minor loops. ``indices``:
    count only those among these samples; ``points``: v's turning points if known."""
    if points is None:
        points = turning_points(v, REVERSAL_TOLERANCE * S)
    inner = [i for i, kind in points
             if (kind > 0 and v[i] < (1 - MAJOR_TOLERANCE) * S)
             or (kind < 0 and v[i] > MAJOR_TOLERANCE * S)]
    if indices is None:
        return len(inner)
    return int(np.isin(inner, indices).sum())


@dataclass
class ValidationRecord:
    """A second record, judged but not fitted (see the module docstring)."""

    u: np.ndarray
    y: np.ndarray
    judged_from: int
    minor_reversals: int

    @classmethod
    def build(cls, pair, lo, S, delay):
        try:
            u2, y2 = pair
        except (TypeError, ValueError):
            raise FitError("validate must be a pair (u, y) of equal-length sequences") from None
        u2, y2 = (np.array(a, dtype=float) for a in (u2, y2))
        if u2.ndim != 1 or u2.shape != y2.shape:
            raise FitError(f"validate: input and output must be one-dimensional and of equal "
                           f"length, got shapes {u2.shape} and {y2.shape}")
        for name, a in (("input", u2), ("output", y2)):
            bad = np.flatnonzero(~np.isfinite(a))
            if bad.size:
                raise FitError(f"validate: {name} sample {bad[0]} is {a[bad[0]]}, not a "
                               f"finite number", index=int(bad[0]), column=name)
        if delay:
            u2, y2 = u2[:-delay], y2[delay:]
        outside = np.flatnonzero((u2 < lo) | (u2 > lo + S))
        if outside.size:
            i = outside[0]
            raise FitError(f"validate: input sample {i} = {u2[i]:g} is outside the model's "
                           f"input range [{lo:g}, {lo + S:g}]", index=int(i), column="input")
        # judged once the input has swept its own range (both ends within 5 % of its span)
        if u2.size == 0 or np.ptp(u2) <= 2 * REVERSAL_TOLERANCE * S:
            raise FitError("validate: the input hardly moves; nothing to judge a model on")
        tol = MAJOR_TOLERANCE * np.ptp(u2)
        lo_hit = np.flatnonzero(u2 <= u2.min() + tol)[0]
        hi_hit = np.flatnonzero(u2 >= u2.max() - tol)[0]
        start = int(max(lo_hit, hi_hit)) + 1
        if u2.size - start < 2:
            raise FitError("validate: the record ends as soon as its input has swept its "
                           "range once (before that the operator states are unknown)")
        minor = interior_reversals(u2 - lo, S, np.arange(start, u2.size))
        return cls(u=u2, y=y2, judged_from=start, minor_reversals=minor)

    def errors(self, model):
        """Error summary after the sweep, mean error removed."""
        y_hat = model.predict(self.u)[self.judged_from:]
        y = self.y[self.judged_from:]
        y_hat = y_hat - np.mean(y_hat - y)
        return error_summary(y, y_hat, float(np.ptp(y)))

    def describe(self):
        return {"samples": int(self.u.size), "judged_from": self.judged_from,
                "judged_samples": int(self.u.size - self.judged_from),
                "interior_reversals": self.minor_reversals,
                "mean_error": "removed (the sensor's zero differs between records)"}


def minor_loops_determined(rec, validation):
    """Whether the data say how the actuator behaves inside the range, and why not."""
    lay = rec.layout
    fitted = interior_reversals(rec.v, rec.S, lay.indices("fit"), lay.points)
    held = interior_reversals(rec.v, rec.S, lay.indices("held_back"), lay.points)
    if validation is not None and validation.minor_reversals:
        return True, None
    if fitted and held:
        return True, None
    where = ("the record never reverses inside its range (only major loops)"
             if not fitted + held else
             "the record reverses inside its range only in its " +
             ("fitted" if fitted else "held-back") + " part, so the minor loops cannot "
             "be both fitted and judged")
    return False, where


def errors_by_kind(fitter, model, validation):
    """{kind: error summary} for every kind of held-back data present."""
    rec = fitter.rec
    y_hat = fitter.predict(model)
    out = {}
    for kind in ("major", "minor"):
        i = rec.layout.indices("held_back", kind)
        if i.size:
            out[kind] = error_summary(rec.y[i], y_hat[i], rec.measured_range)
    if validation is not None:
        out["validation"] = validation.errors(model)
    return out


def judged_rms(fitted, by_kind):
    """The worst RMS over the record's held-back cycles and the validation record;
    the fitted RMS if nothing is held back."""
    values = [e["rms"] for e in (fitted.errors["held_back"], by_kind.get("validation"))
              if e is not None]
    return max(values) if values else fitted.errors["fit"]["rms"]
