"""Identification of creep together with the hysteresis weights (docs/theory/creep.md).

The model with creep is

    H[t] = c + sum_k w_k f_k[t]                       (the PI model: settled displacement)
    z_i[t] = z_i[t-1] + alpha_i[t] (H[t] - z_i[t-1]), alpha_i[t] = 1 - exp(-dt[t]/tau_i)
    y[t] = H[t] - sum_i g_i (H[t] - z_i[t]).

With the time constants tau_i fixed (half decades from the sampling to the record's
length), y is linear in (w, c) and in g separately, but not jointly: the lags are driven
by H, which depends on w. Writing psi_i = H - z_i (the part of each change a lag has not
yet followed), one QP solves

    min || Phi w + c - sum_i g_i psi_i(H_prev) - y ||^2,
    w >= 0 (monotone hysteresis), g = B p, 0 <= p <= G/(2n) (so 0 <= g, sum_i g_i <= G < 1),

with psi from the previous estimate H_prev of the hysteresis output, and is repeated with
H_prev = Phi w + c until H stops changing (creep is a few percent of H, so two or three
passes; B is :func:`log_t_basis`). The structure (family, thresholds, shape) is chosen by
the ordinary fit, run again on the record with the estimated creep removed,
y + sum_i g_i psi_i; the joint QP then refits its weights and the creep gains together.
"""

import numpy as np

from pihyst import _core
from pihyst.exceptions import FitError
from pihyst.identify._qp import solve_qp
from pihyst.model._creep import MAX_TOTAL_GAIN, Creep, default_time_constants

__all__ = ["fit_with_creep"]

CHUNK = 1 << 15
MAX_PASSES = 6


def log_t_basis(n, n_seen=None):
    """Gains g = B p of n lags at half-decade time constants (fastest first), p >= 0:

        g_i = p_0 + p_1 s_i,  s_i = min(i / (n_seen - 1), 1) in [0, 1],

    a creep rate per decade p_0 (equal gains over log-spaced lags: creep linear in
    log t, as measured on piezo actuators) plus a non-negative rise toward the slow
    lags. Free gains would alias: on a record driven at a constant rate a lag much
    faster than the ramps adds tau dH/dt, the sign of the direction, which is a
    hysteresis width, not creep (measured on the simulated beams: free gains put 5 %
    on the 0.3-1 s lags and tripled the tracking error on staircases). ``n_seen`` (default
    n) lags have time constants within the record; the slower ones keep the last one's
    gain: beyond the record creep goes on at the last measured rate per decade.
    """
    n_seen = n if n_seen is None else max(1, min(int(n_seen), n))
    s = np.minimum(np.arange(n) / (n_seen - 1), 1.0) if n_seen > 1 else np.zeros(n)
    return np.column_stack([np.ones(n), s])


def _times(t, n):
    if t is None:
        raise FitError("creep=True needs the sample times: fit(u, y, t=time_s, creep=True)")
    t = np.asarray(t, dtype=np.float64)
    if t.ndim != 1 or t.size != n:
        raise FitError(f"t must have one time per sample ({n}), got shape {t.shape}")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise FitError(f"t[{bad[0]}] is {t[bad[0]]}, not a finite time", index=int(bad[0]))
    dt = np.diff(t)
    back = np.flatnonzero(dt < 0)
    if back.size:
        raise FitError(f"time runs backwards at sample {back[0] + 1}", index=int(back[0] + 1))
    positive = dt[dt > 0]
    if positive.size == 0:
        raise FitError("t does not advance: creep needs sample times that do")
    return float(np.median(positive)), np.r_[np.median(positive), dt], float(t[-1] - t[0])


