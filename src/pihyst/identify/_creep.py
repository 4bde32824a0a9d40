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
from dataclasses import dataclass, field

import numpy as np

from pihyst.exceptions import FitError, PihystWarning
from pihyst.identify._boucwen_creep import fit_shape_and_creep, lag_deficits, tied_deficits
from pihyst.identify._constants import (
    BOUCWEN_CREEP_REACH,
    CREEP_CONVERGED,
    CREEP_ESTIMATE_CONVERGED,
    CREEP_REACH,
    NO_CREEP,
    TOLERANCE,
)
from pihyst.identify._families import CREEP_FAMILIES
from pihyst.identify._qp import solve_qp
from pihyst.identify._record_fit import FIT_SAMPLES, fit_record
from pihyst.identify._record_start import record_start_check
from pihyst.identify._responses import Responses
from pihyst.model._boucwen import BoucWenModel
from pihyst.model._creep import MAX_TOTAL_GAIN, Creep, default_time_constants

__all__ = ["fit_with_creep"]

# rows of operator outputs made at a time: 4,096 x 135 kernels is 4.4 MB, which the
# allocator reuses block after block; above 32 MB every block is fresh memory from the
# system, and first touching it cost 6.6 ms per MB on the development machine
OPERATOR_BLOCK = 1 << 12
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
              duration=np.inf, rows=None, output=None, converged=CREEP_CONVERGED):
    """Weights, offset and creep gains of ``model``'s operators by repeated joint QPs on
    the samples ``rows`` (indices; default every sample from ``start``); ``output``, the
    model's settled output over ``u`` where it is known already.

    ``free_weights=False`` (a regularized kernel basis): the weights keep their shape,
    w = q w_0 with one scale q >= 0, so the joint QP cannot undo the regularization.
    """
    fitted = _fitted_rows(u.size, start, rows)
    hyst = model.replace(creep=None)
    h = hyst.predict(u) if output is None else output
    basis = np.eye(model.n_operators) if free_weights else model.weights[:, None].copy()
    k, n = basis.shape[1], tau.size
    fit_offset = offset is True
    fixed_offset = 0.0 if offset is False else (None if fit_offset else float(offset))
    tie = log_t_basis(n, int(np.count_nonzero(tau <= duration)))
    p = tie.shape[1]
    lower = np.r_[np.zeros(k) if nonnegative else np.full(k, -np.inf),
                  np.full(int(fit_offset), -np.inf), np.zeros(p)]
    # g_i = p_0 + p_1 s_i <= p_0 + p_1: bounding both by G / (2n) keeps sum_i g_i <= G
    upper = np.r_[np.full(k + fit_offset, np.inf), np.full(p, MAX_TOTAL_GAIN / (2 * n))]
    names = ([f"w[{i}]" for i in range(k)] if free_weights else ["weight scale"]) + \
        ["offset"] * fit_offset + ["creep per lag", "creep rise toward slow lags"]
    # the operators' outputs do not depend on the weights: their columns (and their
    # part of the normal equations) are built once, only the lags' change per pass
    fixed = _operator_matrix(hyst, u, fitted, basis, free_weights, ones=fit_offset)
    target = y[fitted] - (fixed_offset or 0.0)
    fixed_gram, fixed_rhs = fixed.T @ fixed, fixed.T @ target
    span = max(float(np.ptp(y[fitted])), 1e-300)
    gains, passes = np.zeros(n), 0
    previous = _current(hyst, basis, free_weights, fit_offset, fixed_offset)
    while passes < MAX_PASSES:
        passes += 1
        q = -tied_deficits(h, hyst.hysteresis_output(hyst.initial_state), dt, tau, tie,
                           fitted)
        cross = fixed.T @ q
        gram = np.block([[fixed_gram, cross], [cross.T, q.T @ q]])
        rhs = np.r_[fixed_rhs, q.T @ target]
        sol = solve_qp(gram, rhs, lower=lower, upper=upper, warn=False, names=names).x
        w = basis @ sol[:k]
        c = sol[k] if fit_offset else fixed_offset
        gains = np.clip(tie @ sol[k + fit_offset:], 0.0, None)
        # H changes by the operator columns times the change of their coefficients (and
        # a fixed offset's change): on the fitted rows that is exact, without running
        # the model over the record
        change = float(np.max(np.abs(fixed @ (sol[:k + fit_offset] - previous)),
                              initial=0.0)) + (0.0 if fit_offset else abs(c - hyst.offset))
        previous = sol[:k + fit_offset]
        hyst = hyst.replace(weights=w, offset=c)
        if change <= converged * span:
            break
        h = hyst.predict(u)
    return hyst, gains, passes


