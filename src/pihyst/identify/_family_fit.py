"""Fitting one family to a record: the record in the fitting frame (:class:`FramedRecord`)
and the fit of one family's weights, thresholds or regularization (:class:`FamilyFitter`,
whose methods the families call; the multislope shape search is in ``_shape``).
:func:`pihyst.identify.fit` runs it for every family.

Equations: the normal equations of ``_gram``, the QP of ``_qp``, the subset search of
``_subsets``; the frames of ``_families`` (docs/theory/identification.md).
"""

import copy
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from pihyst.exceptions import FitError, InfeasibleConstraintsError
from pihyst.identify._assess import minor_loops_determined
from pihyst.identify._constants import (
    CONSTANT_COLUMN,
    KP_UNDETERMINED_TOLERANCE,
    SETTLE_MAX_SHARE,
)
from pihyst.identify._cycles import (
    MIN_SAMPLES,
    checked_signals,
    layout,
    settling_end,
    starts_at_rest,
)
from pihyst.identify._family_result import FamilyFit
from pihyst.identify._gram import Gram, accumulate
from pihyst.identify._kernel_product import product_density_fit
from pihyst.identify._kernel_pruning import kernel_probes, prune_kernels
from pihyst.identify._qp import solve_qp
from pihyst.identify._responses import Responses
from pihyst.identify._subsets import (
    DEFAULT_MAX_EXHAUSTIVE,
    PATH_MAX_EXHAUSTIVE,
    SubsetProblem,
    choose_size,
)
from pihyst.metrics import error_summary

