"""Identification: fit PI-type models to a measured voltage/displacement record.

``fit(u, y)`` does what the paper (Xu et al. 2020) did by hand, from the data:

1. cuts the record into cycles (:mod:`pihyst.identify._cycles`): the first full sweep settles the
   operator states when the record does not start at rest, every other cycle is held
   back to judge the fit;
2. for each family (:mod:`pihyst.identify._families`) runs all candidate operators over the record
   once, accumulating the normal equations of the fitted and of the held-back samples
   (:mod:`pihyst.identify._gram`);
3. fits the weights by constrained least squares, a QP on the Gram matrix
   (:mod:`pihyst.identify._qp`): w >= 0 (the model stays monotone, hence invertible), optional
   bounds and equality constraints (through measured points), a fitted offset;
4. chooses the thresholds as the subset of the candidates with the lowest held-back
   error (:mod:`pihyst.identify._subsets`), identifies the multislope shape (a, b, h) with an
   outer Nelder-Mead search, regularizes the Krasnosel'skii-Pokrovskii basis;
5. judges every family on each kind of held-back data (:mod:`pihyst.identify._assess`:
   held-back major and minor cycles, a validation record), measures its compensator's
   latency (:mod:`pihyst.identify._latency`), and returns the smallest, fastest family
   within 2 % of the best judged error (:mod:`pihyst.identify._choice`), its weights
   refitted on all the cycles, with a report (:mod:`pihyst.identify._report`) of every
   family and of what the data could not determine.
"""

import contextvars
import functools
import warnings
from dataclasses import replace

import numpy as np

from pihyst._arguments import check_fit_sizes, real_array
from pihyst._version import __version__
from pihyst.exceptions import FitError, PihystWarning
from pihyst.identify import _delay
from pihyst.identify._assess import (
    ValidationRecord,
    errors_by_kind,
    judged_rms,
    minor_loops_determined,
)
from pihyst.identify._choice import Candidate, choose
from pihyst.identify._families import FAMILY_NAMES, as_family
from pihyst.identify._family_fit import INITIAL_STATES, FamilyFitter, FramedRecord, cycled_state
from pihyst.identify._latency import estimate_latency
from pihyst.identify._progress import Steps
from pihyst.identify._report import FitReport, FitResult
from pihyst.identify._start_state import start_state
from pihyst.identify._subsets import DEFAULT_MAX_EXHAUSTIVE
from pihyst.identify._sufficiency import check_fit, check_record
from pihyst.model._delay import MAX_DELAY_SAMPLES

__all__ = ["fit", "FAMILY_NAMES", "INITIAL_STATES", "cycled_state"]

DEFAULT_N_CANDIDATES = 16
DELAY_NOTE_GAIN = 0.02   # a delay is worth a note when it lowers the probe's RMS by 2 %


# the delay "auto" adopted and the family chosen then did not hold back better with
# (:func:`_delay_refused`): the report of the fit made again without it says so
_REFUSED_DELAY = contextvars.ContextVar("pihyst_refused_delay", default=None)


def _one_blas_thread(function):
    """Runs ``function`` with BLAS on one thread: the fit's matrices are small (tens to a
    few hundred columns), where a second thread only waits (on a loaded 2-core machine
    an SVD of 300 x 150 took 15 times longer with two), and the sums then run in one
    order, so the same record gives the same model bit for bit whatever the core count."""
    @functools.wraps(function)
    def wrapped(*args, **kwargs):
        import scipy.linalg  # noqa: F401  SciPy's own BLAS: limited only once loaded
        from threadpoolctl import threadpool_limits

        with threadpool_limits(1, user_api="blas"):
            return function(*args, **kwargs)
    return wrapped