def _lag_deficits(model, h, dt, tau, start_state):
    """psi[t, i] = H[t] - z_i[t] for the lags driven by h from rest at H(initial state)."""
    lags = _core.Creep(tau, np.zeros(tau.size), 1.0,
                       np.full(tau.size, model.hysteresis_output(start_state)))
    out = np.empty((h.size, tau.size))
    for a in range(0, h.size, CHUNK):
        b = min(a + CHUNK, h.size)
        out[a:b] = h[a:b, None] - lags.lag_states(h[a:b], dt[a:b])
    return out


def _joint_qp(model, u, y, dt, tau, *, start, offset, nonnegative, free_weights=True,
              duration=np.inf):
    """Weights, offset and creep gains of ``model``'s operators by repeated joint QPs.

    ``free_weights=False`` (a regularized kernel basis): the weights keep their shape,
    w = q w_0 with one scale q >= 0, so the joint QP cannot undo the regularization.
    """
    hyst = model.replace(creep=None)
    h = hyst.predict(u)
    basis = np.eye(model.n_operators) if free_weights else model.weights[:, None].copy()
    k, n = basis.shape[1], tau.size
    fit_offset = offset is True
    fixed_offset = 0.0 if offset is False else (None if fit_offset else float(offset))
    tie = log_t_basis(n, int(np.count_nonzero(tau <= duration)))
    p = tie.shape[1]
    cols = k + fit_offset + p
    lower = np.r_[np.zeros(k) if nonnegative else np.full(k, -np.inf),
                  np.full(int(fit_offset), -np.inf), np.zeros(p)]
    # g_i = p_0 + p_1 s_i <= p_0 + p_1: bounding both by G / (2n) keeps sum_i g_i <= G
    upper = np.r_[np.full(k + fit_offset, np.inf), np.full(p, MAX_TOTAL_GAIN / (2 * n))]
    names = ([f"w[{i}]" for i in range(k)] if free_weights else ["weight scale"]) + \
        ["offset"] * fit_offset + ["creep per lag", "creep rise toward slow lags"]
    span = max(float(np.ptp(y[start:])), 1e-300)
    gains, passes = np.zeros(n), 0
    while passes < MAX_PASSES:
        passes += 1
        psi = _lag_deficits(hyst, h, dt, tau, hyst.initial_state)
        gram, rhs = np.zeros((cols, cols)), np.zeros(cols)
        state = hyst.initial_state
        for a in range(0, u.size, CHUNK):
            b = min(a + CHUNK, u.size)
            phi = hyst.operators(u[a:b], initial_state=state)
            state = phi[-1]
            phi = phi @ basis
            lo = max(start - a, 0)
            if lo >= b - a:
                continue
            x = np.hstack([phi[lo:], np.ones((b - a - lo, int(fit_offset))),
                           -psi[a + lo:b] @ tie])
            d = y[a + lo:b] - (fixed_offset or 0.0)
            gram += x.T @ x
            rhs += x.T @ d
        sol = solve_qp(gram, rhs, lower=lower, upper=upper, warn=False, names=names).x
        w = basis @ sol[:k]
        c = sol[k] if fit_offset else fixed_offset
        gains = np.clip(tie @ sol[k + fit_offset:], 0.0, None)
        hyst = hyst.replace(weights=w, offset=c)
        h_new = hyst.predict(u)
        change = float(np.max(np.abs(h_new - h)))
        h = h_new
        if change <= 1e-6 * span:
            break
    return hyst, gains, passes


def _free(model):
    """Whether the joint QP may move every weight: not for the regularized kernel basis
    (family kp), whose weights it would overfit without the regularization."""
    return model.metadata.get("fit", {}).get("family") != "kp"


def _rms(model, u, y, t, start):
    return float(np.sqrt(np.mean((model.predict(u, t=t)[start:] - y[start:]) ** 2)))