INITIAL_STATES = ("auto", "cycled", "settle", "zero", "rise", "fall")
KP_LAMBDAS = 10.0 ** np.arange(-6, 4)
KP_DEFAULT_LAMBDA = 1e-2
PREDICTIONS_KEPT = 8
KERNEL_SAMPLES = 100_000


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
                if mode == "settle" and settling_end(self.v, self.S) > \
                        SETTLE_MAX_SHARE * self.v.size:
                    # settling would leave little or nothing to fit
                    mode = "rise"
        else:
            mode = "explicit"
            try:
                self.explicit_state = np.asarray(initial_state, dtype=float)
            except (TypeError, ValueError):
                raise FitError("initial_state must be 'auto', 'cycled', 'settle', 'zero', "
                               "'rise', 'fall' or a list of numbers") from None
            if self.explicit_state.ndim != 1 or not np.all(np.isfinite(self.explicit_state)):
                raise FitError("initial_state must be a flat list of finite numbers")
        self.state_mode = mode
        # "auto" resolved to "cycled" or "zero" by identify/_start_state.py: what it compared
        self.state_choice = None
        self.layout = layout(self.v, self.S, settle=(mode == "settle"), holdout=holdout)
        self.has_held_back = self.layout.count("held_back") > 0
        self.through = self._through_indices(through)

    def with_start_choice(self, choice):
        """This record with what "auto" compared to choose its start state
        (identify/_start_state.py)."""
        out = copy.copy(self)
        out.state_choice = choice
        return out

    def shifted(self, delay, stop=None):
        """This record with its output ``delay`` samples later (u[k] paired with
        y[k + delay]), cut at sample ``stop``: the same cycles (the layout follows the
        input), the last ones shortened. A FitError if nothing is left to fit."""
        n = self.u.size - delay if stop is None else min(stop, self.u.size - delay)
        if n < MIN_SAMPLES:
            raise FitError(f"a delay of {delay} samples is too large for a record of "
                           f"{self.u.size} samples: too little is left to fit")
        out = copy.copy(self)
        out.u, out.v = self.u[:n], self.v[:n]
        out.y = self.y[delay:delay + n]
        out.d = out.y - self.fixed_offset
        out.measured_range = float(np.ptp(out.y))
        lay = self.layout
        kept = [((a, min(z, n), r), k) for (a, z, r), k in zip(lay.segments, lay.kinds)
                if a < n]
        # the turning points and the settling sweep past the cut are not in this record
        out.layout = replace(lay, segments=[s for s, _ in kept], kinds=[k for _, k in kept],
                             settle_end=min(lay.settle_end, n),
                             points=None if lay.points is None else
                             [p for p in lay.points if p[0] < n])
        out.has_held_back = out.layout.count("held_back") > 0
        if out.layout.count("fit") < MIN_SAMPLES:
            raise FitError(f"a delay of {delay} samples is too large for a record of "
                           f"{self.u.size} samples: too little is left to fit")
        late = [i for i in self.through if i >= n]
        if late:
            raise FitError(f"through: sample {late[0]} is beyond the record once the output "
                           f"is delayed by {delay} samples")
        return out

    def subsampled(self, max_samples):
        """This record on at most about ``max_samples`` samples plus every local extremum
        of the input, or itself if it is that short. The operators are rate-independent:
        their outputs at the kept samples depend only on the input's extrema before them,
        which are all kept, so they are exactly those of the full record; only the sums
        of squares are taken over fewer samples. For searches that need many passes
        (the multislope shape), with one full pass at the end."""
        keep = self.sample_indices(max_samples)
        return self if keep is None else self.taken(keep)

    def sample_indices(self, max_samples):
        """The samples :meth:`subsampled` keeps (None: all of them)."""
        n = self.u.size
        step = int(np.ceil(n / max_samples))
        if step <= 1:
            return None
        dv = np.diff(self.v)
        turns = np.flatnonzero(dv[1:] * dv[:-1] <= 0) + 1       # local extrema, plateaus
        bounds = [a for a, z, r in self.layout.segments] + [n - 1]
        keep = np.unique(np.concatenate([np.arange(0, n, step), turns, bounds,
                                         np.asarray(self.through, dtype=int)]))
        return None if keep.size > n // 2 else keep

    def taken(self, keep, delay=0):
        """This record at the samples ``keep`` (sorted indices, every input extremum
        among them), the output ``delay`` samples later: u[keep] with y[keep + delay]
        (those beyond the record dropped)."""
        n = self.y.size - delay
        keep = keep[keep < n]
        out = copy.copy(self)
        out.kept = keep
        out.u, out.v = self.u[keep], self.v[keep]
        out.y = self.y[keep + delay]
        out.d = out.y - self.fixed_offset
        if delay:
            out.measured_range = float(np.ptp(out.y))
        at = np.searchsorted(keep, [a for a, z, r in self.layout.segments] + [n])
        kept = [((int(a), int(z), r), k) for (_, _, r), k, a, z in
                zip(self.layout.segments, self.layout.kinds, at[:-1], at[1:]) if z > a]
        out.layout = replace(
            self.layout, settle_end=int(np.searchsorted(keep, self.layout.settle_end)),
            segments=[s for s, _ in kept], kinds=[k for _, k in kept], points=None)
        out.has_held_back = out.layout.count("held_back") > 0
        out.through = [int(np.searchsorted(keep, i)) for i in self.through if i < n]
        return out

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
        if self.state_mode in ("rise", "fall"):
            return moved_state(template, self.S, self.v[0], self.state_mode)
        return cycled_state(template, self.S)


def cycled_state(model: Any, S: float) -> NDArray[np.float64]:
    """Operator state at rest at the bottom of the range after a full bottom -> top ->
    bottom cycle (docs/interfaces.md), for a model of v on [0, S].

    For a monotone sweep the operator output at its end only depends on its end points,
    so three samples are exact.

    Parameters
    ----------
    model : PIModel
        A PI model of the input v on [0, S].
    S : float
        The top of its input range.

    Returns
    -------
    ndarray
        One output per operator.

    Examples
    --------
    >>> from pihyst.model import ClassicalPI
    >>> cycled_state(ClassicalPI([0, 20], [1.0, 1.0], input_range=(0, 100)), 100).tolist()
    [0.0, 20.0]
    """
    return model.simulate(np.array([0.0, S, 0.0])).final_state


def moved_state(model, S, v0, how):
    """Operator state at rest at ``v0`` reached from the cycled rest state at the bottom
    by a monotone rise (``how="rise"``), or from rest at the top after a full cycle by a
    monotone fall (``"fall"``): how a record that starts inside the range (an actuator
    brought to a bias voltage) starts, when its first full sweep comes too late to settle
    the operators (identify/_start_state.py)."""
    path = [0.0, S, 0.0, v0] if how == "rise" else [0.0, S, v0]
    return model.simulate(np.array(path, dtype=float)).final_state