def _current(hyst, basis, free_weights, fit_offset, fixed_offset):
    """The coefficients of ``hyst``'s operator columns (its weights, or its scale 1 of
    the basis) and of the offset column, as the joint QP's solution orders them."""
    weights = hyst.weights if free_weights else np.ones(basis.shape[1])
    return np.r_[weights, [hyst.offset] if fit_offset else []]


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
    fitted = _fitted_rows(u.size, start, rows)
    tie = log_t_basis(tau.size, int(np.count_nonzero(tau <= duration)))
    hyst, gains, passes, _ = fit_shape_and_creep(model.replace(creep=None), u, y, dt, tau,
                                                 tie, fitted, fixed_n=fixed_n)
    return hyst, gains, passes


def _operator_matrix(hyst, u, fitted, basis, free_weights, ones=False):
    """The operators' outputs (times ``basis`` unless ``free_weights``) at the fitted
    rows, then a column of ones with ``ones`` (the offset's), written block by block
    into one array (a 60,000 x 135 matrix is 65 MB: made once, not copied). The
    operators run on every sample, or for a record longer than ``FIT_SAMPLES`` (whose
    fitted rows are thinned) on the fitted rows and every input extremum only (their
    outputs there are exactly the whole record's: identify/_record_fit.py)."""
    rows = np.flatnonzero(fitted)
    if u.size > FIT_SAMPLES:
        dv = np.diff(u)
        turns = np.flatnonzero(dv[1:] * dv[:-1] <= 0) + 1
        run = np.unique(np.r_[0, rows, turns, u.size - 1])
    else:
        run = np.arange(u.size)
    wanted = fitted[run]
    k = hyst.n_operators if free_weights else basis.shape[1]
    out = np.empty((rows.size, k + bool(ones)))
    if ones:
        out[:, k] = 1.0
    state, done = hyst.initial_state, 0
    for a in range(0, run.size, OPERATOR_BLOCK):
        b = min(a + OPERATOR_BLOCK, run.size)
        phi = hyst.operators(u[run[a:b]], initial_state=state)
        state = phi[-1]
        block = phi[wanted[a:b]]
        out[done:done + block.shape[0], :k] = block if free_weights else block @ basis
        done += block.shape[0]
    return out


def _fitted_rows(n, start, rows):
    """The mask of the samples a joint QP sums over: ``rows`` (default every sample from
    ``start``), every k-th of them when they are more than ``FIT_SAMPLES`` (the lags
    still run over every sample; only fewer squares are summed, as the structure of a
    long record is fitted on a subsample, identify/_record_fit.py)."""
    fitted = np.zeros(n, dtype=bool)
    if rows is None:
        fitted[start:] = True
    else:
        fitted[rows] = True
    count = int(np.count_nonzero(fitted))
    if count > FIT_SAMPLES:
        idx = np.flatnonzero(fitted)
        fitted[:] = False
        fitted[idx[::int(np.ceil(count / FIT_SAMPLES))]] = True
    return fitted


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


def _rms(model, u, y, t, start):
    y_hat = model.predict(u) if t is None else model.predict(u, t=t)
    return float(np.sqrt(np.mean((y_hat[start:] - y[start:]) ** 2)))


@dataclass(frozen=True)
class CreepStart:
    """A model to estimate creep with: the model, its fitting family's name and the end
    of the settling sweep of the record it was fitted on."""

    model: object
    family: str
    settled_sample: int

    @property
    def free_weights(self):
        """Whether the joint QP may move every weight: not for the regularized kernel
        basis (family kp), whose weights it would overfit without the regularization."""
        return self.family != "kp"


@dataclass(frozen=True)
class CreepEstimate:
    """What a joint QP of weights (Bouc-Wen: shape and linear part) and creep gains
    found: the model without creep, the gains of the lags, and the family it was
    estimated with."""

    model: object
    gains: np.ndarray
    family: str