def fit_with_creep(fit, u, y, t, *, time_constants=None, **kwargs):
    """``fit(u, y, **kwargs)`` with creep: the structure from the ordinary fit of the
    record with its creep removed, then weights and creep gains in one QP (module notes).

    ``fit`` is :func:`pihyst.fit` (passed in: this module sits beside it).
    """
    u = np.asarray(u, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if kwargs.get("through") is not None:
        raise FitError("through= (equality constraints) is not available with creep=True")
    dt_fixed, dt, duration = _times(t, u.size)
    tau = (default_time_constants(dt_fixed, duration) if time_constants is None
           else np.sort(np.asarray(time_constants, dtype=np.float64)))
    if tau.size == 0 or not np.all(np.isfinite(tau)) or np.any(tau <= 0):
        raise FitError("creep time constants must be finite and > 0 s")
    offset = kwargs.get("offset", True)
    nonnegative = kwargs.get("nonnegative", True)
    t = np.asarray(t, dtype=np.float64)

    first = fit(u, y, **kwargs)
    # the delay the first fit chose (or was given) holds for the second; the creep QPs
    # run on the aligned record u[k] -> y[k + d], its lags at the output's times
    d = first.model.delay
    kwargs["delay"] = d
    ua, ya, dta = u[:u.size - d], y[d:], np.r_[dt[0], dt[d + 1:]]
    start = first.model.metadata.get("fit", {}).get("settled", {}).get("sample", 0)
    # first creep estimate: every weight free (a kp basis may overfit here; only the
    # creep estimate is kept, the structure and weights are fitted again below)
    hyst, gains, _ = _joint_qp(first.model.replace(delay=0), ua, ya, dta, tau, start=start,
                               offset=offset, nonnegative=nonnegative, duration=duration)
    # the record without its creep: the settled displacement the structure is chosen on
    psi = _lag_deficits(hyst, hyst.predict(ua), dta, tau, hyst.initial_state)
    second = fit(u, np.r_[y[:d], ya + psi @ gains], **kwargs)
    start = second.model.metadata.get("fit", {}).get("settled", {}).get("sample", 0)
    hyst, gains, passes = _joint_qp(second.model.replace(delay=0), ua, ya, dta, tau,
                                    start=start, offset=offset, nonnegative=nonnegative,
                                    duration=duration, free_weights=_free(second.model))
    aligned = hyst.replace(creep=Creep(tau, gains, dt_fixed))
    model = aligned.replace(delay=d, sample_period=dt_fixed if d else None)
    meta = dict(second.model.metadata)
    summary = dict(meta.get("fit", {}))
    summary["creep"] = {
        "tau_s": tau.tolist(), "gain": gains.tolist(), "dt_s": dt_fixed,
        "creep_total": float(gains.sum()), "qp_passes": passes,
        "rms_without_creep": _rms(first.model.replace(delay=0), ua, ya, None, start),
        "rms_with_creep": _rms(aligned, ua, ya, t[d:], start),
        "weights": "free" if _free(second.model) else "one scale (regularized kp shape)",
        "note": ("family and thresholds chosen on the record with the estimated creep "
                 "removed; weights, offset and creep gains fitted together on every "
                 "sample after the settling sweep"),
    }
    meta["fit"] = summary
    report = second.report
    if d and "delay" in summary.get("data", {}):
        # the delay was chosen by the first fit (the second was given it): its report
        report = _with_delay_of(second.report, first.report)
        summary["data"] = report.to_dict()["data"]
        summary["undetermined"] = report.to_dict()["undetermined"]
    model = model.replace(metadata=meta)
    models = dict(second.models)
    models[summary.get("family", model.family)] = model
    return type(second)(model=model, report=report, models=models)


def _with_delay_of(report, chooser):
    """``report`` with the delay entry and the delay's note of the report ``chooser``."""
    data, other = report.to_dict(), chooser.to_dict()
    data["data"]["delay"] = other["data"]["delay"]
    note = "the input-output delay:"
    data["undetermined"] = ([t for t in data["undetermined"] if not t.startswith(note)]
                            + [t for t in other["undetermined"] if t.startswith(note)])
    return type(report)(data)
