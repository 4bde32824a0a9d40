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
5. returns the family with the lowest held-back error, its weights refitted on all the
   cycles, and a report (:mod:`pihyst.identify._report`) of every family.
"""

import math
import warnings
from dataclasses import replace

from pihyst._version import __version__
from pihyst.exceptions import FitError, PihystWarning
from pihyst.identify._families import FAMILY_NAMES, as_family
from pihyst.identify._family_fit import INITIAL_STATES, FamilyFitter, FramedRecord, cycled_state
from pihyst.identify._report import FitReport, FitResult
from pihyst.identify._subsets import DEFAULT_MAX_EXHAUSTIVE

__all__ = ["fit", "FAMILY_NAMES", "INITIAL_STATES", "cycled_state"]

DEFAULT_N_CANDIDATES = 16


def fit(u, y, *, family=None, thresholds=None, n_operators=None, candidates=None,
        n_candidates=DEFAULT_N_CANDIDATES, offset=True, nonnegative=True, bounds=None,
        through=None, initial_state="auto", holdout="alternate", refit=True,
        input_range=None, max_exhaustive=DEFAULT_MAX_EXHAUSTIVE):
    """Fit PI-type hysteresis models to a measured record and keep the most accurate.

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
        :class:`~pihyst.model.BoucWenModel` (docs/theory/bouc-wen.md), compared with the
        others when listed (``family=[*pihyst.identify.FAMILY_NAMES, "bouc-wen"]``).
        Default: the PI families (``FAMILY_NAMES``), compared on the held-back cycles;
        the one with the lowest held-back RMS is returned.
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
    initial_state : "auto", "cycled", "settle", "zero" or array_like
        Operator state before the first sample. "cycled": at rest at the bottom of the
        range after a full bottom -> top -> bottom cycle (records made as in
        docs/interfaces.md); "settle": unknown, the first full sweep of the input range settles the
        operators and is not fitted; "auto": "cycled" if the record starts at the bottom
        of its range, else "settle". An array (needs ``thresholds``) is used as given.
    holdout : "alternate", float or None
        Held-back cycles: every other cycle (major and minor separately), the last
        fraction of the record, or none (choices then judged on the fitted data).
    refit : bool
        Refit the chosen model's weights on all cycles (fitted and held-back) after the
        choice. The report's held-back errors are those of the fit before the refit.
    input_range : (min, max), optional
        Input range of the model; default the data's span.
    max_exhaustive : int
        Largest number of subsets of the requested size searched exhaustively (the
        automatic size search uses at most 600 per size, then greedy selection + swaps).

    Returns
    -------
    FitResult
        ``.model`` (the fitted model, with the fit recorded in ``model.metadata["fit"]``),
        ``.report`` (a :class:`FitReport`: errors, per-family comparison, threshold
        choice and its reasons; ``print(report)`` or ``report.to_json()``) and ``.models``
        (every family's fitted model by name).

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
    explicit_family = family is not None
    specs = FAMILY_NAMES if family is None else (
        [family] if isinstance(family, str) or not _is_sequence(family) else list(family))
    families = [as_family(f) for f in specs]
    if len({f.name for f in families}) < len(families):
        raise FitError("each family may be given once (their results are reported by name)")
    rec = FramedRecord(u, y, input_range=input_range, initial_state=initial_state,
                       holdout=holdout, offset=offset, through=through)
    if thresholds is not None and candidates is not None:
        raise FitError("give thresholds (used as they are) or candidates (chosen from), "
                       "not both")
    if rec.state_mode == "explicit" and thresholds is None:
        raise FitError("an explicit initial_state needs explicit thresholds (one value "
                       "per operator)")
    if n_operators is not None and thresholds is not None:
        raise FitError("give thresholds or n_operators (how many to choose), not both")
    if n_operators is not None and (int(n_operators) != n_operators or n_operators < 1):
        raise FitError(f"n_operators must be a positive integer, got {n_operators}")
    fitter = FamilyFitter(rec, thresholds=thresholds, candidates=candidates,
                          n_candidates=n_candidates, n_operators=n_operators,
                          nonnegative=nonnegative, bounds=bounds, max_exhaustive=max_exhaustive)
    chooses_thresholds = (thresholds is not None or candidates is not None
                          or n_operators is not None)

    results, skipped, caught = [], [], {}
    for fam in families:
        kernels = fam.operators_key == "kernels"
        if not explicit_family and kernels and chooses_thresholds:
            skipped.append({"family": fam.name, "reason": "has no thresholds (a grid of "
                            "kernels, regularized)"})
            continue
        if not explicit_family and kernels and not rec.has_held_back:
            skipped.append({"family": fam.name, "reason": "nothing held back to regularize "
                            "it on: a kernel basis would overfit"})
            continue
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always", PihystWarning)
            try:
                res = fitter.fit(fam)
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
    if not results:
        raise FitError("no family could be fitted: " + "; ".join(
            f"{s['family']}: {s['reason']}" for s in skipped))

    if rec.has_held_back:
        best = min(results, key=lambda r: r.judged_rms)
        criterion = "lowest held-back RMS error"
    else:
        n = rec.layout.count("fit")
        best = min(results, key=lambda r: n * math.log(max(r.judged_rms, 1e-300) ** 2)
                   + r.n_params * math.log(n))
        criterion = "lowest BIC on the fitted data (nothing held back)"
    for x in caught[best.name]:
        warnings.warn(f"{best.name}: {x.message}", x.category, stacklevel=2)

    model = best.model
    final_errors = None
    if refit and rec.has_held_back:
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always", PihystWarning)
            model = best.refit()
        if not caught[best.name]:
            for x in w:
                warnings.warn(f"{best.name} (refit): {x.message}", x.category, stacklevel=2)
        final_errors = fitter.errors(model)
    report = FitReport.build(rec, results, skipped, best.name, criterion,
                             refit=bool(refit and rec.has_held_back),
                             final_errors=final_errors)
    fit_summary = report.model_summary()
    if rec.layout.settle_end:
        # the operator state once the first sweep has settled it: predictions of the same
        # record continue from it (model.predict(u[sample:], initial_state=state))
        end = rec.layout.settle_end
        fit_summary["settled"] = {
            "sample": end, "state": model.simulate(rec.u[:end]).final_state.tolist()}
    model = model.replace(metadata={"fit": fit_summary, "pihyst_version": __version__})
    models = {r.name: r.model for r in results}
    models[best.name] = model
    return FitResult(model=model, report=report, models=models)


def _is_sequence(x):
    return isinstance(x, (list, tuple))
