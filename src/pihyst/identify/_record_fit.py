"""One record fitted without creep, step by step (docs/theory/identification.md, "The
procedure"): checks -> fitting frame -> start state -> delay -> cycles and held-back data
-> candidate operators, weights and structure of every family -> choice -> refit ->
report. Each step is a function below that returns a frozen decision
(:mod:`pihyst.identify._decisions`); :func:`fit_record` runs them in order. The creep
step (:mod:`pihyst.identify._creep`) runs :func:`fit_record` on the record with its
creep estimate removed, handing it the delay decided on the record itself.
"""

import warnings
from dataclasses import dataclass, replace
from typing import Optional

import numpy as np

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
from pihyst.identify._constants import DELAY_NOTE_GAIN
from pihyst.identify._decisions import Choice, Delay, FamiliesFitted, StartState
from pihyst.identify._latency import estimate_latency
from pihyst.identify._report import FitReport, FitResult
from pihyst.identify._responses import Responses
from pihyst.identify._start_state import start_state
from pihyst.identify._sufficiency import check_fit, check_record

__all__ = ["RecordFit", "fit_record"]

# A record longer than this is fitted, judged and refitted on about this many samples
# plus every input extremum (FramedRecord.subsampled: the operators are rate-independent,
# so their outputs there are exactly those of the whole record; only fewer squares are
# summed). A search budget, not a decision: every record the population and the measured
# sets judge the fit on has at most 50,001 samples and is fitted whole; a 10^6-sample
# record then costs about what a 60,000-sample one does, plus its predictions.
FIT_SAMPLES = 60_000


@dataclass(frozen=True)
class RecordFit:
    """A record fitted without creep: the result and the decisions later steps use."""

    result: FitResult
    start: StartState
    delay: Delay
    choice: Choice
    settled_sample: int                  # end of the settling sweep (0: none)
    record_start: Optional[list] = None  # a Bouc-Wen model's (x, z) at the record's start


@dataclass(frozen=True)
class _Attempt:
    """The families fitted and the choice made at one delay."""

    rec: object               # FramedRecord, output shifted by the delay
    fitter: object            # its FamilyFitter
    validation: object
    minor_loops: tuple        # (determined, why not)
    fitted: FamiliesFitted
    choice: Choice


def fit_record(u, y, options, steps, *, t=None, delay=None, responses=None):
    """:class:`RecordFit` of ``(u, y)`` with ``options`` (a FitOptions; creep is not
    this function's step); ``delay``: a :class:`Delay` decided before (else decided
    here); ``responses``: the output-independent results of other fits of the same
    input (a ``_responses.Responses``); ``steps`` reports each step's end."""
    responses = Responses() if responses is None else responses
    rec, start = decide_start_state(u, y, options)
    steps.done(f"start state: {start.mode}")
    if delay is None:
        delay = decide_delay(rec, options)
    steps.done(f"delay: {delay.samples} samples"
               + (" (decided on the record itself)" if delay.decided_before else ""))
    attempt = fit_at_delay(rec, delay, options, steps, responses)
    refused, reuse = delay_refusal(rec, attempt, delay, options, responses)
    if refused is not None:
        delay = refused
        attempt = fit_at_delay(rec, delay, options, steps, responses, reuse=reuse)
    return finish(attempt, start, delay, options, steps, t)


# ------------------------------------------------------------------ checks, frame, start
def decide_start_state(u, y, options):
    """(framed record, :class:`StartState`): the record in the fitting frame, checked,
    from the state "auto" finds (identify/_start_state.py) or the one given."""
    rec = options.frame(u, y)
    check_record(rec.u, rec.y)
    compared = None
    if isinstance(options.initial_state, str) and options.initial_state == "auto" and \
            rec.state_mode in ("cycled", "rise"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PihystWarning)
            rec, compared = start_state(rec, lambda s: options.frame(u, y, s),
                                        options.fitter)
        rec = rec.with_start_choice(compared)
    if rec.state_mode == "explicit" and options.thresholds is None:
        raise FitError("an explicit initial_state needs explicit thresholds (one value "
                       "per operator)")
    return rec, StartState(mode=rec.state_mode, compared=compared)


