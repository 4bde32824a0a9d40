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

A Bouc-Wen model (docs/theory/bouc-wen.md) carries creep the same way: for a fixed
shape (beta, gamma, n) its output H = c + c_1 x + c_2 x^2 + a z is linear in
(c, c_1, c_2, a) under the monotonicity bound, which becomes plain bounds in two cases
(a >= 0, a <= 0; identify/_boucwen.py), so each pass solves the same bounded QP in
(c, c_1, c_2, a, p) once per case and keeps the better; the shape is searched with that
joint fit inside the criterion (:func:`_joint_qp_boucwen`, identify/_boucwen_creep.py).
"""

import functools
import warnings

import numpy as np

from pihyst.exceptions import FitError, PihystWarning
from pihyst.identify._boucwen_creep import fit_shape_and_creep, lag_deficits
from pihyst.identify._choice import TOLERANCE
from pihyst.identify._families import CREEP_FAMILIES
from pihyst.identify._family_fit import FramedRecord
from pihyst.identify._progress import Steps
from pihyst.identify._qp import solve_qp
from pihyst.identify._record_start import record_start_check
from pihyst.model._boucwen import BoucWenModel
from pihyst.model._creep import MAX_TOTAL_GAIN, Creep, default_time_constants

__all__ = ["fit_with_creep"]

CHUNK = 1 << 15
# Creep estimated with the other kind of model (Bouc-Wen against PI operators) is tried
# only where it could win: that kind's held-back RMS without creep at most CREEP_REACH
# times what the chosen family reaches with creep. Creep lowered a family's held-back RMS
# by up to 10x on the population (benchmarks/bench_population.py: Bouc-Wen actuators
# 4.9-10.3x, Preisach 2.6-9.1x with their own kind); twice that for margin. The other
# kind costs a second creep fit (a Bouc-Wen one doubles the fit time).
CREEP_REACH = 20.0
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
    return lag_deficits(h, model.hysteresis_output(start_state), dt, tau)


def _joint_qp(model, u, y, dt, tau, *, start, offset, nonnegative, free_weights=True,
              duration=np.inf, rows=None):
    """Weights, offset and creep gains of ``model``'s operators by repeated joint QPs on
    the samples ``rows`` (indices; default every sample from ``start``).

    ``free_weights=False`` (a regularized kernel basis): the weights keep their shape,
    w = q w_0 with one scale q >= 0, so the joint QP cannot undo the regularization.
    """
    fitted = np.zeros(u.size, dtype=bool)
    if rows is None:
        fitted[start:] = True
    else:
        fitted[rows] = True
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
    span = max(float(np.ptp(y[fitted])), 1e-300)
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
            sel = fitted[a:b]
            if not sel.any():
                continue
            x = np.hstack([phi[sel], np.ones((int(sel.sum()), int(fit_offset))),
                           -psi[a:b][sel] @ tie])
            d = y[a:b][sel] - (fixed_offset or 0.0)
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


def _joint_qp_boucwen(model, u, y, dt, tau, *, start, offset, duration=np.inf, rows=None,
                      fixed_n=None, **_):
    """Shape, linear part (offset, c_1, c_2, a) and creep gains of the Bouc-Wen
    ``model`` fitted together on the samples ``rows`` (default every sample from
    ``start``), the shape searched from ``model``'s (identify/_boucwen_creep.py; the
    gains tied by :func:`log_t_basis` as for :func:`_joint_qp`). A Bouc-Wen model always
    fits its offset."""
    if offset is not True:
        raise FitError("bouc-wen fits its own offset: a fixed offset is not available "
                       "with creep")
    fitted = np.zeros(u.size, dtype=bool)
    if rows is None:
        fitted[start:] = True
    else:
        fitted[rows] = True
    tie = log_t_basis(tau.size, int(np.count_nonzero(tau <= duration)))
    hyst, gains, passes, _ = fit_shape_and_creep(model.replace(creep=None), u, y, dt, tau,
                                                 tie, fitted, fixed_n=fixed_n)
    return hyst, gains, passes


def _joint_qp_of(model, fixed_n=None):
    """The joint QP of the model's kind: :func:`_joint_qp` (PI operators) or
    :func:`_joint_qp_boucwen` (``fixed_n``: the exponent the family was given)."""
    if isinstance(model, BoucWenModel):
        return functools.partial(_joint_qp_boucwen, fixed_n=fixed_n)
    return _joint_qp


def _fixed_exponent(family):
    """The exponent a Bouc-Wen family object among the ``family`` option fixes, or None."""
    specs = family if isinstance(family, (list, tuple)) else [family]
    return next((getattr(f, "n", None) for f in specs
                 if getattr(f, "name", None) == BoucWenModel.family), None)


def _free(model):
    """Whether the joint QP may move every weight: not for the regularized kernel basis
    (family kp), whose weights it would overfit without the regularization."""
    return model.metadata.get("fit", {}).get("family") != "kp"


def _rms(model, u, y, t, start):
    y_hat = model.predict(u) if t is None else model.predict(u, t=t)
    return float(np.sqrt(np.mean((y_hat[start:] - y[start:]) ** 2)))


def fit_with_creep(fit, u, y, t, *, time_constants=None, decide=False, **kwargs):
    """``fit(u, y, **kwargs)`` with creep: the structure from the ordinary fit of the
    record with its creep removed, then weights and creep gains in one QP (module notes).

    ``decide`` (``creep="auto"``): creep is kept only if it lowers the held-back RMS of
    the fit by more than the choice's tolerance (:func:`_judge`); otherwise the ordinary
    fit is returned, with the comparison in its report and metadata.

    ``fit`` is :func:`pihyst.fit` (passed in: this module sits beside it).
    """
    u = np.asarray(u, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    # the ordinary fits see the sample times too (a fitted delay's sample period)
    fit = functools.partial(fit, t=t, creep=False)
    if kwargs.get("through") is not None:
        if decide:
            return _without_creep(fit(u, y, **kwargs), {
                "kept": False, "reason": "through= (equality constraints) is not available "
                                         "with creep"})
        raise FitError("through= (equality constraints) is not available with creep=True")
    step = Steps(kwargs.get("progress"))
    first = fit(u, y, **kwargs)         # the record's own errors (too short, ...) first
    step.done(f"fit without creep: {first.report.chosen}")
    dt_fixed, dt, duration = _times(t, u.size)
    tau = (default_time_constants(dt_fixed, duration) if time_constants is None
           else np.sort(np.asarray(time_constants, dtype=np.float64)))
    if tau.size == 0 or not np.all(np.isfinite(tau)) or np.any(tau <= 0):
        raise FitError("creep time constants must be finite and > 0 s")
    offset = kwargs.get("offset", True)
    nonnegative = kwargs.get("nonnegative", True)
    t = np.asarray(t, dtype=np.float64)
    # the delay the first fit chose (or was given) holds for the second; the creep QPs
    # run on the aligned record u[k] -> y[k + d], its lags at the output's times
    d = first.model.delay
    kwargs["delay"] = d
    ua, ya, dta, ta = u[:u.size - d], y[d:], np.r_[dt[0], dt[d + 1:]], t[d:]
    qp = dict(offset=offset, nonnegative=nonnegative, duration=duration)
    fixed_n = _fixed_exponent(kwargs.get("family"))
    start_model = _creep_capable(first, kwargs.get("family") is not None or decide)
    rows = None
    if decide:
        rec = FramedRecord(ua, ya, input_range=kwargs.get("input_range"),
                           initial_state=kwargs.get("initial_state", "auto"),
                           holdout=kwargs.get("holdout", "alternate"), offset=offset,
                           through=None)
        if not rec.has_held_back:
            return _without_creep(first, {"kept": False, "reason": "nothing held back to "
                                          "judge it on (creep=True fits it regardless)"})
        if start_model is None:
            return _without_creep(first, {"kept": False, "reason": f"the chosen family, "
                                          f"{first.report.chosen}, cannot carry creep"})
        rows = rec.layout.indices("fit")
    elif start_model is None:
        raise FitError(f"a {first.report.chosen} model has no creep: fit creep with one of "
                       f"{', '.join(CREEP_FAMILIES)}")

    def structure_without_creep(model, families=None):
        """The ordinary fit of the record with the creep ``model``'s joint QP estimates
        removed (the settled displacement the structure is chosen on), among
        ``families`` (default: every creep-capable family the fit was given)."""
        model = model.replace(creep=None, delay=0)
        start = model.metadata.get("fit", {}).get("settled", {}).get("sample", 0)
        # every weight free (a kp basis may overfit here; only the creep estimate is
        # kept, the structure and weights are fitted again)
        hyst, gains, _ = _joint_qp_of(model, fixed_n)(model, ua, ya, dta, tau, start=start,
                                                      rows=rows, **qp)
        psi = _lag_deficits(hyst, hyst.predict(ua), dta, tau, hyst.initial_state)
        second_kw = dict(kwargs)
        if families is not None:
            second_kw["family"] = families
        elif second_kw.get("family") is None:
            second_kw["family"] = list(CREEP_FAMILIES)
        if not decide:
            return fit(u, np.r_[y[:d], ya + psi @ gains], **second_kw)
        # a trial: its warnings are about the record with this creep estimate removed,
        # and are the user's only if that structure is kept (_keep_warnings)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", PihystWarning)
            second = fit(u, np.r_[y[:d], ya + psi @ gains], **second_kw)
        trial_warnings[id(second)] = [w for w in caught
                                      if issubclass(w.category, PihystWarning)]
        for w in caught:
            if not issubclass(w.category, PihystWarning):
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        return second

    trial_warnings = {}

    judged = None
    if decide:
        # each kind of model estimates creep its own way; the structure chosen on the
        # record with one kind's estimate removed is judged against the other's
        def judged_structure(model, families=None):
            second = structure_without_creep(model, families)
            start = second.model.metadata.get("fit", {}).get("settled", {}).get("sample", 0)
            judged = _judge(first, second, ua, ya, ta, dta, tau, start, rows,
                            rec.layout.indices("held_back"), qp, fixed_n)
            step.done(f"creep estimated with "
                      f"{model.metadata.get('fit', {}).get('family', model.family)}: "
                      f"{judged['family_with']} holds back {judged['held_back_rms_with']:.4g}")
            return second, start, judged

        second, start, judged = judged_structure(start_model)
        other = _other_kind(first, start_model)
        if other is not None:
            model, families, rms_without = other
            name = model.metadata["fit"]["family"]
            if rms_without <= CREEP_REACH * judged["held_back_rms_with"]:
                alternative = judged_structure(model, families)
                tried = [dict(family=judged["family_without"], **_with_creep(judged)),
                         dict(family=name, **_with_creep(alternative[2]))]
                if alternative[2]["held_back_rms_with"] < judged["held_back_rms_with"]:
                    second, start, judged = alternative
                judged["creep_estimated_with"] = tried
            else:
                judged["other_kind_not_tried"] = (
                    f"{name}: its held-back RMS without creep, {rms_without:.4g}, is more "
                    f"than {CREEP_REACH:g} times {judged['held_back_rms_with']:.4g}, what "
                    f"{judged['family_with']} reaches with creep")
        if not judged["kept"]:
            # from the state the record started from as fitted (a Bouc-Wen z away from
            # rest): its hysteresis forgetting that start is no creep decay
            plain = first.model.replace(delay=0).predict(
                ua, initial_state=first.model.metadata.get("fit", {}).get("record_start"))
            judged["record_start"] = record_start_check(ya[start:] - plain[start:], ta[start:],
                                                        tau, duration, np.ptp(ya[start:]))
            return _without_creep(first, judged)
    else:
        second = structure_without_creep(start_model)
        start = second.model.metadata.get("fit", {}).get("settled", {}).get("sample", 0)
    for w in trial_warnings.get(id(second), ()):
        # the structure kept: what its fit said about the record is the user's
        warnings.warn(w.message, w.category, stacklevel=3)
    hyst, gains, passes = _joint_qp_of(second.model, fixed_n)(
        second.model.replace(delay=0), ua, ya, dta, tau, start=start,
        free_weights=_free(second.model), **qp)
    aligned = hyst.replace(creep=Creep(tau, gains, dt_fixed))
    model = aligned.replace(delay=d, sample_period=dt_fixed if d else None)
    residual = ya[start:] - aligned.predict(ua, t=t[d:])[start:]
    record_start = record_start_check(residual, ta[start:], tau, duration,
                                      np.ptp(ya[start:]))
    if judged is not None:
        judged["record_start"] = record_start
    meta = dict(second.model.metadata)
    summary = dict(meta.get("fit", {}))
    summary["creep"] = {
        "tau_s": tau.tolist(), "gain": gains.tolist(), "dt_s": dt_fixed,
        "creep_total": float(gains.sum()), "qp_passes": passes,
        "rms_without_creep": _rms(first.model.replace(delay=0), ua, ya, None, start),
        "rms_with_creep": float(np.sqrt(np.mean(residual ** 2))),
        "record_start": record_start,
        "weights": ("shape and linear part (offset, c_1, c_2, a) fitted with the gains"
                    if isinstance(hyst, BoucWenModel) else
                    "free" if _free(second.model) else "one scale (regularized kp shape)"),
        "note": ("family and thresholds chosen on the record with the estimated creep "
                 "removed; weights, offset and creep gains fitted together on every "
                 "sample after the settling sweep"),
        **({} if judged is None else {"decision": judged}),
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
    if judged is not None:
        report = report.with_creep(judged)
    return type(second)(model=model, report=report, models=models)


def _creep_capable(result, chosen_only):
    """The model to estimate creep with: the chosen one if it can carry creep (every
    family of CREEP_FAMILIES, Bouc-Wen included), else (with ``chosen_only`` False) the
    creep-capable family with the lowest judged error; None if none.

    With ``creep="auto"`` only the chosen family is given creep: the family is chosen
    on the record as it is. Otherwise the lags of a PI family absorb what its structure
    lacks (the
    drifting minor loops of a Bouc-Wen actuator, docs/theory/creep.md) and win the
    held-back cycles: measured on a random Bouc-Wen actuator with a triangle record,
    modified-pi with creep erred 1.4 % on ramps and staircases, Bouc-Wen alone 0.8 %."""
    if result.report.chosen in CREEP_FAMILIES or chosen_only:
        name = result.report.chosen
        return result.models[name] if name in CREEP_FAMILIES else None
    fams = [f for f in result.report.families if f["family"] in CREEP_FAMILIES]
    if not fams:
        return None
    best = min(fams, key=lambda f: f["judged_rms"])["family"]
    return _as_start(result, best)


def _other_kind(result, model):
    """(model, families, held-back RMS): the best eligible creep-capable family of
    ``result`` of the other kind than ``model`` (Bouc-Wen against PI operators), the
    eligible families of that kind and its held-back RMS without creep; None if none.

    The creep the joint QP estimates depends on the model it is estimated with, and the
    structure chosen on the record with that creep removed leans to the same kind:
    measured on a random Preisach actuator recorded on a two-cycle triangle
    (benchmarks/bench_population.py, seed 28), creep estimated with Bouc-Wen led to
    Bouc-Wen with creep (held back 0.24 um, 1.0 % of range on ramps and staircases),
    while the PI estimate led to a kp basis that held back 0.09 um (0.2 %)."""
    bw = isinstance(model, BoucWenModel)
    fams = [f for f in result.report.families
            if f["family"] in CREEP_FAMILIES and f.get("excluded") is None
            and isinstance(result.models.get(f["family"]), BoucWenModel) != bw]
    if not fams:
        return None
    best = min(fams, key=lambda f: f["judged_rms"])
    return (_as_start(result, best["family"]), [f["family"] for f in fams],
            float(best["errors"]["held_back"]["rms"]))


def _with_creep(judged):
    return {"family_with": judged["family_with"],
            "held_back_rms_with": judged["held_back_rms_with"]}


def _as_start(result, name):
    """``result``'s model of family ``name``, with the metadata the creep fit reads."""
    return result.models[name].replace(metadata={"fit": {
        "family": name, **({"settled": result.model.metadata["fit"]["settled"]}
                           if "settled" in result.model.metadata.get("fit", {}) else {})}})