@_one_blas_thread
def fit(u, y, *, family=None, thresholds=None, n_operators=None, candidates=None,
        n_candidates=DEFAULT_N_CANDIDATES, offset=True, nonnegative=True, bounds=None,
        through=None, initial_state="auto", holdout="alternate", refit=True,
        input_range=None, validate=None, delay="auto", max_operators=None, max_latency=None,
        max_exhaustive=DEFAULT_MAX_EXHAUSTIVE, t=None, creep="auto", progress=None):
    """Fit PI-type hysteresis models to a measured record and keep the smallest, fastest
    one of those that generalize best.

    Parameters
    ----------
    u, y : array_like
        Input (e.g. voltage) and measured output (e.g. displacement), same length.
    family : str, family object, or a list of them, optional
        The fitting families (:mod:`pihyst.identify`): ``"classical"``
        (:class:`~pihyst.identify.Classical`), ``"multislope"``
        (:class:`~pihyst.identify.Multislope`: the paper's shape a = 0.8, b = 1.2,
        h = 0.5 on the data's range, or ``Multislope(shape={...})``),
        ``"multislope-identified"`` (:class:`~pihyst.identify.MultislopeIdentified`: shape
        fitted to the data), ``"modified-pi"`` (:class:`~pihyst.identify.ModifiedPI`:
        classical + monotone input function of ``segments`` pieces), ``"kp"``
        (:class:`~pihyst.identify.KrasnoselskiiPokrovskii`: a ``grid`` of kernels). A
        name stands for the family with its default options. ``"bouc-wen"``
        (:class:`~pihyst.identify.BoucWen`) is not a PI family: a
        :class:`~pihyst.model.BoucWenModel` (docs/theory/bouc-wen.md).
        Default: every family (``FAMILY_NAMES``: the PI families and Bouc-Wen),
        judged on held-back data (and ``validate``); of those within 2 % of the lowest
        judged RMS, a piecewise-linear compensator (PI) before an iterative one
        (Bouc-Wen), then the fewest operators, then the lowest judged error, is returned.
        When the data do not determine the minor loops (no reversals inside the range),
        families whose structure or regularization fixes them plausibly (classical,
        modified-pi, kp, Bouc-Wen; not multislope) are preferred.
    thresholds : array_like, optional
        Use exactly these thresholds (input units, measured from the bottom of the input
        range) instead of choosing them (families with thresholds only).
    n_operators : int, optional
        Number of operators to choose from the candidates. Default: chosen from the data
        (the smallest number within 1 % of the lowest held-back RMS).
    candidates : array_like, optional
        Candidate thresholds; default ``n_candidates`` equally spaced ones over the
        family's useful range ([0, S/2) classical, [0, (1-a)U/(1-ah)] multislope).
    n_candidates : int
        Size of the default candidate grid (16, as in the paper).
    offset : bool or float
        True: fit a constant offset (the sensor's zero is arbitrary); a number: fixed.
    nonnegative : bool
        Constrain the weights to w >= 0 (monotone, invertible model).
    bounds : (lower, upper), optional
        Bounds on the weights (scalars, or per operator with explicit thresholds).
    through : "top" or list of int, optional
        Sample indices the model must pass through exactly ("top": the sample at the
        highest input).
    initial_state : "auto", "cycled", "settle", "zero", "rise", "fall" or array_like
        Operator state before the first sample. "cycled": at rest at the bottom of the
        range after a full bottom -> top -> bottom cycle (records made as in
        docs/interfaces.md); "settle": unknown, the first full sweep of the input range settles the
        operators and is not fitted; "rise" / "fall": at rest at the first input after
        a rise from the bottom / a fall from the top; "auto": at the bottom of the
        range "cycled" or "zero", whichever the record shows, else "settle", or (when
        the first full sweep comes after more than half the record) "rise", "fall" or
        "zero", whichever the record shows. An array (needs ``thresholds``) is used as
        given.
    holdout : "alternate", float or None
        Held-back cycles: every other cycle (major and minor separately), the last
        fraction of the record, or none (choices then judged on the fitted data).
    refit : bool
        Refit the chosen model's weights on all cycles (fitted and held-back) after the
        choice. The report's held-back errors are those of the fit before the refit.
    input_range : (min, max), optional
        Input range of the model; default the data's span.
    validate : (u2, y2), optional
        A second record (another trajectory), judged but not fitted: every family's
        error on it is reported, and counts in the choice (the worse of it and the
        held-back cycles). Its mean error is removed (the sensor's zero differs between
        records); it is judged once its input has swept its own range.
    delay : int or "auto"
        Samples by which the output lags the input (a dead time): the models are fitted
        to u[k] -> y[k + delay] and carry it (``model.delay``: ``model.predict(u)`` is
        the delayed output, ``pihyst.compensate`` previews the trajectory). "auto"
        (default): the delay with the lowest held-back RMS of a probe model, 0 to 5 % of
        a cycle, adopted only when it lowers the held-back RMS of that probe and of the
        fitted structure by more than 5 % (docs/theory/identification.md), else 0. The
        report states the delay used and why; with 0 it still says which delay the
        record favours.
    max_operators : int, optional
        Choose only among models with at most this many operators.
    max_latency : float, optional
        Choose only among models whose compensator's worst-case time per sample
        (estimated from the model's structure by a calibrated cost model, never timed:
        the same record gives the same model on every run; see the report) is at most
        this many seconds.
    max_exhaustive : int
        Largest number of subsets of the requested size searched exhaustively (the
        automatic size search uses at most 600 per size, then greedy selection + swaps).
    t : array_like, optional
        Sample times (s). With them the default fit also tries creep (``creep="auto"``).
    creep : "auto", bool or array_like
        Fit creep (docs/theory/creep.md): first-order lags of the hysteresis output
        with half-decade time constants (or these time constants, s), their gains fitted
        with the weights in one QP. The model then carries ``model.creep``. ``True``
        (or time constants): always. ``"auto"`` (default): when ``t`` is given, creep is
        fitted on the fitted cycles and kept only if it lowers the held-back RMS by more
        than 2 % (the report's ``creep`` entry says which and why); without ``t``, none.
        ``False``: none.
    progress : callable, optional
        Called with one line of text as each step ends (the step and its time in
        seconds): the command line prints them on a terminal.

    Returns
    -------
    FitResult
        ``.model`` (the fitted model, with the fit recorded in ``model.metadata["fit"]``),
        ``.report`` (a :class:`FitReport`: errors per kind of held-back data, compensator
        latency and operator count per family, threshold choice and its reasons, what
        the data could not determine; ``print(report)`` or ``report.to_json()``) and
        ``.models`` (every family's fitted model by name).

    Raises
    ------
    FitError
        Too few samples, constant input, NaN, a threshold the input never reaches,
        infeasible constraints (:class:`~pihyst.exceptions.InfeasibleConstraintsError`),
        an unknown family.

    Warns
    -----
    IllConditionedWarning
        When the chosen model's weights are not all determined by the data.

    Examples
    --------
    Recover a classical PI from data it generated:

    >>> import numpy as np
    >>> import pihyst
    >>> true = pihyst.ClassicalPI([0, 15, 30], [0.3, 0.2, 0.1])
    >>> u = np.r_[np.linspace(0, 150, 151), np.linspace(150, 0, 151)[1:],
    ...           np.linspace(0, 100, 101)[1:], np.linspace(100, 40, 61)[1:],
    ...           np.linspace(40, 150, 111)[1:], np.linspace(150, 0, 151)[1:]]
    >>> res = pihyst.fit(u, true.predict(u), family="classical", thresholds=[0, 15, 30],
    ...                  initial_state="zero", offset=False)
    >>> [round(float(w), 6) for w in res.model.weights]
    [0.3, 0.2, 0.1]

    A family with its own options:

    >>> res = pihyst.fit(u, true.predict(u), family=pihyst.identify.ModifiedPI(segments=2),
    ...                  n_operators=2)
    >>> res.report.chosen, res.model.family
    ('modified-pi', 'pwl')
    """
    # no new local names here: locals() below passes the arguments on
    real_array(u, "u"), real_array(y, "y"), real_array(t, "t")
    check_fit_sizes(n_candidates=n_candidates, n_operators=n_operators,
                    thresholds=thresholds, candidates=candidates)
    if isinstance(creep, str) and creep != "auto":
        raise FitError(f"creep must be 'auto', True, False or time constants (s), got "
                       f"{creep!r}")
    decide = isinstance(creep, str)
    if decide and t is None:
        creep = False            # no sample times: nothing to fit creep on
    if creep is not False and creep is not None:
        from pihyst.identify._creep import fit_with_creep
        kw = {k: v for k, v in locals().items()
              if k not in ("u", "y", "t", "creep", "decide", "fit_with_creep")}
        return fit_with_creep(fit, u, y, t, decide=decide,
                              time_constants=None if creep is True or decide else creep,
                              **kw)
    explicit_family = family is not None
    specs = FAMILY_NAMES if family is None else (
        [family] if isinstance(family, str) or not _is_sequence(family) else list(family))
    families = [as_family(f) for f in specs]
    if len({f.name for f in families}) < len(families):
        raise FitError("each family may be given once (their results are reported by name)")
    if thresholds is not None and candidates is not None:
        raise FitError("give thresholds (used as they are) or candidates (chosen from), "
                       "not both")
    if n_operators is not None and thresholds is not None:
        raise FitError("give thresholds or n_operators (how many to choose), not both")
    if n_operators is not None and (int(n_operators) != n_operators or n_operators < 1):
        raise FitError(f"n_operators must be a positive integer, got {n_operators}")
    _check_bounds(max_operators, max_latency, delay)
    _check_weight_bounds(bounds)

    def fitter_of(r):
        return FamilyFitter(r, thresholds=thresholds, candidates=candidates,
                            n_candidates=n_candidates, n_operators=n_operators,
                            nonnegative=nonnegative, bounds=bounds,
                            max_exhaustive=max_exhaustive)

    def record_in(state):
        return FramedRecord(u, y, input_range=input_range, initial_state=state,
                            holdout=holdout, offset=offset, through=through)

    step = Steps(progress)
    rec = record_in(initial_state)
    check_record(rec.u, rec.y)
    if isinstance(initial_state, str) and initial_state == "auto" and \
            rec.state_mode in ("cycled", "rise"):
        # at rest after a full cycle, or from the zero state; a record starting inside its
        # range that its first sweep settles too late: after a rise or after a fall
        # (identify/_start_state.py)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PihystWarning)
            rec, rec.state_choice = start_state(rec, record_in, fitter_of)
    step.done(f"start state: {rec.state_mode}")
    if rec.state_mode == "explicit" and thresholds is None:
        raise FitError("an explicit initial_state needs explicit thresholds (one value "
                       "per operator)")
    delay_info = _delay_choice(rec, fitter_of, delay, _delay.confirming_family(families))
    step.done(f"delay: {delay_info['samples']} samples")
    refused = _REFUSED_DELAY.get()
    if refused is not None:
        delay_info.update(refused)
    unshifted = rec
    if delay_info["samples"]:
        rec = rec.shifted(delay_info["samples"])
    validation = (None if validate is None else
                  ValidationRecord.build(validate, rec.lo, rec.S, delay_info["samples"]))
    fitter = fitter_of(rec)
    chooses_thresholds = (thresholds is not None or candidates is not None
                          or n_operators is not None)

    known, unknown_reason = minor_loops_determined(rec, validation)
    results, skipped, caught = [], [], {}
    # where the data cannot tell the minor loops, a family whose structure does not fix
    # them cannot be chosen while one that does is fitted (_choice): it is fitted only
    # if none of those could be (a list of families given included: the rule is the
    # choice's)
    deferred = [] if known else [
        f for f in families if not f.minor_loops_fixed]
    if len(deferred) == len(families):
        deferred = []
    for fam in [f for f in families if f not in deferred] + deferred:
        if fam in deferred and results:
            skipped.append({"family": fam.name, "reason": (
                f"its minor loops are not fixed by its structure and the data "
                f"cannot determine them: {unknown_reason}")})
            continue
        kernels = fam.operators_key == "kernels"
        if not explicit_family and not fam.has_thresholds and chooses_thresholds:
            skipped.append({"family": fam.name, "reason": "has no thresholds (" + (
                "a grid of kernels, regularized)" if kernels else "not a PI model)")})
            continue
        if not explicit_family and kernels and not rec.has_held_back:
            skipped.append({"family": fam.name, "reason": "nothing held back to regularize "
                            "it on: a kernel basis would overfit"})
            continue
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always", PihystWarning)
            try:
                res = fitter.fit(fam, rival_rms=min((r.judged_rms for r in results),
                                                    default=None))
            except FitError as err:
                if explicit_family:
                    raise
                skipped.append({"family": fam.name, "reason": str(err)})
                continue
        caught[fam.name] = [x for x in w if issubclass(x.category, PihystWarning)]
        for x in w:
            if not issubclass(x.category, PihystWarning):
                warnings.warn_explicit(x.message, x.category, x.filename, x.lineno)
        results.append(replace(res, warnings=tuple(str(x.message) for x in caught[fam.name])))
        step.done(f"{fam.name} fitted: judged RMS {res.judged_rms:.4g}")
    if not results:
        raise FitError("no family could be fitted: " + "; ".join(
            f"{s['family']}: {s['reason']}" for s in skipped))

    results.sort(key=lambda r: [f.name for f in families].index(r.name))
    cands = []
    for r in results:
        by_kind = errors_by_kind(r.judged_on or fitter, r.model, validation)
        cands.append(Candidate(r, by_kind, judged_rms(r, by_kind), _latency(r.model)))
    best_c, criterion = choose(
        cands, minor_loops_known=known, unknown_reason=unknown_reason,
        judged_on_held_back=rec.has_held_back or validation is not None,
        n_fitted=rec.layout.count("fit"), max_operators=max_operators,
        max_latency=max_latency)
    best = best_c.fitted
    if delay_info["auto"] and delay_info["samples"]:
        refused = _delay_refused(unshifted, fitter_of, best, best_c.judged_rms, validate,
                                 delay_info)
        if refused is not None:
            token = _REFUSED_DELAY.set(refused)
            try:
                return fit(u, y, family=family, thresholds=thresholds,
                           n_operators=n_operators, candidates=candidates,
                           n_candidates=n_candidates, offset=offset,
                           nonnegative=nonnegative, bounds=bounds, through=through,
                           initial_state=initial_state, holdout=holdout, refit=refit,
                           input_range=input_range, validate=validate, delay=0,
                           max_operators=max_operators, max_latency=max_latency,
                           max_exhaustive=max_exhaustive, t=t, creep=False,
                           progress=progress)
            finally:
                _REFUSED_DELAY.reset(token)
    for x in caught[best.name]:
        warnings.warn(f"{best.name}: {x.message}", x.category, stacklevel=2)

    model = best.model
    final_errors = None
    if refit and rec.has_held_back:
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always", PihystWarning)
            model = best.refit()
        step.done(f"{best.name} refitted on all cycles")
        if not caught[best.name]:
            for x in w:
                warnings.warn(f"{best.name} (refit): {x.message}", x.category, stacklevel=2)
        final_errors = (best.judged_on or fitter).errors(model)
        if validation is not None:
            final_errors["validation"] = validation.errors(model)
    check_fit(rec, best_c.judged_rms, model)
    undetermined = _undetermined(rec, validation, known, unknown_reason, delay_info, cands,
                                 skipped)
    report = FitReport.build(rec, cands, skipped, best.name, criterion,
                             refit=bool(refit and rec.has_held_back),
                             final_errors=final_errors, delay=delay_info,
                             validation=None if validation is None else validation.describe(),
                             undetermined=undetermined)
    fit_summary = report.model_summary()
    record_start = (model.metadata or {}).get("fit", {}).get("record_start")
    if record_start is not None:
        # the state the record started from, as fitted (a Bouc-Wen z not at rest)
        fit_summary["record_start"] = record_start
    if rec.layout.settle_end:
        # the operator state once the first sweep has settled it: predictions of the same
        # record continue from it (model.predict(u[sample:], initial_state=state,
        # pending_input=pending_input) with a delay)
        end = rec.layout.settle_end
        fit_summary["settled"] = {
            "sample": int(end), "state": model.simulate(rec.u[:end]).final_state.tolist()}
    # the models carry the delay they were fitted with (u[k] -> y[k + d]), and the
    # sample period it holds at when the sample times are known
    lag = _carried_delay(delay_info["samples"], t, rec.u.size + delay_info["samples"])
    if delay_info["samples"] and "settled" in fit_summary and end >= delay_info["samples"]:
        # the inputs the settled state has not yet shown at the output
        fit_summary["settled"]["pending_input"] = \
            rec.u[end - delay_info["samples"]:end].tolist()
    model = model.replace(metadata={"fit": fit_summary, "pihyst_version": __version__},
                          **lag)
    models = {r.name: r.model.replace(**lag) if lag else r.model for r in results}
    models[best.name] = model
    return FitResult(model=model, report=report, models=models)