# ------------------------------------------------------------------ delay
def decide_delay(rec, options):
    """The :class:`Delay` used: given, or by the rule of :mod:`pihyst.identify._delay`
    (a scan of a probe, confirmed by the fitted structure)."""
    if rec.state_mode == "explicit":     # a state of other operators than the probe's
        tried = []
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PihystWarning)
            tried = _delay.scan(rec, options.fitter, _delay.max_delay(rec))
    finite = [t for t in tried if np.isfinite(t["rms"])]
    best = min(finite, key=lambda t: t["rms"]) if finite else None
    confirm = None
    auto = options.delay == "auto"
    if auto and not tried:
        used, rule = 0, ("not probed (an explicit initial state is not the probe's): none "
                         "assumed; give the delay as a number of samples")
    elif auto:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PihystWarning)
            used, rule, confirm = _delay.adopted(
                rec, options.fitter, tried, _delay.confirming_family(options.families))
    else:
        used = int(options.delay)
        rule = "given" if used else "none assumed (delay=0)"
    return Delay(samples=used, rule=rule, best=None if best is None else best["samples"],
                 tried=tuple(tried), confirmation=confirm, auto=auto,
                 probe=f"classical PI, {_delay.PROBE_PLAYS} equally spaced plays")


def delay_refusal(rec, attempt, delay, options, responses):
    """(refused :class:`Delay`, {family: (FamilyFit, warnings)} to reuse) when the
    family chosen with the delay "auto" adopted holds back better without it, else
    (None, None). The probe and the modified PI that confirm a delay can both fail to
    fit the loop's shape, which a shift then imitates (an asymmetric Preisach actuator
    recorded on a growing sine with a 2-sample lag: both gain 20-27 % at 8 samples; the
    kernels chosen hold back 0.81 um with them, 0.57 without, and err 1.1-1.5 % of range
    on ramps and staircases, 0.46-0.51 % without)."""
    if not (delay.auto and delay.samples) or delay.decided_before:
        return None, None
    chosen = attempt.choice.chosen
    validation = (None if options.validate is None else
                  ValidationRecord.build(options.validate, rec.lo, rec.S, 0))
    fitter = options.fitter(rec.subsampled(FIT_SAMPLES), responses)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PihystWarning)
        try:
            res = fitter.fit(chosen.fitted.family)
        except FitError:
            return None, None
    without = judged_rms(res, errors_by_kind(res.judged_on or fitter, res.model, validation))
    if not without <= chosen.judged_rms:
        return None, None
    # a Bouc-Wen fit depends on the families fitted before it (rival_rms): not reused
    reuse = {} if chosen.fitted.family.name == "bouc-wen" else {
        res.name: (res, fitter, caught)}
    return delay.refusing(chosen.name, chosen.judged_rms, without), reuse


# ------------------------------------------------------------------ families and choice
def fit_at_delay(rec, delay, options, steps, responses, reuse=None):
    """The :class:`_Attempt` of every family on ``rec`` with its output ``delay``
    samples later: cycles and held-back data, each family's fit, the choice."""
    if delay.samples:
        rec = rec.shifted(delay.samples)
    validation = (None if options.validate is None else
                  ValidationRecord.build(options.validate, rec.lo, rec.S, delay.samples))
    fitter = options.fitter(rec.subsampled(FIT_SAMPLES), responses)
    if reuse:
        fitter = next(iter(reuse.values()))[1]
    minor_loops = minor_loops_determined(rec, validation)
    fitted = fit_families(fitter.rec, fitter, options, minor_loops, steps, reuse or {})
    choice = choose_family(fitter.rec, fitter, fitted, validation, minor_loops, options)
    return _Attempt(rec=rec, fitter=fitter, validation=validation, minor_loops=minor_loops,
                    fitted=fitted, choice=choice)


