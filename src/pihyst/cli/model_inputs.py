"""What a command runs a model on: the input range rule for voltages a hair outside the
model's range, and the operator state at the first sample (--initial-state).

The rule (docs/records.md): a voltage outside the model's input range by at most
``TOLERANCE`` of its span is predicted, with the operators extended past the range where
the model allows it (classical and piecewise-linear models) or at the nearest end of the
range (a multislope model's envelopes end at U), and the command says how many samples,
how far, and over which span the model was fitted. A voltage farther out is an error.
"""

import numpy as np

from pihyst.cli.errors import UsageError
from pihyst.exceptions import InvalidArgumentError, InvalidModelError
from pihyst.identify._cycles import record_settling_end

TOLERANCE = 0.01
INITIAL_STATES = ("model", "bottom", "top", "zero", "settle")


class InputRange:
    """Checks voltages block by block against a model's input range with the tolerance,
    and gives the model (or the clamped voltages) to run them with."""

    def __init__(self, model):
        self.model = model
        lo, hi = model.input_range
        self.lo, self.hi = lo, hi
        self.margin = TOLERANCE * (hi - lo)
        self.outside = 0
        self.worst = 0.0
        # a Bouc-Wen model's input range is its normalization x = (u - u_lo) / (u_hi - u_lo):
        # another range would be another model, so its voltages are clamped instead
        if model.family == "bouc-wen":
            self.run_model, self.extends = model, False
            return
        try:
            self.run_model = model.replace(input_range=(lo - self.margin, hi + self.margin))
            self.extends = True
        except InvalidModelError:
            self.run_model, self.extends = model, False

    def check(self, u, record, quantity="voltage", name="voltage_V"):
        """The voltages to run (clamped if the model cannot be extended); an error at
        the first voltage beyond the tolerance."""
        if u.size == 0 or (u.min() >= self.lo and u.max() <= self.hi):
            return u
        far = np.flatnonzero((u < self.lo - self.margin) | (u > self.hi + self.margin))
        if far.size:
            i = int(far[0])
            raise record.error(i, quantity,
                               f"{name} = {u[i]:g} is outside the model's input range "
                               f"[{self.lo:g}, {self.hi:g}]{self._fitted()} by more than "
                               f"the {100 * TOLERANCE:g} % tolerance")
        out = (u < self.lo) | (u > self.hi)
        self.outside += int(out.sum())
        self.worst = max(self.worst, float(np.max(np.maximum(self.lo - u, u - self.hi))))
        return u if self.extends else np.clip(u, self.lo, self.hi)

    def _fitted(self):
        span = fitted_span(self.model)
        if span is None or tuple(span) == (self.lo, self.hi):
            return ""
        return f" (fitted on [{span[0]:g}, {span[1]:g}])"

    def note(self):
        """A line for the user, or None when every voltage was inside the range."""
        if not self.outside:
            return None
        how = ("the operators extended past it" if self.extends else
               "the voltage taken at the nearest end of the range (a multislope model's "
               "envelopes end there)")
        return (f"{self.outside} samples outside the model's input range "
                f"[{self.lo:g}, {self.hi:g}] V{self._fitted()} by up to {self.worst:.3g} V "
                f"(within the {100 * TOLERANCE:g} % tolerance) were predicted with {how}")


def fitted_span(model):
    """The input span the model was fitted on, from its metadata (None if unknown)."""
    data = model.metadata.get("fit", {}).get("data", {}) if hasattr(
        model.metadata.get("fit", {}), "get") else {}
    span = data.get("input_range") if hasattr(data, "get") else None
    return tuple(span) if span is not None and len(span) == 2 else None


def add_initial_state_option(p, modes=INITIAL_STATES, default="model"):
    p.add_argument("--initial-state", choices=modes, default=default,
                   help=f"operator state at the first sample (default {default}): 'model' "
                        "(the model file's), 'bottom' / 'top' (at rest at the bottom / top of the "
                        "input range after a full cycle), 'zero' (every operator at 0)"
                        + (", 'settle' (the first full sweep of the record settles the "
                           "operators; its samples are marked and left out of the errors)"
                           if "settle" in modes else ""))


def initial_state(model, mode):
    """The operator state a mode names (settle starts from the model's own state)."""
    lo, hi = model.input_range
    # the virgin state: zero operators, or for Bouc-Wen z = 0 at the bottom of the range
    zero = np.array([lo, 0.0]) if model.family == "bouc-wen" else np.zeros(model.n_operators)
    if mode in ("model", "settle"):
        return model.initial_state
    if mode == "zero":
        return zero
    # cycled without the delay: a delayed model would not yet see the last inputs
    model = model.replace(delay=0)
    if mode == "bottom":
        return model.simulate(np.array([lo, hi, lo]), initial_state=zero).final_state
    if mode == "top":
        return model.simulate(np.array([hi, lo, hi]), initial_state=zero).final_state
    raise UsageError(f"--initial-state: unknown mode {mode!r}")


def settle_end(u):
    """Index after the sweep of ``u`` that settles the operators (--initial-state settle):
    the rule of pihyst.fit(initial_state="settle"), so that a command and the fit judge
    the same samples."""
    return record_settling_end(u)


def creep_times(model, rec, t_last):
    """The keyword arguments that run a model with creep at a record chunk's sample times:
    ``t`` (its time column, or none: every ``creep.dt``) and ``t_previous`` (the previous
    chunk's last time); empty for a model without creep. A time that is not finite or
    runs backwards is an error at its file, line and column."""
    if getattr(model, "creep", None) is None or rec.time is None:
        return {}
    t = rec.time
    full = t if t_last is None else np.r_[t_last, t]
    bad = np.flatnonzero(~np.isfinite(full) | np.r_[False, np.diff(full) < 0])
    if bad.size:
        i = int(bad[0]) - (0 if t_last is None else 1)
        what = "is not a finite time" if not np.isfinite(full[bad[0]]) else "runs backwards"
        raise rec.error(max(i, 0), "time", f"time_s = {t[max(i, 0)]:g} {what}: the model's "
                        f"creep needs increasing sample times")
    return {"t": t, "t_previous": t_last}


def delay_for_run(model, path, *, t=None, period=None):
    """``model`` with its delay in samples of a run at the sample times ``t`` (s) or the
    sample period ``period`` (s): converted when exact (docs/interfaces.md), unchanged
    without a delay or a period known on both sides. A delay that is not a whole number
    of the run's samples is a UsageError naming ``path``, the file that sets the run's
    period (the record, or the rig's configuration)."""
    if not model.delay or model.sample_period is None or (t is None and period is None):
        return model
    try:
        d = model.delay_at(period, t=t)
    except InvalidArgumentError as err:
        raise UsageError(f"{path}: {err}") from None
    if period is None:
        steps = np.diff(np.asarray(t, dtype=np.float64))
        if steps.size == 0:
            return model
        period = float(np.median(steps))
    # the converted delay holds at the run's period (a later conversion is the identity)
    return model.replace(delay=d, sample_period=period)