def _carried_delay(d, t, n):
    """The delay arguments of the fitted models: {} without a delay, else the delay and,
    with sample times ``t``, their median interval as the sample period."""
    if not d:
        return {}
    if t is None:
        return {"delay": d}
    t = np.asarray(t, dtype=np.float64)
    steps = np.diff(t) if t.ndim == 1 and t.size == n else np.empty(0)
    steps = steps[np.isfinite(steps) & (steps > 0)]
    return {"delay": d, "sample_period": float(np.median(steps)) if steps.size else None}


def _is_sequence(x):
    return isinstance(x, (list, tuple))


def _check_bounds(max_operators, max_latency, delay):
    if max_operators is not None and (int(max_operators) != max_operators
                                      or max_operators < 1):
        raise FitError(f"max_operators must be a positive integer, got {max_operators}")
    if max_latency is not None and not (isinstance(max_latency, (int, float))
                                        and max_latency > 0):
        raise FitError(f"max_latency must be a positive number of seconds, got {max_latency!r}")
    if delay != "auto" and not (isinstance(delay, (int, np.integer)) and delay >= 0):
        raise FitError(f"delay must be a number of samples >= 0 or 'auto', got {delay!r}")
    if delay != "auto" and delay > MAX_DELAY_SAMPLES:
        raise FitError(f"delay = {delay} is more than the {MAX_DELAY_SAMPLES:,} samples "
                       f"pihyst holds as an input delay")