def fit_families(rec, fitter, options, minor_loops, steps, reuse):
    """:class:`FamiliesFitted`: every family of ``options`` fitted on ``fitter``'s record,
    or skipped with the reason. Where the data cannot tell the minor loops, a family
    whose structure does not fix them cannot be chosen while one that does is fitted
    (_choice): it is fitted only if none of those could be."""
    families = options.families
    known, unknown_reason = minor_loops
    deferred = [] if known else [f for f in families if not f.minor_loops_fixed]
    if len(deferred) == len(families):
        deferred = []
    results, skipped, caught = [], [], {}
    for fam in [f for f in families if f not in deferred] + deferred:
        reason = _skip_reason(fam, fam in deferred and results, rec, options,
                              unknown_reason)
        if reason is None:
            try:
                res, caught[fam.name] = _fit_family(fitter, fam, results, reuse)
            except FitError as err:
                if options.explicit_family:
                    raise
                reason = str(err)
        if reason is not None:
            skipped.append({"family": fam.name, "reason": reason})
            continue
        results.append(res)
        steps.done(f"{fam.name} fitted: judged RMS {res.judged_rms:.4g}")
    if not results:
        raise FitError("no family could be fitted: " + "; ".join(
            f"{s['family']}: {s['reason']}" for s in skipped))
    order = [f.name for f in families]
    results.sort(key=lambda r: order.index(r.name))
    return FamiliesFitted(results=tuple(results), skipped=tuple(skipped), warnings=caught)


def _skip_reason(fam, deferred_behind_fitted, rec, options, unknown_reason):
    """Why ``fam`` is not fitted, or None."""
    kernels = fam.operators_key == "kernels"
    if deferred_behind_fitted:
        return (f"its minor loops are not fixed by its structure and the data cannot "
                f"determine them: {unknown_reason}")
    if not options.explicit_family and not fam.has_thresholds and options.chooses_thresholds:
        return "has no thresholds (" + ("a grid of kernels, regularized)" if kernels
                                        else "not a PI model)")
    if not options.explicit_family and kernels and not rec.has_held_back:
        return "nothing held back to regularize it on: a kernel basis would overfit"
    return None


def _fit_family(fitter, fam, results, reuse):
    """(FamilyFit with its warnings' texts, the PihystWarnings its fit gave); other
    warnings pass on to the caller."""
    if fam.name in reuse:
        res, _, w = reuse[fam.name]
    else:
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always", PihystWarning)
            res = fitter.fit(fam, rival_rms=min((r.judged_rms for r in results),
                                                default=None))
    ours = tuple(x for x in w if issubclass(x.category, PihystWarning))
    for x in w:
        if not issubclass(x.category, PihystWarning):
            warnings.warn_explicit(x.message, x.category, x.filename, x.lineno)
    return replace(res, warnings=tuple(str(x.message) for x in ours)), ours


def choose_family(rec, fitter, fitted, validation, minor_loops, options):
    """The :class:`Choice` among the families fitted (identify/_choice.py), each judged
    on every kind of held-back data, with its compensator's estimated latency."""
    cands = []
    for r in fitted.results:
        by_kind = errors_by_kind(r.judged_on or fitter, r.model, validation)
        cands.append(Candidate(r, by_kind, judged_rms(r, by_kind), _latency(r.model)))
    known, unknown_reason = minor_loops
    return choose(cands, minor_loops_known=known, unknown_reason=unknown_reason,
                  judged_on_held_back=rec.has_held_back or validation is not None,
                  n_fitted=rec.layout.count("fit"), max_operators=options.max_operators,
                  max_latency=options.max_latency)


def _latency(model):
    if model.family != "bouc-wen" and np.any(model.weights < 0):
        return None                  # negative weights (nonnegative=False): no compensator
    return estimate_latency(model)


# ------------------------------------------------------------------ refit and report
def finish(attempt, start, delay, options, steps, t):
    """:class:`RecordFit`: the chosen family refitted on every used cycle, checked, with
    its report and the model's ``metadata["fit"]``."""
    rec, best_c = attempt.rec, attempt.choice.chosen
    best = best_c.fitted
    caught = attempt.fitted.warnings[best.name]
    for x in caught:
        warnings.warn(f"{best.name}: {x.message}", x.category, stacklevel=4)
    model, final_errors = refit(attempt, options, steps, quiet=bool(caught))
    check_fit(rec, best_c.judged_rms, model)
    report = FitReport.build(
        rec, start, attempt.choice, attempt.fitted.skipped,
        fitted_on=int(attempt.fitter.rec.u.size),
        refit=final_errors is not None, final_errors=final_errors,
        delay=delay.to_report(),
        validation=None if attempt.validation is None else attempt.validation.describe(),
        undetermined=undetermined(attempt, delay))
    summary = report.model_summary()
    record_start = (model.metadata or {}).get("fit", {}).get("record_start")
    if record_start is not None:
        summary["record_start"] = record_start
    summary.update(_settled(rec, model, delay.samples))
    lag = _carried_delay(delay.samples, t, rec.u.size + delay.samples)
    model = model.replace(metadata={"fit": summary, "pihyst_version": __version__}, **lag)
    models = {r.name: r.model.replace(**lag) if lag else r.model
              for r in attempt.fitted.results}
    models[best.name] = model
    return RecordFit(result=FitResult(model=model, report=report, models=models),
                     start=start, delay=delay, choice=attempt.choice,
                     settled_sample=int(rec.layout.settle_end), record_start=record_start)


