"""Fitting one model family to a record: the record in the fitting frame (:class:`FramedRecord`)
and the fit of one family's weights, thresholds, shape or regularization
(:class:`FamilyFitter`). :func:`pihyst.identify.fit` runs it for every family.

Equations: the normal equations of ``_gram``, the QP of ``_qp``, the subset search of
``_subsets``; the frames of ``_families`` (docs/theory/identification.md).
"""

import numpy as np

from pihyst.exceptions import FitError, InfeasibleConstraintsError
from pihyst.identify._cycles import checked_signals, layout, starts_at_rest
from pihyst.identify._families import KrasnoselskiiPokrovskii, Multislope, MultislopeIdentified
from pihyst.identify._gram import Gram, accumulate
from pihyst.identify._qp import solve_qp
from pihyst.identify._subsets import PATH_MAX_EXHAUSTIVE, SubsetProblem, choose_size
from pihyst.metrics import error_summary
from pihyst.model import InvalidModelError

INITIAL_STATES = ("auto", "cycled", "settle", "zero")
SHAPE_BOUNDS = {"a": (0.05, 0.995), "b": (1.005, 3.0), "h": (0.0, 1.0)}
KP_LAMBDAS = 10.0 ** np.arange(-6, 4)
KP_DEFAULT_LAMBDA = 1e-2
CONSTANT_COLUMN = 1e-9  # an operator whose output varies less than this * S never moved


class FramedRecord:
    """The record in the fitting frame and every option that applies to all families."""

    def __init__(self, u, y, *, input_range, initial_state, holdout, offset, through):
        self.u, self.y = checked_signals(u, y)
        lo, hi = (float(self.u.min()), float(self.u.max())) if input_range is None else \
            (float(input_range[0]), float(input_range[1]))
        if not lo < hi:
            raise FitError(f"input_range must be [min, max] with min < max, got [{lo}, {hi}]")
        outside = np.flatnonzero((self.u < lo) | (self.u > hi))
        if outside.size:
            i = outside[0]
            raise FitError(f"input sample {i} = {self.u[i]:g} is outside input_range "
                           f"[{lo:g}, {hi:g}]", index=int(i), column="input")
        self.lo, self.S = lo, hi - lo
        self.v = self.u - lo
        self.measured_range = float(np.ptp(self.y))
        # offset: True = fitted, a number = fixed (subtracted from the data), False = 0
        if offset is True:
            self.fit_offset, self.fixed_offset = True, 0.0
        else:
            self.fit_offset, self.fixed_offset = False, float(offset or 0.0)
        self.d = self.y - self.fixed_offset

        self.explicit_state = None
        if isinstance(initial_state, str):
            if initial_state not in INITIAL_STATES:
                raise FitError(f"initial_state must be one of {', '.join(INITIAL_STATES)} or "
                               f"an array, got {initial_state!r}")
            mode = initial_state
            if mode == "auto":
                mode = "cycled" if starts_at_rest(self.v, self.S) else "settle"
        else:
            mode = "explicit"
            try:
                self.explicit_state = np.asarray(initial_state, dtype=float)
            except (TypeError, ValueError):
                raise FitError("initial_state must be 'auto', 'cycled', 'settle', 'zero' or "
                               "a list of numbers") from None
            if self.explicit_state.ndim != 1 or not np.all(np.isfinite(self.explicit_state)):
                raise FitError("initial_state must be a flat list of finite numbers")
        self.state_mode = mode
        self.layout = layout(self.v, self.S, settle=(mode == "settle"), holdout=holdout)
        self.has_held_back = self.layout.count("held_back") > 0
        self.through = self._through_indices(through)

    def _through_indices(self, through):
        if through is None:
            return []
        used = np.concatenate([self.layout.indices("fit"), self.layout.indices("held_back")])
        if isinstance(through, str):
            if through != "top":
                raise FitError(f"through must be 'top' or sample indices, got {through!r}")
            return [int(used[np.argmax(self.v[used])])]
        idx = [int(i) for i in np.atleast_1d(through)]
        for i in idx:
            if not 0 <= i < self.v.size:
                raise FitError(f"through: sample {i} is not in the record (0..{self.v.size - 1})")
            if i < self.layout.settle_end:
                raise FitError(f"through: sample {i} is in the first cycle, which only settles "
                               f"the operator states", index=i)
        return idx

    def start_state(self, family, template):
        """Operator state (fitting frame) before the first sample."""
        if self.state_mode == "explicit":
            state = family.v_state(self.explicit_state, self.lo)
            if state.size != template.n_operators:
                raise FitError(f"initial_state has {state.size} values but the model has "
                               f"{template.n_operators} operators")
            return state
        if self.state_mode == "zero":
            return family.v_state(np.zeros(template.n_operators), self.lo)
        return cycled_state(template, self.S)