def _check_weight_bounds(bounds):
    """``bounds`` as fit takes it: None, or (lower, upper) with each None, a number or
    one number per operator (their count is checked once the operators are known)."""
    if bounds is None:
        return
    if not isinstance(bounds, (list, tuple, np.ndarray)) or np.ndim(bounds) == 0 or \
            len(bounds) != 2:
        raise FitError(f"bounds must be a pair (lower, upper), got {bounds!r:.40}")
    for name, value in zip(("lower", "upper"), bounds):
        if value is None:
            continue
        a = np.asarray(value)
        if a.dtype.kind not in "iuf" or a.ndim > 1 or np.isnan(a).any():
            raise FitError(f"bounds: the {name} bound must be a number or one number per "
                           f"operator (None: no bound), got {value!r:.40}")


def _delay_choice(rec, fitter_of, delay, family):
    """The delay used (given, or by the rule of :mod:`pihyst.identify._delay`) and the
    scan of the record."""
    if rec.state_mode == "explicit":     # a state of other operators than the probe's
        tried = []
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PihystWarning)
            tried = _delay.scan(rec, fitter_of, _delay.max_delay(rec))
    finite = [t for t in tried if np.isfinite(t["rms"])]
    best = min(finite, key=lambda t: t["rms"]) if finite else None
    confirm = None
    if delay == "auto" and not tried:
        used, rule = 0, ("not probed (an explicit initial state is not the probe's): none "
                         "assumed; give the delay as a number of samples")
    elif delay == "auto":
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PihystWarning)
            used, rule, confirm = _delay.adopted(rec, fitter_of, tried, family)
    else:
        used, rule = int(delay), "given" if delay else "none assumed (delay=0)"
    return {"samples": used, "rule": rule, "best": None if best is None else best["samples"],
            "tried": tried, "confirmation": confirm, "auto": delay == "auto",
            "probe": f"classical PI, {_delay.PROBE_PLAYS} equally spaced plays"}