@dataclass(frozen=True)
class _Aligned:
    """The record with its output ``d`` samples later (u[k] -> y[k + d]), its sample
    intervals and times at the output, the creep time constants and the QP options;
    ``outputs`` keeps the settled output of each structure the QPs start from (the
    judgement's and the final fit's are the same structure's)."""

    u: np.ndarray
    y: np.ndarray
    dt: np.ndarray
    t: np.ndarray
    tau: np.ndarray
    qp: dict
    fixed_n: object
    outputs: dict = field(default_factory=dict, compare=False)

    def settled_output(self, structure):
        """H of ``structure`` (a RecordFit)'s PI model, no delay and no creep, over
        ``u``: computed once per structure (None for Bouc-Wen, whose joint fit
        searches its shape and computes its own)."""
        if isinstance(structure.result.model, BoucWenModel):
            return None
        key = id(structure)
        if key not in self.outputs:
            model = structure.result.model.replace(delay=0, creep=None)
            self.outputs[key] = (structure, model.predict(self.u))
        return self.outputs[key][1]


def fit_with_creep(u, y, t, options, steps):
    """The fit with creep (``options.creep`` "auto" or "always"): the structure from the
    ordinary fit of the record with its creep removed, then weights and creep gains in
    one QP (module notes). "auto": creep is kept only if it lowers the held-back RMS of
    the fit by more than the choice's tolerance (:func:`_judge`); otherwise the
    ordinary fit is returned, with the comparison in its report and metadata."""
    u = np.asarray(u, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    decide = options.creep == "auto"
    plain = options.but(creep="off")
    responses = Responses()          # the same input is fitted up to three times
    if options.through is not None:
        if decide:
            return _without_creep(fit_record(u, y, plain, steps, t=t).result, {
                "kept": False, "reason": "through= (equality constraints) is not available "
                                         "with creep"})
        raise FitError("through= (equality constraints) is not available with creep=True")
    first = fit_record(u, y, plain, steps, t=t, responses=responses)  # its errors first
    steps.done(f"fit without creep: {first.result.report.chosen}")
    dt_fixed, dt, duration = _times(t, u.size)
    tau = (default_time_constants(dt_fixed, duration) if options.time_constants is None
           else np.asarray(options.time_constants, dtype=np.float64))
    t = np.asarray(t, dtype=np.float64)
    d = first.delay.samples
    rec = _aligned(u, y, dt, t, d, tau, options, duration)
    start = _creep_capable(first, options.explicit_family or decide)
    rows = held = None
    if decide:
        framed = plain.frame(rec.u, rec.y)    # through= is None here
        if not framed.has_held_back:
            return _without_creep(first.result, {
                "kept": False, "reason": "nothing held back to judge it on (creep=True "
                                         "fits it regardless)"})
        if start is None:
            return _without_creep(first.result, {
                "kept": False, "reason": f"the chosen family, {first.result.report.chosen}, "
                                         f"cannot carry creep"})
        rows, held = framed.layout.indices("fit"), framed.layout.indices("held_back")
    elif start is None:
        raise FitError(f"a {first.result.report.chosen} model has no creep: fit creep with "
                       f"one of {', '.join(CREEP_FAMILIES)}")
    trial = _Trial(u, y, t, d, rec, plain, first, rows, held, decide, steps, responses)
    if not decide:
        second = trial.structure(start)
        return _with_creep_fit(first, second, rec, t, d, dt_fixed, duration, None)
    second, judged = trial.judged(start)
    second, judged = _other_kind_tried(trial, first, start, second, judged)
    if not judged["kept"]:
        return _not_kept(first, rec, judged, duration)
    trial.keep_warnings(second)
    return _with_creep_fit(first, second, rec, t, d, dt_fixed, duration, judged)


def _aligned(u, y, dt, t, d, tau, options, duration):
    """The record aligned by the delay the first fit chose (or was given): the creep
    QPs run on u[k] -> y[k + d], its lags at the output's times."""
    fixed_n = _fixed_exponent(options.families if options.explicit_family else None)
    return _Aligned(u=u[:u.size - d], y=y[d:], dt=np.r_[dt[0], dt[d + 1:]], t=t[d:],
                    tau=tau, fixed_n=fixed_n,
                    qp=dict(offset=options.offset, nonnegative=options.nonnegative,
                            duration=duration))


class _Trial:
    """The ordinary fit of the record with one creep estimate removed, and its
    judgement on the held-back cycles (``decide``)."""

    def __init__(self, u, y, t, d, rec, plain, first, rows, held, decide, steps, responses):
        self.u, self.y, self.t, self.d, self.rec = u, y, t, d, rec
        self.responses = responses
        self.plain, self.first, self.rows, self.held = plain, first, rows, held
        self.decide, self.steps = decide, steps
        self.warnings = {}

    def estimate(self, start):
        """:class:`CreepEstimate` of the creep ``start``'s joint QP finds on the fitted
        rows (``rows``; every sample from the settling sweep without a judgement). Every
        weight is free in that QP (a kp basis may overfit there; only the creep estimate
        is kept, the structure and weights are fitted again, so it converges to
        ``CREEP_ESTIMATE_CONVERGED``)."""
        rec = self.rec
        model = start.model.replace(creep=None, delay=0)
        hyst, gains, _ = _joint_qp_of(model, rec.fixed_n)(
            model, rec.u, rec.y, rec.dt, rec.tau, start=start.settled_sample,
            rows=self.rows, converged=CREEP_ESTIMATE_CONVERGED, **rec.qp)
        return CreepEstimate(hyst, gains, start.family)

    def structure(self, start, families=None, estimate=None):
        """:class:`RecordFit` of the record with the creep ``start``'s joint QP
        estimates (``estimate``, default: :meth:`estimate`) removed (the settled
        displacement the structure is chosen on), among ``families`` (default: every
        creep-capable family the fit was given)."""
        rec = self.rec
        estimate = self.estimate(start) if estimate is None else estimate
        hyst, gains = estimate.model, estimate.gains
        psi = _lag_deficits(hyst, hyst.predict(rec.u), rec.dt, rec.tau, hyst.initial_state)
        names = families if families is not None else (
            self.plain.families if self.plain.explicit_family else CREEP_FAMILIES)
        if self._unchanged(psi @ gains, names):
            return self.first
        # the families the user named are still theirs (a failure is an error); the
        # default ones are skipped with the reason where they cannot be fitted, as in the
        # fit without creep (with thresholds= or n_operators=, kp and Bouc-Wen)
        options = self.plain.but(families=names)
        y = np.r_[self.y[:self.d], rec.y + psi @ gains]
        if not self.decide:
            return fit_record(self.u, y, options, self.steps, t=self.t,
                              delay=self.first.delay.given(), responses=self.responses)
        # a trial: its warnings are about the record with this creep estimate removed,
        # and are the user's only if that structure is kept (keep_warnings)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", PihystWarning)
            second = fit_record(self.u, y, options, self.steps, t=self.t,
                                delay=self.first.delay.given(), responses=self.responses)
        self.warnings[id(second)] = [w for w in caught
                                     if issubclass(w.category, PihystWarning)]
        for w in caught:
            if not issubclass(w.category, PihystWarning):
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        return second

    def _unchanged(self, shift, names):
        """Whether removing the creep estimate (``shift``, the displacement it adds)
        leaves the record as the first fit saw it, among the same families: then the
        structure is the first fit's, not fitted twice."""
        span = float(np.ptp(self.rec.y))
        fitted = {f["family"] for f in self.first.result.report.families}
        return (float(np.max(np.abs(shift), initial=0.0)) <= NO_CREEP * span
                and fitted <= {getattr(name, "name", name) for name in names})

    def judged(self, start, families=None):
        """(RecordFit, judgement) of the structure chosen with ``start``'s estimate.

        A Bouc-Wen structure chosen again is judged with the estimate itself: that joint
        fit of shape, linear part and creep gains on the fitted rows is the one the
        judgement needs, and a second shape search from another start would fit the same
        thing twice (0.35 s of the 2 s fit of P-885)."""
        estimate = self.estimate(start)
        second = self.structure(start, families, estimate)
        fitted = (estimate if isinstance(estimate.model, BoucWenModel)
                  and second.result.report.chosen == start.family else None)
        judged = _judge(self.first.result, second, self.rec, self.rows, self.held, fitted)
        self.steps.done(f"creep estimated with {start.family}: {judged['family_with']} "
                        f"holds back {judged['held_back_rms_with']:.4g}")
        return second, judged

    def keep_warnings(self, second):
        """The warnings of the structure kept: what its fit said about the record is the
        user's."""
        for w in self.warnings.get(id(second), ()):
            warnings.warn(w.message, w.category, stacklevel=4)


def _other_kind_tried(trial, first, start, second, judged):
    """Each kind of model estimates creep its own way; the structure chosen on the
    record with one kind's estimate removed is judged against the other's: (second,
    judged) of the better, with both in the judgement."""
    other = _other_kind(first, start.model)
    if other is None:
        return second, judged
    start_other, families, rms_without = other
    reach = (BOUCWEN_CREEP_REACH if isinstance(start_other.model, BoucWenModel)
             else CREEP_REACH)
    if rms_without > reach * judged["held_back_rms_with"]:
        judged["other_kind_not_tried"] = (
            f"{start_other.family}: its held-back RMS without creep, {rms_without:.4g}, is "
            f"more than {reach:g} times {judged['held_back_rms_with']:.4g}, what "
            f"{judged['family_with']} reaches with creep")
        return second, judged
    try:
        second_other, judged_other = trial.judged(start_other, families)
    except FitError as err:
        judged["other_kind_not_tried"] = f"{start_other.family}: {err}"
        return second, judged
    tried = [dict(family=judged["family_without"], **_with_creep(judged)),
             dict(family=start_other.family, **_with_creep(judged_other))]
    if judged_other["held_back_rms_with"] < judged["held_back_rms_with"]:
        second, judged = second_other, judged_other
    judged["creep_estimated_with"] = tried
    return second, judged


def _not_kept(first, rec, judged, duration):
    """The ordinary fit, with the judgement and whether the record started at rest:
    from the state the record started from as fitted (a Bouc-Wen z away from rest),
    its hysteresis forgetting that start is no creep decay."""
    start = first.settled_sample
    plain = first.result.model.replace(delay=0).predict(rec.u, initial_state=first.record_start)
    judged["record_start"] = record_start_check(rec.y[start:] - plain[start:], rec.t[start:],
                                                rec.tau, duration, np.ptp(rec.y[start:]))
    return _without_creep(first.result, judged)


def _with_creep_fit(first, second, rec, t, d, dt_fixed, duration, judged):
    """The structure ``second`` (a RecordFit) with its weights and creep gains fitted
    together on every sample after the settling sweep, its report and metadata."""
    start = second.settled_sample
    chosen = second.result.model
    hyst, gains, passes = _joint_qp_of(chosen, rec.fixed_n)(
        chosen.replace(delay=0), rec.u, rec.y, rec.dt, rec.tau, start=start,
        free_weights=second.result.report.chosen != "kp",
        output=rec.settled_output(second), **rec.qp)
    aligned = hyst.replace(creep=Creep(rec.tau, gains, dt_fixed))
    model = aligned.replace(delay=d, sample_period=dt_fixed if d else None)
    residual = rec.y[start:] - aligned.predict(rec.u, t=t[d:])[start:]
    record_start = record_start_check(residual, rec.t[start:], rec.tau, duration,
                                      np.ptp(rec.y[start:]))
    if judged is not None:
        judged["record_start"] = record_start
    meta = dict(chosen.metadata)
    summary = dict(meta.get("fit", {}))
    summary["creep"] = {
        "tau_s": rec.tau.tolist(), "gain": gains.tolist(), "dt_s": dt_fixed,
        "creep_total": float(gains.sum()), "qp_passes": passes,
        "rms_without_creep": _rms(first.result.model.replace(delay=0), rec.u, rec.y, None,
                                  start),
        "rms_with_creep": float(np.sqrt(np.mean(residual ** 2))),
        "record_start": record_start,
        "weights": ("shape and linear part (offset, c_1, c_2, a) fitted with the gains"
                    if isinstance(hyst, BoucWenModel) else
                    "free" if second.result.report.chosen != "kp" else
                    "one scale (regularized kp shape)"),
        "note": ("family and thresholds chosen on the record with the estimated creep "
                 "removed; weights, offset and creep gains fitted together on every "
                 "sample after the settling sweep"),
        **({} if judged is None else {"decision": judged}),
    }
    meta["fit"] = summary
    model = model.replace(metadata=meta)
    models = dict(second.result.models)
    models[summary.get("family", model.family)] = model
    report = second.result.report
    if judged is not None:
        report = report.with_creep(judged)
    return type(second.result)(model=model, report=report, models=models)


def _creep_capable(first, chosen_only):
    """The :class:`CreepStart` to estimate creep with: the chosen model if it can carry
    creep (every family of CREEP_FAMILIES, Bouc-Wen included), else (with
    ``chosen_only`` False) the creep-capable family with the lowest judged error; None
    if none.

    With ``creep="auto"`` only the chosen family is given creep: the family is chosen
    on the record as it is. Otherwise the lags of a PI family absorb what its structure
    lacks (the drifting minor loops of a Bouc-Wen actuator, docs/theory/creep.md) and
    win the held-back cycles: measured on a random Bouc-Wen actuator with a triangle
    record, modified-pi with creep erred 1.4 % on ramps and staircases, Bouc-Wen alone
    0.8 %."""
    result = first.result
    name = result.report.chosen
    if name in CREEP_FAMILIES or chosen_only:
        return (CreepStart(result.models[name], name, first.settled_sample)
                if name in CREEP_FAMILIES else None)
    fams = [f for f in result.report.families if f["family"] in CREEP_FAMILIES]
    if not fams:
        return None
    best = min(fams, key=lambda f: f["judged_rms"])["family"]
    return CreepStart(result.models[best], best, first.settled_sample)


def _other_kind(first, model):
    """(CreepStart, families, held-back RMS): the best eligible creep-capable family of
    the fit ``first`` of the other kind than ``model`` (Bouc-Wen against PI operators),
    the eligible families of that kind and its held-back RMS without creep; None if
    none.

    The creep the joint QP estimates depends on the model it is estimated with, and the
    structure chosen on the record with that creep removed leans to the same kind:
    measured on a random Preisach actuator recorded on a two-cycle triangle
    (benchmarks/bench_population.py, seed 28), creep estimated with Bouc-Wen led to
    Bouc-Wen with creep (held back 0.24 um, 1.0 % of range on ramps and staircases),
    while the PI estimate led to a kp basis that held back 0.09 um (0.2 %)."""
    result = first.result
    bw = isinstance(model, BoucWenModel)
    fams = [f for f in result.report.families
            if f["family"] in CREEP_FAMILIES and f.get("excluded") is None
            and isinstance(result.models.get(f["family"]), BoucWenModel) != bw]
    if not fams:
        return None
    best = min(fams, key=lambda f: f["judged_rms"])
    return (CreepStart(result.models[best["family"]], best["family"], first.settled_sample),
            [f["family"] for f in fams], float(best["errors"]["held_back"]["rms"]))


def _with_creep(judged):
    return {"family_with": judged["family_with"],
            "held_back_rms_with": judged["held_back_rms_with"]}


def _judge(first, second, rec, fit_rows, held_rows, fitted=None):
    """Whether creep generalizes: the structure of ``second`` (a RecordFit, chosen on
    the record with its creep removed) with weights and creep gains fitted on the
    fitted cycles only (``fitted``, a :class:`CreepEstimate` of that structure on those
    rows, when there is one), against the ordinary fit ``first`` (a FitResult), both on
    the held-back cycles (the choice's RMS, before any refit). Creep is kept when it
    lowers that RMS by more than the choice's tolerance."""
    chosen = second.result.model
    if fitted is None:
        hyst, gains, _ = _joint_qp_of(chosen, rec.fixed_n)(
            chosen.replace(delay=0), rec.u, rec.y, rec.dt, rec.tau,
            start=second.settled_sample, rows=fit_rows,
            free_weights=second.result.report.chosen != "kp",
            output=rec.settled_output(second), **rec.qp)
    else:
        hyst, gains = fitted.model, fitted.gains
    with_creep = hyst.replace(creep=Creep(rec.tau, gains, float(np.median(rec.dt))))
    r = with_creep.predict(rec.u, t=rec.t)[held_rows] - rec.y[held_rows]
    rms_creep = float(np.sqrt(np.mean(r * r)))
    rms_plain = float(first.report.family(first.report.chosen)["errors"]["held_back"]["rms"])
    kept = rms_creep < (1.0 - TOLERANCE) * rms_plain
    name_with = second.result.report.chosen
    return {"kept": bool(kept), "held_back_rms_without": rms_plain,
            "family_without": first.report.chosen,
            "held_back_rms_with": rms_creep, "family_with": name_with,
            "creep_total_on_fitted_cycles": float(gains.sum()),
            "reason": (f"held-back RMS {rms_creep:.4g} with creep ({name_with}) "
                       f"against {rms_plain:.4g} without ({first.report.chosen}): "
                       + ("more than" if kept else "not")
                       + f" {100 * TOLERANCE:g} % lower")}


def _without_creep(result, decision):
    """The ordinary fit, with why creep was not kept in its report and metadata."""
    meta = dict(result.model.metadata)
    meta["fit"] = {**meta.get("fit", {}), "creep": {"decision": decision}}
    return type(result)(model=result.model.replace(metadata=meta),
                        report=result.report.with_creep(decision), models=result.models)
