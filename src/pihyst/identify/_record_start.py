"""Did the record's creep start at rest? (docs/theory/creep.md, "A record that does not
start at rest").

A creep model starts with its lags settled at the first output. An actuator that held
another voltage just before the record starts with lags away from rest, and a lag that
starts at z_i[0] = H[0] + delta_i keeps the difference as it decays, exactly:

    z_i[t] = z_i^rest[t] + delta_i exp(-(t - t_0) / tau_i)

(each step multiplies it by 1 - alpha_i[t] = exp(-dt[t] / tau_i)), so the record holds

    y[t] = y^rest[t] + sum_i e_i exp(-(t - t_0) / tau_i),    e_i = g_i delta_i,     (1)

a sum of decays from its start that a model fitted from rest cannot follow: it bends its
creep gains towards them instead, and holds (staircases) then go wrong. Measured on the
simulated paper beam recorded on decaying triangles after a 10-600 s hold at the top of
the range: 0.08 % of range on staircases from rest, 0.36-1.0 % after the hold.

Fitting the e_i of (1) with the gains does not mend it: a record that starts at rest
carries its own creep transient, the lags following the mean of H from its first value,
with the same decays, and the two cannot be told apart (the fitted gains came out 30-40 %
high and the staircases no better). What the record does tell is whether (1) is there:
the share of the fitted model's residual that the decays explain, which was at most 8 %
on the 30 random actuators of benchmarks/bench_population.py, recorded from rest, and
29-82 % after a hold. Above :data:`UNSETTLED_SHARE` the fit warns, with what to do.
"""

import warnings

import numpy as np

from pihyst.exceptions import InsufficientDataWarning
from pihyst.identify._constants import MIN_DECAY, UNSETTLED_SHARE

# the residual's least squares on the decays runs on at most about this many samples
MAX_ROWS = 50_000


def start_columns(t, tau, duration):
    """E (N x m): the decays of (1), exp(-(t - t_0) / tau_i) for the lags within the
    record (tau_i <= ``duration``); the slower ones decay as 1 - (t - t_0) / tau_i over
    it, a constant and the ramp (t - t_0) / duration, which is the last column."""
    s = np.asarray(t, dtype=np.float64) - float(t[0])
    tau = np.asarray(tau, dtype=np.float64)
    seen = tau[tau <= duration]
    cols = [np.exp(-s / tau_i) for tau_i in seen]
    if seen.size < tau.size:
        cols.append(s / max(float(duration), 1e-300))
    return np.column_stack(cols) if cols else np.zeros((s.size, 0))


def start_decay(residual, t, tau, duration):
    """(share, rms): the share of ``residual``'s variance (mean removed) that the decays
    of (1) explain, and the RMS of what they explain (least squares on [1, E] over at
    most about :data:`MAX_ROWS` evenly spaced rows)."""
    r = np.asarray(residual, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    keep = slice(None, None, max(1, r.size // MAX_ROWS))
    E = start_columns(t, tau, duration)[keep]
    r = r[keep]
    rc = r - r.mean()
    total = float(rc @ rc)
    if E.shape[1] == 0 or total <= 0.0:
        return 0.0, 0.0
    X = np.column_stack([np.ones(r.size), E])
    part = X @ np.linalg.lstsq(X, r, rcond=None)[0]
    part = part - part.mean()
    share = float(np.clip(1.0 - float((rc - part) @ (rc - part)) / total, 0.0, 1.0))
    return share, float(np.sqrt(np.mean(part * part)))


def record_start_check(residual, t, tau, duration, span):
    """The entry ``record_start`` of the creep decision: how much of the fitted model's
    error on the record is a decay from its start (:func:`start_decay`), and whether
    the record started at rest: not when that is more than :data:`UNSETTLED_SHARE` of
    the error and more than :data:`MIN_DECAY` of the output ``span`` (a model that fits
    well has an error of little else); warns (InsufficientDataWarning) when not."""
    share, rms = start_decay(residual, t, tau, duration)
    settled = share <= UNSETTLED_SHARE or rms <= MIN_DECAY * span
    note = (f"{100 * share:.0f} % of the model's error on the record is a decay from its "
            f"start, {100 * rms / max(span, 1e-300):.2g} % of the output range RMS (not "
            f"at rest: more than {100 * UNSETTLED_SHARE:g} % and {100 * MIN_DECAY:g} %)")
    if not settled:
        advice = (f"the record's creep likely did not start at rest: {note}. The actuator "
                  f"held another voltage before the record (or started in another "
                  f"hysteresis state than the fit assumed)? Creep fitted from it may be off "
                  f"on holds; before recording, leave the actuator at the record's first "
                  f"voltage for longer than the record ({float(duration):.3g} s)")
        warnings.warn(advice, InsufficientDataWarning, stacklevel=4)
        note = advice
    return {"settled": bool(settled), "decay_share": share, "decay_rms": rms, "note": note}