def _judge(first, second, u, y, t, dt, tau, start, fit_rows, held_rows, qp, fixed_n=None):
    """Whether creep generalizes: the structure of ``second`` (chosen on the record with
    its creep removed) with weights and creep gains fitted on the fitted cycles only,
    against the ordinary fit, both on the held-back cycles (the choice's RMS, before any
    refit). Creep is kept when it lowers that RMS by more than the choice's tolerance."""
    joint_qp = _joint_qp_of(second.model, fixed_n)
    hyst, gains, _ = joint_qp(second.model.replace(delay=0), u, y, dt, tau, start=start,
                              rows=fit_rows, free_weights=_free(second.model), **qp)
    with_creep = hyst.replace(creep=Creep(tau, gains, float(np.median(dt))))
    r = with_creep.predict(u, t=t)[held_rows] - y[held_rows]
    rms_creep = float(np.sqrt(np.mean(r * r)))
    chosen = first.report.family(first.report.chosen)
    rms_plain = float(chosen["errors"]["held_back"]["rms"])
    kept = rms_creep < (1.0 - TOLERANCE) * rms_plain
    return {"kept": bool(kept), "held_back_rms_without": rms_plain,
            "family_without": first.report.chosen,
            "held_back_rms_with": rms_creep, "family_with": second.report.chosen,
            "creep_total_on_fitted_cycles": float(gains.sum()),
            "reason": (f"held-back RMS {rms_creep:.4g} with creep ({second.report.chosen}) "
                       f"against {rms_plain:.4g} without ({first.report.chosen}): "
                       + ("more than" if kept else "not")
                       + f" {100 * TOLERANCE:g} % lower")}


def _without_creep(result, decision):
    """The ordinary fit, with why creep was not kept in its report and metadata."""
    meta = dict(result.model.metadata)
    meta["fit"] = {**meta.get("fit", {}), "creep": {"decision": decision}}
    return type(result)(model=result.model.replace(metadata=meta),
                        report=result.report.with_creep(decision), models=result.models)


def _with_delay_of(report, chooser):
    """``report`` with the delay entry and the delay's note of the report ``chooser``."""
    data, other = report.to_dict(), chooser.to_dict()
    data["data"]["delay"] = other["data"]["delay"]
    note = "the input-output delay:"
    data["undetermined"] = ([t for t in data["undetermined"] if not t.startswith(note)]
                            + [t for t in other["undetermined"] if t.startswith(note)])
    return type(report)(data)