class FamilyFitter:
    """Fits families to one record with the options common to all families; each
    family's :meth:`~pihyst.identify._families.Family.fit` calls :meth:`fit_subsets` or
    :meth:`fit_kernels`, which return a :class:`FamilyFit`."""

    def __init__(self, rec, *, thresholds=None, candidates=None, n_candidates=16,
                 n_operators=None, nonnegative=True, bounds=None,
                 max_exhaustive=DEFAULT_MAX_EXHAUSTIVE, responses=None):
        self.rec = rec
        # output-independent results shared by the fits of this record's input
        self.responses = Responses() if responses is None else responses
        self.thresholds = None if thresholds is None else np.sort(np.asarray(thresholds, float))
        self.candidates = None if candidates is None else np.sort(np.asarray(candidates, float))
        self.n_candidates, self.n_operators = n_candidates, n_operators
        self.nonnegative, self.bounds = nonnegative, bounds
        self.max_exhaustive = max_exhaustive
        self.notes = []
        self._predictions = []

    def subsampled(self, max_samples, note=None):
        """This fitter on the record subsampled to about ``max_samples`` samples and
        every input extremum (``FramedRecord.subsampled``: exact operator outputs, fewer
        squares summed), or itself for a record that short; the note says so (``note``:
        its text from the samples kept and the samples there were, default: fitted on
        those, errors on all)."""
        rec = self.rec.subsampled(max_samples)
        if rec is self.rec:
            return self
        out = copy.copy(self)
        out.rec, out._predictions = rec, []
        if note is None:
            self.note(f"fitted on {rec.u.size} of {self.rec.u.size} samples (evenly spaced, "
                      f"and every input extremum); errors on all")
        else:
            self.note(note(rec.u.size, self.rec.u.size))
        return out

    def windowed(self, stop, note):
        """This fitter on the record's first ``stop`` samples (whole cycles: a stop at a
        cycle's end), with the note ``note(kept, n)``."""
        out = copy.copy(self)
        out.rec, out._predictions = self.rec.shifted(0, stop), []
        self.note(note(out.rec.u.size, self.rec.u.size))
        return out

    def note(self, text):
        """Adds ``text`` to the notes of the family being fitted (once)."""
        if text not in self.notes:
            self.notes.append(text)

    def fit(self, family, rival_rms=None):
        """``family`` fitted to the record (notes collected afresh); ``rival_rms``, the
        lowest judged RMS of the families fitted before it, lets a family with an
        expensive search stop early where it cannot come near (Bouc-Wen)."""
        self.notes = []
        return family.fit(self, rival_rms)

    # ---------------------------------------------------------------- columns
    def grams(self, family, template, roles=("fit", "held_back")):
        """Initial state, normal equations per role, and the rows of the ``through``
        samples, of ``template``'s operators over the record."""
        rec = self.rec
        state0 = rec.start_state(family, template)
        segments = [(a, z, r if r in roles or r == "settle" else "settle")
                    for a, z, r in rec.layout.segments]
        parts, rows = accumulate(template, rec.v, rec.d, segments, state0, offset=True,
                                 rows_at=rec.through)
        return state0, parts, rows

    def _bounds(self, family, n_ops):
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
                                   f"({n_ops} for {family.name} here), got {value.size}")
                (lo if k == 0 else hi)[:] = value
        return lo, hi

    def problem(self, family, parts, rows, n_cand, names):
        """SubsetProblem over columns [candidates..., fixed operators..., offset]."""
        rec = self.rec
        m = parts["fit"].G.shape[0]
        keep = list(range(m)) if rec.fit_offset else list(range(m - 1))
        fit = _restrict(parts["fit"], keep)
        judge = _restrict(parts["held_back"], keep) if rec.has_held_back else fit
        lo, hi = self._bounds(family, m - 1)
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
    def fit_subsets(self, family):
        """Thresholds chosen by subset search (or given), weights by QP."""
        rec = self.rec
        fam = family.prepare(self)
        explicit = self.thresholds is not None
        if explicit or self.candidates is not None:
            cand = self.thresholds if explicit else self.candidates
            self._check_thresholds(fam, cand)
        else:
            cand = fam.candidates(rec.S, self.n_candidates)
        template = fam.template(cand, rec.S)
        state0, parts, rows = self.grams(fam, template)
        const = self._constant_columns(parts, len(cand))
        if const.size and explicit:
            r = cand[const[0]]
            # the fitted cycles' own span: after a settling sweep, or with alternate
            # cycles held back, it can be far less than the record's
            fitted = rec.v[rec.layout.indices("fit")]
            span = float(np.ptp(fitted)) if fitted.size else 0.0
            raise FitError(f"{fam.name}: the fitted cycles never move the operator of "
                           f"threshold {r:g} (their input spans {span:g} of the range "
                           f"{rec.S:g}): its output is constant, so its weight is "
                           f"undetermined; use thresholds below "
                           f"{min(fam.max_threshold(rec.S), 0.5 * span):g}", column="input")
        if const.size:
            dropped = [float(cand[i]) for i in const]
            cand = np.delete(cand, const)
            template = fam.template(cand, rec.S)
            state0, parts, rows = self.grams(fam, template)
            self.note(f"candidate thresholds {_fmt_list(dropped)} dropped: the input "
                              f"never moves their operators")
        names = [f"r={r:g}" for r in cand] + [f"input segment {j}" for j in range(fam.n_fixed)]
        prob = self.problem(fam, parts, rows, len(cand), names)
        if explicit:
            chosen, choice = tuple(range(len(cand))), None
        else:
            chosen, choice = self._choose(fam, prob, cand)
        _, x = prob.solve(chosen, warn=True)
        if x is None:
            raise InfeasibleConstraintsError(f"{fam.name}: no weights satisfy the constraints")
        fitted = self.subset_result(fam, cand, chosen, x, state0, prob, choice)
        return fam.refine(self, fitted)

    def subset_result(self, fam, cand, chosen, x, state0, prob, choice):
        """FamilyFit of the subset ``chosen`` of the candidates ``cand``, weights ``x``."""
        def refit():
            both = _both(prob)
            joint = SubsetProblem(fit=both, judge=both, n_candidates=prob.n_candidates,
                                  lower=prob.lower, upper=prob.upper, A_eq=prob.A_eq,
                                  b_eq=prob.b_eq, names=prob.names)
            _, x_all = joint.solve(chosen, warn=True)
            return self._model(fam, cand, chosen, x_all, state0)[0]

        model, ops, w, c = self._model(fam, cand, chosen, x, state0)
        return self._fit_result(fam, model, ops, w, c, refit, threshold_choice=choice)

    def _check_thresholds(self, fam, r):
        if r.size == 0:
            raise FitError("thresholds is empty")
        if np.any(r < 0) or np.any(np.diff(r) <= 0):
            raise FitError("thresholds must be >= 0 and distinct")
        fam.check_thresholds(r, self.rec.S)

    def _choose(self, fam, prob, cand):
        K = len(cand)
        if self.n_operators is not None:
            if not 1 <= self.n_operators <= K:
                raise FitError(f"{fam.name}: cannot choose {self.n_operators} operators "
                               f"from {K} candidate thresholds")
            best = prob.best_of_size(self.n_operators, self.max_exhaustive)
            if not np.isfinite(best.rms):
                raise InfeasibleConstraintsError(f"{fam.name}: no {self.n_operators} "
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

    # ---------------------------------------------------------------- kernel families
    def fit_kernels(self, fam):
        """All kernels of the family's grid, regularized by ``fam.penalty``; the strength
        chosen on the held-back cycles. A record without minor loops gets the mean of
        that density and the product-form one (:mod:`pihyst.identify._kernel_product`):
        measured on 47 random Preisach actuators recorded on a two-cycle triangle, ramps
        and staircases 0.16 / 0.30 / 0.41 % of range (median / p95 / max), against
        0.18 / 0.57 / 0.67 % with the penalty's density alone."""
        if self.thresholds is not None or self.candidates is not None or \
                self.n_operators is not None:
            raise FitError(f"{fam.name}: has no thresholds (a grid of kernels, regularized); "
                           f"drop thresholds/candidates/n_operators")
        rec = self.rec
        # a Gram pass costs (kernels)^2 per sample: long records are subsampled
        on = self.subsampled(KERNEL_SAMPLES)
        pairs = fam.pairs()
        template = fam.template(pairs, rec.S)
        state0, parts, rows = on.grams(fam, template)
        const = self._constant_columns(parts, len(pairs))
        if const.size:
            # e.g. the widest kernel: after a full cycle it stays at 1/2 for good; the
            # kept kernels' normal equations are those rows and columns of the grid's
            kept = [k for k in range(len(pairs)) if k not in set(const)]
            state0, parts, rows = _kept_columns(kept, len(pairs), state0, parts, rows)
            pairs = [pairs[k] for k in kept]
            template = fam.template(pairs, rec.S)
            self.note(f"{const.size} kernel{'s' if const.size > 1 else ''} dropped: "
                              f"the input never moves {'them' if const.size > 1 else 'it'}")
        names = [f"kernel {p}" for p in pairs]
        prob = on.problem(fam, parts, rows, len(pairs), names)
        n_ops = len(pairs)
        cols = list(range(len(prob.lower)))
        chosen = tuple(range(n_ops))
        trace = np.trace(prob.fit.G[:n_ops, :n_ops])
        # a record without minor loops leaves the density's spread over the plane open:
        # the first penalty shape is the prior; with minor loops in the fitted and the
        # held-back cycles, those choose the shape as they choose the strength
        open_loops = rec.has_held_back and not minor_loops_determined(rec, None)[0]
        shapes = list(fam.PENALTIES)
        if open_loops or not rec.has_held_back:
            shapes = shapes[:1]
        scales, penalties = {}, {}
        for shape in shapes:
            P = fam.penalty(pairs, shape)
            scales[shape] = float(trace / max(np.trace(P), 1e-300))
            penalties[shape] = scales[shape] * P

        def solve(shape, lam, gram, product=None, warn=False):
            H = gram.G.copy()
            H[:n_ops, :n_ops] += lam * penalties[shape]
            x = solve_qp(H, gram.b, lower=prob.lower, upper=prob.upper, A_eq=prob.A_eq,
                         b_eq=prob.b_eq, warn=warn, names=prob.names).x
            return x if product is None else 0.5 * (x + product)

        def product_of(gram):
            if not open_loops:
                return None
            return product_density_fit(gram, pairs, fam.grid, prob.lower, prob.upper,
                                       A_eq=prob.A_eq, b_eq=prob.b_eq)

        product = product_of(prob.fit)
        tried = []
        shape = shapes[0]
        if rec.has_held_back:
            for sh in shapes:
                for lam in KP_LAMBDAS:
                    rms = prob.judge.rms(cols, solve(sh, lam, prob.fit, product))
                    tried.append({"penalty": sh, "lambda": float(lam), "rms": rms})
            shape, lam, rule = _kernel_lambda(tried, not open_loops)
        else:
            lam = KP_DEFAULT_LAMBDA
            rule = "default (nothing held back to choose it on)"
            self.note("nothing held back: regularization strength not chosen from data")
        probes = kernel_probes(self.responses, template, fam.grid, rec.S, rec.fit_offset)
        x = solve(shape, lam, prob.fit, product, warn=True)
        reference = prob.judge.rms(cols, x)
        x, pruning = prune_kernels(x, n_ops, prob.fit, prob.judge, probes, prob,
                                   reference)
        reg = {"lambda": lam, "scale": scales[shape], "rule": rule, "tried": tried,
               "kernels": len(pairs), "pruning": pruning,
               "penalty": fam.PENALTIES[shape], "penalty_shape": shape,
               "product_density": None if not open_loops else {
                   "held_back_rms": None if product is None else prob.judge.rms(cols,
                                                                                product),
                   "rule": "minor loops not in the record: the mean of the penalty's "
                           "density and the product-form one" if product is not None else
                           "minor loops not in the record, but no product-form density "
                           "meets the equality constraints: the penalty's density alone"}}

        def refit():
            both = _both(prob)
            x_all = prune_kernels(solve(shape, lam, both, product_of(both), warn=True),
                                  n_ops, both, both, probes, prob, reference)[0]
            return self._model(fam, pairs, chosen, x_all, state0)[0]

        model, ops, w, c = self._model(fam, pairs, chosen, x, state0)
        return self._fit_result(fam, model, ops, w, c, refit, regularization=reg)

    # ---------------------------------------------------------------- results
    def _model(self, fam, cand, chosen, x, state0):
        """The raw-frame model of weights x over columns [chosen..., fixed..., offset]:
        (model, operators, weights, offset). Operators with zero weight are left out of
        a kernel model (they are many, and cost time in a compensator)."""
        rec = self.rec
        ops = [cand[i] for i in chosen]
        n_ops = len(ops) + fam.n_fixed
        w = x[:n_ops]
        c = (x[n_ops] if rec.fit_offset else 0.0) + rec.fixed_offset
        idx = list(chosen) + list(range(len(cand), len(cand) + fam.n_fixed))
        state = state0[idx]
        if fam.operators_key == "kernels":
            nz = np.flatnonzero(w != 0) if np.any(w != 0) else np.array([0])
            ops, w, state = [ops[i] for i in nz], w[nz], state[nz]
            model = fam.final_model(ops, w, c, state, rec.lo, rec.S)
        else:
            model = fam.final_model(np.asarray(ops, dtype=float), w, c, state, rec.lo, rec.S)
        return model, tuple(ops), w, float(c)

    def _fit_result(self, fam, model, ops, w, c, refit, **how):
        rec = self.rec
        errors = self.errors(model)
        judged = errors["held_back"]["rms"] if rec.has_held_back else errors["fit"]["rms"]
        return FamilyFit(family=fam, model=model, operators=ops, weights=w, offset=c,
                         errors=errors, judged_rms=judged,
                         n_params=int(np.count_nonzero(w)) + int(rec.fit_offset),
                         notes=tuple(self.notes), refit=refit, **how)

    def predict(self, model):
        """``model``'s prediction of the record (the last few kept: the report asks for
        the same model's several times)."""
        for m, y_hat in self._predictions:
            if m is model:
                return y_hat
        # the model's initial state is the state the record was processed from
        y_hat = model.predict(self.rec.u)
        self._predictions = [(model, y_hat)] + self._predictions[:PREDICTIONS_KEPT - 1]
        return y_hat

    def errors(self, model):
        """Error summaries of ``model`` on the fitted and the held-back samples."""
        rec = self.rec
        y_hat = self.predict(model)
        out = {}
        for role in ("fit", "held_back"):
            i = rec.layout.indices(role)
            out[role] = (error_summary(rec.y[i], y_hat[i], rec.measured_range)
                         if i.size else None)
        return out


def _both(prob):
    """Normal equations of the fitted and held-back samples together."""
    return prob.fit + prob.judge if prob.judge is not prob.fit else prob.fit


def _restrict(gram, keep):
    return Gram(gram.G[np.ix_(keep, keep)], gram.b[keep], gram.dd, gram.n)


def _kept_columns(kept, n_candidates, state0, parts, rows):
    """(state, normal equations, through rows) of the candidates ``kept`` of
    ``n_candidates``, from those of all of them (columns [candidates..., fixed
    operators..., offset], as :meth:`FamilyFitter.grams` gives them): every entry of G
    and b sums over its own two columns only, so these are the numbers a pass over the
    kept candidates alone would give, bit for bit."""
    m = parts["fit"].G.shape[0]
    columns = list(kept) + list(range(n_candidates, m))
    operators = list(kept) + list(range(n_candidates, state0.size))
    return (state0[operators], {role: _restrict(g, columns) for role, g in parts.items()},
            {i: r[columns] for i, r in rows.items()})


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


def _kernel_lambda(tried, minor_loops_known):
    """(penalty shape, lambda, rule) of a kernel basis from the held-back RMS of each
    shape and strength tried.

    A record with minor loops in both its fitted and held-back parts judges the minor
    loops: the lowest held-back RMS. One without them judges the major loop only (one
    shape is tried), and any strength that fits it leaves the interior of the Preisach
    plane to the penalty: the strongest within KP_UNDETERMINED_TOLERANCE of the lowest
    RMS is taken.
    """
    best = min(t["rms"] for t in tried)
    if minor_loops_known:
        t = min(tried, key=lambda t: t["rms"])
        return t["penalty"], t["lambda"], "lowest held-back RMS"
    near = [t for t in tried if t["rms"] <= best * (1 + KP_UNDETERMINED_TOLERANCE)]
    t = max(near, key=lambda t: t["lambda"])
    return (t["penalty"], t["lambda"],
            f"the strongest within {100 * KP_UNDETERMINED_TOLERANCE:g} % of the lowest "
            f"held-back RMS (the record has no minor loops to judge)")
