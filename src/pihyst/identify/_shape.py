"""The multislope shape search of family ``multislope-identified``
(docs/theory/identification.md, "Multislope shape search"): an outer Nelder-Mead search
over (a, b, h) (and U) around the linear problem, whose weights are always the exact QP
solution for the shape being tried.

1. :func:`identify_shape`: the shape with all candidate operators, before the threshold
   search;
2. :func:`refine_shape`: the shape again with only the chosen operators, their
   thresholds held as fractions of the largest valid threshold (1 - a)U/(1 - a h).

Each search evaluates its objective on the record subsampled to ``SEARCH_SAMPLES``
samples plus every input extremum (exact operator outputs there, fewer squares summed);
the weights of the shape found are then fitted on the full record.
"""

import numpy as np

from pihyst.model import InvalidModelError

SHAPE_BOUNDS = {"a": (0.05, 0.995), "b": (1.005, 3.0), "h": (0.0, 1.0)}
EVALUATIONS_PER_PARAMETER = 60
SEARCH_SAMPLES = 20_000


def _search_fitter(fitter):
    """``fitter`` on the subsampled record (itself for a short record)."""
    from pihyst.identify._boucwen import FAMILY_TRAVEL, travel_window

    stop = travel_window(fitter.rec, FAMILY_TRAVEL)
    if stop is not None:
        # a record of much input travel: every extremum of it kept would cost each of
        # the search's evaluations a pass over thousands of reversals (2 s on 10^6
        # samples of level ramps); its first cycles tell the shape as well
        fitter = fitter.windowed(stop, note=lambda kept, n: (
            f"shape searched on the first {kept} of {n} samples ({FAMILY_TRAVEL:g} ranges "
            f"of input travel), the weights then fitted on all"))
    return fitter.subsampled(SEARCH_SAMPLES, note=lambda kept, n: (
        f"shape searched on {kept} of {n} samples (evenly spaced, and every input "
        f"extremum), the weights then fitted on all"))


def _names(fam):
    return ["a", "b", "h"] + (["U"] if fam.identify == "with-U" else [])


def _bounds(names, S):
    return [SHAPE_BOUNDS[k] if k != "U" else (0.5 * S, 2.0 * S) for k in names]


def _objective(fitter, fam, names, fractions=None):
    """RMS error on the fitted samples as a function of the shape, weights by QP."""
    rec = fitter.rec
    bad = 1e6 * (rec.measured_range + 1.0)

    def objective(p):
        trial = fam.with_shape(**dict(zip(names, (float(v) for v in p))))
        s = trial.shape(rec.S)
        if not (0 < s["a"] < 1 < s["b"] and 0 <= s["h"] <= 1):
            return bad
        if fitter.thresholds is not None:
            cand = fitter.thresholds
            if cand.max() > trial.max_threshold(rec.S):
                return bad
        elif fractions is not None:
            cand = fractions * trial.max_threshold(rec.S)
        else:
            cand = trial.candidates(rec.S, fitter.n_candidates)
        try:
            template = trial.template(cand, rec.S)
        except InvalidModelError:
            return bad
        _, parts, rows = fitter.grams(trial, template, roles=("fit",))
        prob = fitter.problem(trial, parts, rows, len(cand),
                              [f"r{i}" for i in range(len(cand))])
        cols, x = prob.solve(tuple(range(len(cand))))
        return bad if x is None else prob.fit.rms(cols, x)
    return objective


def _minimize(fitter, fam, fractions=None):
    """(family with the best shape found, fitted RMS at the start, at the end)."""
    S = fitter.rec.S
    names = _names(fam)
    start = fam.shape(S)
    x0 = np.array([start[k] for k in names])
    objective = _objective(_search_fitter(fitter), fam, names, fractions)
    f0 = objective(x0)
    from scipy.optimize import minimize  # lazy: SciPy optimize takes 0.2 s to load

    bounds = _bounds(names, S)
    res = minimize(objective, x0, method="Nelder-Mead", bounds=bounds,
                   options={"maxfev": EVALUATIONS_PER_PARAMETER * len(names), "xatol": 1e-4,
                            "fatol": 1e-7 * max(fitter.rec.measured_range, 1e-300)})
    x = res.x if res.fun <= f0 else x0
    at_bound = [f"{k} = {v:.4g}" for k, v, (lo, hi) in zip(names, x, bounds)
                if min(v - lo, hi - v) <= 1e-3 * (hi - lo)]
    if at_bound and res.fun < f0:
        fitter.note(f"identified shape at the edge of its search range: "
                            f"{', '.join(at_bound)} (the data favour a shape beyond it)")
    return fam.with_shape(**dict(zip(names, (float(v) for v in x)))), f0, min(res.fun, f0)


def identify_shape(fitter, fam):
    """``fam`` with the shape identified with all candidate operators."""
    S = fitter.rec.S
    start = fam.shape(S)
    new, f0, f1 = _minimize(fitter, fam)
    end = new.shape(S)
    changes = ", ".join(f"{k} {start[k]:.4g} -> {end[k]:.4g}" for k in _names(fam))
    fitter.note(f"shape identified with all candidate operators: {changes}; "
                        f"fitted RMS {f0:.4g} -> {f1:.4g}")
    return new


def refine_shape(fitter, fitted):
    """``fitted`` (a FamilyFit) with the shape re-identified for its chosen operators
    (thresholds kept as fractions of the largest valid threshold), weights refitted."""
    fam, S = fitted.family, fitter.rec.S
    fractions = np.asarray(fitted.operators, dtype=float) / fam.max_threshold(S)
    new, f0, f1 = _minimize(fitter, fam, fractions)
    if f1 < f0:
        fitter.note(f"shape refined for the chosen operators: a={new.a:.4g}, "
                            f"b={new.b:.4g}, h={new.h:.4g}; fitted RMS {f0:.4g} -> {f1:.4g}")
    r = fractions * new.max_threshold(S)
    template = new.template(r, S)
    state0, parts, rows = fitter.grams(new, template)
    prob = fitter.problem(new, parts, rows, len(r), [f"r={v:g}" for v in r])
    chosen = tuple(range(len(r)))
    _, x = prob.solve(chosen, warn=True)
    choice = dict(fitted.threshold_choice)
    choice.update(chosen=[float(v) for v in r], shape_refined=True,
                  note="the thresholds were chosen, and the reasons computed, with the "
                       "shape identified on all candidates; the shape was then refined for "
                       "the chosen operators (thresholds kept as fractions of the largest "
                       "valid one)")
    return fitter.subset_result(new, r, chosen, x, state0, prob, choice)