def cycled_state(model, S):
    """Operator state at rest at the bottom of the range after a full bottom -> top ->
    bottom cycle (docs/interfaces.md), for a model of v on [0, S]. For a monotone sweep
    the operator output at its end only depends on its end points, so three samples are
    exact."""
    return model.simulate(np.array([0.0, S, 0.0])).final_state


class FamilyFitter:
    """Fits one family to a record; results are plain dicts for the report."""

    def __init__(self, rec, family, *, thresholds, candidates, n_candidates, n_operators,
                 nonnegative, bounds, max_exhaustive, identify_shape):
        self.rec, self.family = rec, family
        self.thresholds = None if thresholds is None else np.sort(np.asarray(thresholds, float))
        self.candidates = None if candidates is None else np.sort(np.asarray(candidates, float))
        self.n_candidates, self.n_operators = n_candidates, n_operators
        self.nonnegative, self.bounds = nonnegative, bounds
        self.max_exhaustive = max_exhaustive
        self.identify_shape = identify_shape
        self.notes = []

    # ---------------------------------------------------------------- columns
    def _grams(self, template, roles=("fit", "held_back")):
        rec = self.rec
        state0 = rec.start_state(self.family, template)
        segments = [(a, z, r if r in roles or r == "settle" else "settle")
                    for a, z, r in rec.layout.segments]
        parts, rows = accumulate(template, rec.v, rec.d, segments, state0, offset=True,
                                 rows_at=rec.through)
        return state0, parts, rows

    def _bounds(self, n_ops):
        """Bounds of the operator weights: w >= 0 by default, or the user's."""
        lo = np.full(n_ops, 0.0 if self.nonnegative else -np.inf)
        hi = np.full(n_ops, np.inf)
        if self.bounds is not None:
            for k, value in enumerate(self.bounds):
                if value is None:
                    continue
                value = np.asarray(value, dtype=float)
                if value.ndim and value.size != n_ops:
                    raise FitError(f"per-operator bounds need one value per operator "
                                   f"({n_ops} for {self.family.name} here), got {value.size}")
                (lo if k == 0 else hi)[:] = value
        return lo, hi

    def _problem(self, parts, rows, n_cand, names):
        """SubsetProblem over columns [candidates..., fixed operators..., offset]."""
        rec = self.rec
        m = parts["fit"].G.shape[0]
        keep = list(range(m)) if rec.fit_offset else list(range(m - 1))
        fit = _restrict(parts["fit"], keep)
        judge = _restrict(parts["held_back"], keep) if rec.has_held_back else fit
        lo, hi = self._bounds(m - 1)
        if rec.fit_offset:
            lo, hi = np.r_[lo, -np.inf], np.r_[hi, np.inf]
        A_eq = b_eq = None
        if rec.through:
            A_eq = np.array([rows[i][keep] for i in rec.through])
            b_eq = np.array([rec.d[i] for i in rec.through])
        return SubsetProblem(fit=fit, judge=judge, n_candidates=n_cand, lower=lo, upper=hi,
                             A_eq=A_eq, b_eq=b_eq,
                             names=names + (["offset"] if rec.fit_offset else []))

    def _constant_columns(self, parts, n_cols):
        """Operators whose output does not vary over the fitted samples."""
        g = parts["fit"]
        n = g.n
        mean = g.G[:n_cols, -1] / n
        var = np.diag(g.G)[:n_cols] / n - mean ** 2
        return np.flatnonzero(var <= (CONSTANT_COLUMN * self.rec.S) ** 2)

    # ---------------------------------------------------------------- subset families
    def fit_subset_family(self):
        fam, rec = self.family, self.rec
        if isinstance(fam, MultislopeIdentified):
            fam = self._identify_shape(fam)
            self.family = fam
        explicit = self.thresholds is not None
        if explicit:
            cand = self.thresholds
            self._check_thresholds(cand)
        elif self.candidates is not None:
            cand = self.candidates
            self._check_thresholds(cand)
        else:
            cand = fam.candidates(rec.S, self.n_candidates)
        template = fam.template(cand, rec.S)
        state0, parts, rows = self._grams(template)
        const = self._constant_columns(parts, len(cand))
        if const.size and explicit:
            r = cand[const[0]]
            raise FitError(f"{fam.name}: the input never reaches threshold {r:g} (span of "
                           f"the fitted data {rec.S:g}): that operator's output is constant, "
                           f"so its weight is undetermined; use thresholds below "
                           f"{_reach_limit(fam, rec.S):g}", column="input")
        dropped = []
        if const.size:
            dropped = [float(cand[i]) for i in const]
            keep_c = [i for i in range(len(cand)) if i not in set(const)]
            cand = cand[keep_c]
            template = fam.template(cand, rec.S)
            state0, parts, rows = self._grams(template)
            self.notes.append(f"candidate thresholds {_fmt_list(dropped)} dropped: the input "
                              f"never moves their operators")
        names = [f"r={r:g}" for r in cand] + [f"input segment {j}" for j in range(fam.n_fixed)]
        prob = self._problem(parts, rows, len(cand), names)

        if explicit:
            chosen = tuple(range(len(cand)))
            choice = None
        else:
            chosen, choice = self._choose(prob, cand)
        cols, x = prob.solve(chosen, warn=True)
        if x is None:
            raise InfeasibleConstraintsError(f"{fam.name}: no weights satisfy the constraints")
        if isinstance(fam, MultislopeIdentified) and not explicit and self.identify_shape:
            fam, cand, chosen, cols, x, state0, parts, prob = self._refine_shape(
                fam, cand, chosen, choice)
            self.family = fam
        return self._result(fam, cand, chosen, cols, x, state0, parts, prob, choice, dropped)

    def _check_thresholds(self, r):
        if r.size == 0:
            raise FitError("thresholds is empty")
        if np.any(r < 0) or np.any(np.diff(r) <= 0):
            raise FitError("thresholds must be >= 0 and distinct")
        limit = self.family.max_threshold(self.rec.S)
        if isinstance(self.family, Multislope) and r.max() > limit * (1 + 1e-12):
            s = self.family.shape(self.rec.S)
            raise FitError(f"{self.family.name}: threshold {r.max():g} is above (1 - a)U/(1 - a h) "
                           f"= {limit:g} for U={s['U']:g}, a={s['a']:g}, h={s['h']:g}",
                           column="input")

    def _choose(self, prob, cand):
        K = len(cand)
        if self.n_operators is not None:
            if not 1 <= self.n_operators <= K:
                raise FitError(f"{self.family.name}: cannot choose {self.n_operators} operators "
                               f"from {K} candidate thresholds")
            best = prob.best_of_size(self.n_operators, self.max_exhaustive)
            if not np.isfinite(best.rms):
                raise InfeasibleConstraintsError(f"{self.family.name}: no {self.n_operators} "
                                                 f"operators satisfy the constraints")
            path = [best]
            size_rule = f"requested: {self.n_operators}"
        else:
            path = prob.path(min(self.max_exhaustive, PATH_MAX_EXHAUSTIVE))
            best = choose_size(path)
            size_rule = ("smallest number of operators within 1 % of the lowest "
                         + ("held-back RMS" if self.rec.has_held_back else
                            "fitted RMS (nothing held back)"))
        reasons = prob.reasons(best.subset)
        judged_on = "held_back" if self.rec.has_held_back else "fit"
        choice = {
            "candidates": [float(c) for c in cand],
            "chosen": [float(cand[i]) for i in best.subset],
            "judged_on": judged_on,
            "search": best.method,
            "subsets_evaluated": prob.evaluations,
            "size_rule": size_rule,
            "sizes": [{"n_operators": len(c.subset), "thresholds": [float(cand[i]) for i in
                                                                    c.subset],
                       "rms": c.rms, "search": c.method} for c in path],
            "reasons": [_reason(r, cand, best.rms, judged_on) for r in reasons],
        }
        return best.subset, choice

    # ---------------------------------------------------------------- multislope shape
    def _shape_vector(self, fam):
        names = ["a", "b", "h"] + (["U"] if self.identify_shape == "with-U" else [])
        s = fam.shape(self.rec.S)
        return names, np.array([s[k] for k in names])

    def _shape_bounds(self, names):
        S = self.rec.S
        return [SHAPE_BOUNDS[k] if k != "U" else (0.5 * S, 2.0 * S) for k in names]

    def _shape_objective(self, fam, names, fractions=None):
        """RMS error on the fitted samples as a function of the shape, weights by QP."""
        rec = self.rec
        bad = 1e6 * (rec.measured_range + 1.0)

        def objective(p):
            shape = dict(zip(names, p))
            cand_fam = fam.with_shape(**shape)
            s = cand_fam.shape(rec.S)
            if not (0 < s["a"] < 1 < s["b"] and 0 <= s["h"] <= 1):
                return bad
            if self.thresholds is not None:
                cand = self.thresholds
                if cand.max() > cand_fam.max_threshold(rec.S):
                    return bad
            elif fractions is not None:
                cand = fractions * cand_fam.max_threshold(rec.S)
            else:
                cand = cand_fam.candidates(rec.S, self.n_candidates)
            try:
                template = cand_fam.template(cand, rec.S)
            except InvalidModelError:
                return bad
            _, parts, rows = self._grams(template, roles=("fit",))
            prob = self._problem(parts, rows, len(cand), [f"r{i}" for i in range(len(cand))])
            cols, x = prob.solve(tuple(range(len(cand))))
            return bad if x is None else prob.fit.rms(cols, x)
        return objective

    def _minimize_shape(self, fam, fractions=None):
        names, x0 = self._shape_vector(fam)
        objective = self._shape_objective(fam, names, fractions)
        f0 = objective(x0)
        from scipy.optimize import minimize  # lazy: SciPy optimize takes 0.2 s to load

        res = minimize(objective, x0, method="Nelder-Mead", bounds=self._shape_bounds(names),
                       options={"maxfev": 60 * len(names), "xatol": 1e-4,
                                "fatol": 1e-7 * max(self.rec.measured_range, 1e-300)})
        x = res.x if res.fun <= f0 else x0
        at_bound = [f"{k} = {v:.4g}" for k, v, (lo, hi) in
                    zip(names, x, self._shape_bounds(names))
                    if min(v - lo, hi - v) <= 1e-3 * (hi - lo)]
        if at_bound and res.fun < f0:
            self.notes.append(f"identified shape at the edge of its search range: "
                              f"{', '.join(at_bound)} (the data favour a shape beyond it)")
        return fam.with_shape(**dict(zip(names, (float(v) for v in x)))), f0, min(res.fun, f0)

    def _identify_shape(self, fam):
        if not self.identify_shape:
            return fam
        start = fam.shape(self.rec.S)
        new, f0, f1 = self._minimize_shape(fam)
        end = new.shape(self.rec.S)
        changes = ", ".join(f"{k} {start[k]:.4g} -> {end[k]:.4g}" for k in ("a", "b", "h", "U")
                            if k != "U" or self.identify_shape == "with-U")
        self.notes.append(f"shape identified with all candidate operators: {changes}; "
                          f"fitted RMS {f0:.4g} -> {f1:.4g}")
        return new

    def _refine_shape(self, fam, cand, chosen, choice):
        """Re-identify the shape for the chosen operators (thresholds kept as fractions of
        the largest valid threshold), then refit."""
        rmax = fam.max_threshold(self.rec.S)
        fractions = np.asarray(cand)[list(chosen)] / rmax
        new, f0, f1 = self._minimize_shape(fam, fractions)
        if f1 < f0:
            self.notes.append(f"shape refined for the chosen operators: a={new.a:.4g}, "
                              f"b={new.b:.4g}, h={new.h:.4g}; fitted RMS {f0:.4g} -> {f1:.4g}")
        fam = new
        r = fractions * fam.max_threshold(self.rec.S)
        template = fam.template(r, self.rec.S)
        state0, parts, rows = self._grams(template)
        names = [f"r={v:g}" for v in r]
        prob = self._problem(parts, rows, len(r), names)
        sub = tuple(range(len(r)))
        cols, x = prob.solve(sub, warn=True)
        if choice is not None:
            choice["chosen"] = [float(v) for v in r]
            choice["shape_refined"] = True
            choice["note"] = ("the thresholds were chosen, and the reasons computed, with the "
                              "shape identified on all candidates; the shape was then refined "
                              "for the chosen operators (thresholds kept as fractions of the "
                              "largest valid one)")
        return fam, r, sub, cols, x, state0, parts, prob

    # ---------------------------------------------------------------- KP family
    def fit_kp(self):
        fam, rec = self.family, self.rec
        pairs = fam.pairs()
        template = fam.template(pairs, rec.S)
        state0, parts, rows = self._grams(template)
        const = self._constant_columns(parts, len(pairs))
        if const.size:
            # e.g. the widest kernel: after a full cycle it stays at 1/2 for good
            pairs = [p for k, p in enumerate(pairs) if k not in set(const)]
            template = fam.template(pairs, rec.S)
            state0, parts, rows = self._grams(template)
            self.notes.append(f"{const.size} kernels dropped: the input never moves them")
        names = [f"kernel {p}" for p in pairs]
        prob = self._problem(parts, rows, len(pairs), names)
        n_ops = len(pairs)
        P = fam.penalty(pairs)
        g = prob.fit
        scale = np.trace(g.G[:n_ops, :n_ops]) / max(np.trace(P), 1e-300)
        cols = list(range(len(prob.lower)))
        tried = []

        def solve(lam, warn=False, gram=None):
            gram = g if gram is None else gram
            H = gram.G.copy()
            H[:n_ops, :n_ops] += lam * scale * P
            return solve_qp(H, gram.b, lower=prob.lower, upper=prob.upper, A_eq=prob.A_eq,
                            b_eq=prob.b_eq, warn=warn, names=prob.names).x

        if rec.has_held_back:
            for lam in KP_LAMBDAS:
                x = solve(lam)
                tried.append({"lambda": float(lam), "rms": prob.judge.rms(cols, x)})
            lam = min(tried, key=lambda t: t["rms"])["lambda"]
            rule = "lowest held-back RMS"
        else:
            lam = KP_DEFAULT_LAMBDA
            rule = "default (nothing held back to choose it on)"
            self.notes.append("nothing held back: regularization strength not chosen from data")
        x = solve(lam, warn=True)
        reg = {"lambda": lam, "scale": float(scale), "rule": rule, "tried": tried,
               "kernels": len(pairs),
               "penalty": "differences of neighbouring kernels along the diagonal (same width)"}
        self._kp_solve = solve
        return self._result(fam, pairs, tuple(range(n_ops)), cols, x, state0, parts, prob,
                            None, [], regularization=reg)

    # ---------------------------------------------------------------- results
    def _result(self, fam, cand, chosen, cols, x, state0, parts, prob, choice, dropped,
                regularization=None):
        rec = self.rec
        n_fixed = fam.n_fixed
        ops = [cand[i] for i in chosen]
        n_ops = len(ops) + n_fixed
        w = x[:n_ops]
        c = (x[n_ops] if rec.fit_offset else 0.0) + rec.fixed_offset
        idx = list(chosen) + list(range(len(cand), len(cand) + n_fixed))
        state_sel = state0[idx]
        if isinstance(fam, KrasnoselskiiPokrovskii):
            # kernels with zero weight are left out of the model
            nz = np.flatnonzero(w != 0) if np.any(w != 0) else np.array([0])
            ops, w, state_sel = [ops[i] for i in nz], w[nz], state_sel[nz]
        fitted = fam.final_model(np.asarray(ops, dtype=float) if not isinstance(
            fam, KrasnoselskiiPokrovskii) else ops, w, c, state_sel, rec.lo, rec.S)
        errors = self._errors(fitted)
        judged = errors["held_back"]["rms"] if rec.has_held_back else errors["fit"]["rms"]
        return {
            "family": fam.name, "title": fam.title, "fam": fam, "model": fitted,
            "operators": ops, "cand": cand, "chosen": chosen, "prob": prob, "state0": state0,
            "parts": parts, "n_operators": len(ops), "weights": w, "offset": float(c),
            "errors": errors, "judged_rms": judged, "choice": choice,
            "dropped": dropped, "regularization": regularization, "notes": list(self.notes),
            "n_params": int(np.count_nonzero(w)) + int(rec.fit_offset),
        }

    def _errors(self, model):
        rec = self.rec
        # the model's initial state is the state the record was processed from
        y_hat = model.predict(rec.u)
        out = {}
        for role in ("fit", "held_back"):
            i = rec.layout.indices(role)
            out[role] = (error_summary(rec.y[i], y_hat[i], rec.measured_range)
                         if i.size else None)
        return out


def _restrict(gram, keep):
    return Gram(gram.G[np.ix_(keep, keep)], gram.b[keep], gram.dd, gram.n)


def _reach_limit(fam, S):
    return fam.max_threshold(S)


def _fmt_list(values):
    return ", ".join(f"{v:g}" for v in values)


def _reason(r, cand, base, judged_on):
    where = "held-back" if judged_on == "held_back" else "fitted"
    thr = float(cand[r["index"]])
    text = (f"r = {thr:.4g}: without it the {where} RMS rises from {base:.4g} to "
            f"{r['rms_without']:.4g} (+{r['increase_without']:.4g})")
    repl = r["best_replacement_index"]
    if repl is not None:
        text += (f"; the best replacement, r = {float(cand[repl]):.4g}, gives "
                 f"{r['rms_with_replacement']:.4g}")
    return {"threshold": thr, "rms_without": r["rms_without"],
            "increase_without": r["increase_without"],
            "best_replacement": None if repl is None else float(cand[repl]),
            "rms_with_replacement": r["rms_with_replacement"], "text": text}