def refit(attempt, options, steps, quiet):
    """(model, errors after the refit or None): the chosen family's weights fitted on
    the fitted and held-back cycles together (``options.refit``). The report's
    held-back errors stay those of the fit before it. ``quiet``: its warnings repeat
    the fit's, already given."""
    best = attempt.choice.chosen.fitted
    if not (options.refit and attempt.rec.has_held_back):
        return best.model, None
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always", PihystWarning)
        model = best.refit()
    steps.done(f"{best.name} refitted on all cycles")
    if not quiet:
        for x in w:
            warnings.warn(f"{best.name} (refit): {x.message}", x.category, stacklevel=5)
    final_errors = (best.judged_on or attempt.fitter).errors(model)
    if attempt.validation is not None:
        final_errors["validation"] = attempt.validation.errors(model)
    return model, final_errors


def _settled(rec, model, d):
    """The operator state once the first sweep has settled it, as the model's metadata
    records it: predictions of the same record continue from it
    (``model.predict(u[sample:], initial_state=state, pending_input=pending_input)``
    with a delay); {} when nothing settles."""
    end = rec.layout.settle_end
    if not end:
        return {}
    settled = {"sample": int(end), "state": model.simulate(rec.u[:end]).final_state.tolist()}
    if d and end >= d:
        # the inputs the settled state has not yet shown at the output
        settled["pending_input"] = rec.u[end - d:end].tolist()
    return {"settled": settled}


def _carried_delay(d, t, n):
    """The delay arguments of the fitted models: {} without a delay, else the delay and,
    with sample times ``t``, their median interval as the sample period."""
    if not d:
        return {}
    if t is None:
        return {"delay": d}
    t = np.asarray(t, dtype=np.float64)
    intervals = np.diff(t) if t.ndim == 1 and t.size == n else np.empty(0)
    intervals = intervals[np.isfinite(intervals) & (intervals > 0)]
    return {"delay": d,
            "sample_period": float(np.median(intervals)) if intervals.size else None}


def undetermined(attempt, delay):
    """What the data could not determine, as sentences for the report."""
    rec, validation = attempt.rec, attempt.validation
    known, unknown_reason = attempt.minor_loops
    out = []
    if not rec.has_held_back and validation is None:
        out.append("nothing is held back and there is no validation record: every error "
                   "is on the fitted data (optimistic), and the choices were made by BIC")
    if not known:
        dropped = [name for name, why in attempt.choice.excluded.items()
                   if "minor loops" in why] + [
            x["family"] for x in attempt.fitted.skipped if "minor loops" in x["reason"]]
        out.append(f"the minor loops (reversals inside the range): {unknown_reason}. "
                   f"Families whose structure fixes them from the major loop were preferred"
                   + (f" ({', '.join(dropped)} not chosen)" if dropped else "")
                   + "; a record with reversals inside the range, or validate=(u2, y2), "
                     "would tell")
    note = _delay_note(delay)
    if note:
        out.append(note)
    return out


def _delay_note(delay):
    """The report's sentence on a delay the record favours but the models do not assume."""
    tried = {t["samples"]: t["rms"] for t in delay.tried}
    used, best = delay.samples, delay.best
    adopted = delay.auto and used     # the rule's sentence says why
    if best is None or best == used or adopted or \
            not tried[best] < (1 - DELAY_NOTE_GAIN) * tried.get(used, np.inf):
        return None
    hint = (f"not adopted, {delay.rule}" if delay.auto else
            "align the record, or fit with delay='auto'")
    at_used = f"{tried[used]:.4g} at {used}" if used in tried else f"{used} not probed"
    return (f"the input-output delay: the record fits best with the output lagging by "
            f"{best} samples (probe RMS {tried[best]:.4g} against {at_used}); the models "
            f"assume {used}. A delay is not hysteresis: {hint}")