def _delay_refused(rec, fitter_of, best, judged, validate, delay_info):
    """None if the family chosen holds back better with the delay "auto" adopted than
    without it; else the report's delay entry for the fit made again without it. The
    probe and the modified PI that confirm a delay can both fail to fit the loop's shape,
    which a shift then imitates (an asymmetric Preisach actuator recorded on a growing
    sine with a 2-sample lag: both gain 20-27 % at 8 samples; the kernels chosen hold
    back 0.81 um with them, 0.57 without, and err 1.1-1.5 % of range on ramps and
    staircases, 0.46-0.51 % without)."""
    validation = (None if validate is None else
                  ValidationRecord.build(validate, rec.lo, rec.S, 0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PihystWarning)
        fitter = fitter_of(rec)
        try:
            res = fitter.fit(best.family)
        except FitError:
            return None
        without = judged_rms(res, errors_by_kind(res.judged_on or fitter, res.model,
                                                 validation))
    if not without <= judged:
        return None
    d = delay_info["samples"]
    return {"auto": True, "best": delay_info["best"], "tried": delay_info["tried"],
            "confirmation": delay_info["confirmation"], "refused": d,
            "rule": (f"{d} samples lowered the probes' held-back RMS, but the family "
                     f"chosen, {best.name}, holds back {judged:.4g} with them against "
                     f"{without:.4g} without: a shape the probes cannot fit, not a dead "
                     f"time")}


def _latency(model):
    if model.family != "bouc-wen" and np.any(model.weights < 0):
        return None                  # negative weights (nonnegative=False): no compensator
    return estimate_latency(model)


def _undetermined(rec, validation, known, unknown_reason, delay_info, cands, skipped):
    """What the data could not determine, as sentences for the report."""
    out = []
    if not rec.has_held_back and validation is None:
        out.append("nothing is held back and there is no validation record: every error "
                   "is on the fitted data (optimistic), and the choices were made by BIC")
    if not known:
        dropped = [c.name for c in cands if c.excluded and "minor loops" in c.excluded] + [
            x["family"] for x in skipped if "minor loops" in x["reason"]]
        out.append(f"the minor loops (reversals inside the range): {unknown_reason}. "
                   f"Families whose structure fixes them from the major loop were preferred"
                   + (f" ({', '.join(dropped)} not chosen)" if dropped else "")
                   + "; a record with reversals inside the range, or validate=(u2, y2), "
                     "would tell")
    tried = {t["samples"]: t["rms"] for t in delay_info["tried"]}
    used, best = delay_info["samples"], delay_info["best"]
    adopted = delay_info["auto"] and used     # the rule's sentence says why
    if best is not None and best != used and not adopted and \
            tried[best] < (1 - DELAY_NOTE_GAIN) * tried.get(used, np.inf):
        hint = (f"not adopted, {delay_info['rule']}" if delay_info["auto"] else
                "align the record, or fit with delay='auto'")
        at_used = (f"{tried[used]:.4g} at {used}" if used in tried else
                   f"{used} not probed")
        out.append(f"the input-output delay: the record fits best with the output lagging "
                   f"by {best} samples (probe RMS {tried[best]:.4g} against {at_used}); "
                   f"the models assume {used}. A delay is not hysteresis: {hint}")
    return out
