"""Can the record support a model? The checks :func:`pihyst.fit` makes before and after
fitting, so that data that cannot be fitted gives a clear :class:`FitError` (or a warning)
and never a solver's internal message.

Before fitting (:func:`check_record`), a :class:`FitError` for

- values so large that the sums of their squares overflow (the normal equations), or so
  small, or so close together next to their size, that floating point cannot resolve
  their changes;
- too little excitation: an input with fewer than :data:`MIN_INPUT_LEVELS` distinct
  levels, or one that never reverses (a rise alone, or a fall alone, has no loop).

After fitting (:func:`check_fit`), on the chosen model:

- a :class:`FitError` when it explains less than :data:`MIN_EXPLAINED` of the output's
  variance on the samples it is judged on (pure noise, or the wrong columns): such a
  model would compensate nothing;
- an :class:`InsufficientDataWarning` when it explains less than :data:`WEAK_EXPLAINED`,
  or when its loop is narrower than :data:`MIN_LOOP_WIDTH` of its output span (the
  record shows no hysteresis: the model is a plain curve).
"""

import warnings

import numpy as np

from pihyst.exceptions import FitError, InsufficientDataWarning
from pihyst.identify._constants import (
    MIN_EXPLAINED,
    MIN_INPUT_LEVELS,
    MIN_LOOP_WIDTH,
    WEAK_EXPLAINED,
)

MAX_MAGNITUDE = 1e100        # sums of N squares stay far from the float64 overflow
MIN_MAGNITUDE = 1e-100       # spans smaller than this underflow once squared
MIN_RELATIVE_SPAN = 1e-9     # span / magnitude: fewer digits than that left to fit
_LOOP_POINTS = 201


def check_record(u, y):
    """FitError if the record ``(u, y)`` (finite, equal lengths) cannot support a model."""
    for values, column in ((u, "input"), (y, "output")):
        magnitude = float(np.max(np.abs(values)))
        if magnitude > MAX_MAGNITUDE:
            i = int(np.argmax(np.abs(values)))
            raise FitError(f"{column} values reach {values[i]:.3g}: too large to fit (the sums "
                           f"of their squares overflow); rescale the {column} (other units)",
                           index=i, column=column)
        span = float(np.max(values)) - float(np.min(values))
        if 0 < span < max(MIN_MAGNITUDE, MIN_RELATIVE_SPAN * magnitude):
            raise FitError(f"the {column} varies by only {span:.3g} around {magnitude:.3g}: "
                           f"too little for floating point to fit; rescale or remove the "
                           f"constant part of the {column}", column=column)
    levels = np.unique(u).size
    if levels < MIN_INPUT_LEVELS:
        raise FitError(f"the input takes only {levels} distinct values: too little excitation "
                       f"to identify a loop; record a sweep of the input up and down",
                       column="input")
    steps = np.sign(np.diff(u))
    steps = steps[steps != 0]
    if not np.any(steps[1:] != steps[:-1]):
        way = "rises" if steps[0] > 0 else "falls"
        raise FitError(f"the input never reverses (it only {way}): a loop needs a rise and a "
                       f"fall, so no hysteresis can be identified; record a sweep up and down",
                       column="input")


def check_fit(rec, judged_rms, model):
    """FitError or InsufficientDataWarning for a fitted model the record ``rec`` (a
    FramedRecord) hardly supports; ``judged_rms`` is the model's RMS error on the samples
    it is judged on (held back, or fitted when nothing is held back)."""
    judged = rec.layout.indices("held_back" if rec.has_held_back else "fit")
    variance = float(np.var(rec.y[judged])) if judged.size else 0.0
    explained = 1.0 - judged_rms ** 2 / variance if variance > 0 else 0.0
    if explained < MIN_EXPLAINED:
        falling = _falling(rec.u[judged], rec.y[judged])
        if falling is not None:
            raise FitError(f"the displacement falls as the voltage rises (correlation "
                           f"{falling:.2f}) and a hysteresis model rises with its input: "
                           f"if the sensor counts the other way (a distance to the "
                           f"target), negate the displacement (pihyst fit "
                           f"--displacement-gain -1, or fit(u, -y))", column="output")
        raise FitError(f"the displacement does not follow the voltage: the best model "
                       f"explains only {100 * max(explained, 0.0):.0f} % of its variance on "
                       f"the samples it is judged on (pure noise, or the wrong columns?)",
                       column="output")
    if explained < WEAK_EXPLAINED:
        warnings.warn(f"the model explains only {100 * explained:.0f} % of the displacement's "
                      f"variance on the samples it is judged on: the record is noisy or not "
                      f"the kind of hysteresis a PI model describes", InsufficientDataWarning,
                      stacklevel=3)
    width, span = loop_width(model)
    if span > 0 and width < MIN_LOOP_WIDTH * span:
        warnings.warn(f"the record shows no hysteresis: the fitted loop is "
                      f"{100 * width / span:.2g} % of the output span wide, so the model is "
                      f"a plain curve (is the displacement column the measured one?)",
                      InsufficientDataWarning, stacklevel=3)


def _falling(u, y):
    """The correlation of ``y`` with ``u`` where it is clearly negative (below -0.5: a
    displacement that falls as the voltage rises), else None."""
    if u.size < 2 or np.ptp(u) == 0 or np.ptp(y) == 0:
        return None
    r = float(np.corrcoef(u, y)[0, 1])
    return r if r < -0.5 else None


def loop_width(model):
    """(largest gap between the falling and rising branch, output span) of the model's
    major loop over its input range, after one settling cycle."""
    lo, hi = model.input_range
    up = np.linspace(lo, hi, _LOOP_POINTS)
    down = up[::-1]
    cycle = np.concatenate((up, down[1:], up[1:], down[1:]))
    y = model.predict(cycle)
    rising = y[2 * _LOOP_POINTS - 2:3 * _LOOP_POINTS - 2]
    falling = y[3 * _LOOP_POINTS - 3:][::-1]
    return float(np.max(np.abs(falling - rising))), float(np.ptp(y))
