"""Best subset of candidate operators, judged on held-back data, from one Gram matrix.

The paper picked 4 of 16 equally spaced thresholds "by repeated experiments"; here every
subset S of the candidates is fitted on the fitted part of the record (a QP on the
submatrix G_fit[S, S], see :mod:`pihyst.identify._qp`) and judged by its RMS error on the
held-back part, computed from G_held[S, S] by eq. (1) of :mod:`pihyst.identify._gram` - so the
search never touches the data again. The best subset of a size is found exhaustively
when there are at most ``max_exhaustive`` subsets of that size, otherwise by greedy
forward selection followed by single swaps until no swap improves the held-back error.

Columns beyond the candidates (``fixed``: an offset, an input function) are in every
subset.
"""

import itertools
import math
from dataclasses import dataclass, field

import numpy as np
import quadprog

from pihyst.exceptions import InfeasibleConstraintsError
from pihyst.identify._constants import SIZE_TOLERANCE, STALL, TIE
from pihyst.identify._qp import DEFAULT_RCOND, solve_qp

DEFAULT_MAX_EXHAUSTIVE = 2000     # a requested size: 4 of 16 (1820 subsets) is exhaustive
PATH_MAX_EXHAUSTIVE = 600         # every size in turn: 1..3 of 16 exhaustive, then greedy
# batched subset QPs: only matrices whose condition number is below this fraction of
# solve_qp's limit (1 / DEFAULT_RCOND) take the batched path; the others get its ridge
BATCH_CONDITION_MARGIN = 1e-2


@dataclass
class SubsetChoice:
    """Best subset of one size: candidate indices, judged RMS, how it was found."""

    subset: tuple
    rms: float
    method: str
    evaluated: int


@dataclass
class SubsetProblem:
    """Constrained least squares over subsets of candidate columns.

    Parameters
    ----------
    fit, judge : pihyst.identify._gram.Gram
        Normal equations of the fitted and of the judging (held-back) samples over all
        columns: the ``n_candidates`` candidates first, then the ``fixed`` ones. ``judge``
        may be the fit itself when nothing is held back.
    n_candidates : int
    lower, upper : (m,) arrays
        Bounds of every column's weight.
    A_eq, b_eq : arrays or None
        Equality constraints over all m columns.
    names : list of str
        Column names, for messages.
    """

    fit: object
    judge: object
    n_candidates: int
    lower: np.ndarray
    upper: np.ndarray
    A_eq: np.ndarray | None = None
    b_eq: np.ndarray | None = None
    names: list | None = None
    _cache: dict = field(default_factory=dict, repr=False)
    evaluations: int = 0

    @property
    def fixed(self):
        return list(range(self.n_candidates, self.fit.G.shape[0]))

    def columns(self, subset):
        return sorted(subset) + self.fixed

    def solve(self, subset, warn=False):
        """Weights (over ``columns(subset)``) fitted on the fitted samples, or None if the
        constraints cannot be met with these columns."""
        cols = self.columns(subset)
        if not cols:
            return cols, np.zeros(0)
        A_eq = None if self.A_eq is None else self.A_eq[:, cols]
        try:
            sol = solve_qp(self.fit.G[np.ix_(cols, cols)], self.fit.b[cols],
                           lower=self.lower[cols], upper=self.upper[cols], A_eq=A_eq,
                           b_eq=self.b_eq, warn=warn,
                           names=None if self.names is None else
                           [self.names[c] for c in cols])
        except InfeasibleConstraintsError:
            if warn:
                raise
            return cols, None
        return cols, sol.x

    def score(self, subset):
        """Judged RMS error of the subset (inf if its constraints are infeasible)."""
        key = tuple(sorted(subset))
        if key not in self._cache:
            self.evaluations += 1
            cols, x = self.solve(key)
            self._cache[key] = np.inf if x is None else self.judge.rms(cols, x)
        return self._cache[key]

    def score_many(self, subsets):
        """Judged RMS of many subsets (cached like :meth:`score`), those of one size
        at a time solved together: the same QP as :func:`~pihyst.identify._qp.solve_qp`
        (variables scaled to a unit diagonal; the unconstrained minimizer when it is
        within the bounds, else quadprog), batched in NumPy. Subsets whose scaled
        matrix is not clearly well-conditioned, or with equality constraints, go
        through :meth:`score` (solve_qp's ridge and checks)."""
        keys = [k for k in dict.fromkeys(tuple(sorted(s)) for s in subsets)
                if k not in self._cache]
        if self.A_eq is not None:
            return [self.score(k) for k in subsets]
        by_size = {}
        for k in keys:
            by_size.setdefault(len(k), []).append(k)
        for group in by_size.values():
            self._batch(group)
        return [self.score(k) for k in subsets]

    def best(self, subsets):
        """The subset of ``subsets`` with the lowest judged RMS; among those within a
        relative ``TIE`` of it (equal but for rounding: the data cannot tell them apart)
        the lexicographically first, so the choice does not depend on rounding."""
        keys = [tuple(sorted(s)) for s in subsets]
        scores = self.score_many(keys)
        lowest = min(scores)
        return min(k for k, v in zip(keys, scores) if v <= lowest + TIE * abs(lowest)
                   or v == lowest)

    def _batch(self, keys):
        cols = np.array([list(k) + self.fixed for k in keys], dtype=int)
        m, p = cols.shape
        if p == 0:
            return
        G = self.fit.G[cols[:, :, None], cols[:, None, :]]
        b = self.fit.b[cols]
        diag = np.diagonal(G, axis1=1, axis2=2)
        s = np.sqrt(np.where(diag > 0, diag, 1.0))
        Hs = G / (s[:, :, None] * s[:, None, :])
        Hs = 0.5 * (Hs + np.swapaxes(Hs, 1, 2))
        gs = b / s
        sv = np.linalg.svd(Hs, compute_uv=False)
        # 1-norm condition <= p * 2-norm condition: clearly below solve_qp's threshold
        good = (sv[:, -1] > 0) & (p * sv[:, 0] < BATCH_CONDITION_MARGIN / DEFAULT_RCOND
                                  * sv[:, -1])
        idx = np.flatnonzero(good)
        if not idx.size:
            return
        x = np.linalg.solve(Hs[idx], gs[idx][:, :, None])[:, :, 0] / s[idx]
        lo, hi = self.lower[cols[idx]], self.upper[cols[idx]]
        inside = np.all((x >= lo) & (x <= hi), axis=1)
        ok = inside.copy()
        for j in np.flatnonzero(~inside):
            k = idx[j]
            has_lo, has_hi = np.isfinite(lo[j]), np.isfinite(hi[j])
            eye = np.eye(p)
            C = np.hstack([eye[:, has_lo], -eye[:, has_hi]])
            c = np.concatenate([lo[j][has_lo] * s[k][has_lo], -hi[j][has_hi] * s[k][has_hi]])
            try:
                xs = quadprog.solve_qp(Hs[k], gs[k], C, c, 0)[0]
            except ValueError:
                continue                       # left to score()
            x[j] = np.clip(xs / s[k], lo[j], hi[j])
            ok[j] = True
        # judged RMS by eq. (1) of _gram, for all at once
        Gj = self.judge.G[cols[idx][:, :, None], cols[idx][:, None, :]]
        bj = self.judge.b[cols[idx]]
        sse = self.judge.dd - 2 * np.einsum("ij,ij->i", bj, x) + np.einsum(
            "ij,ijk,ik->i", x, Gj, x)
        rms = np.sqrt(np.maximum(sse, 0.0) / self.judge.n)
        for j in np.flatnonzero(ok):
            key = keys[idx[j]]
            if key not in self._cache:
                self.evaluations += 1
                self._cache[key] = float(rms[j])

    # ------------------------------------------------------------------ search
    def best_of_size(self, size, max_exhaustive=DEFAULT_MAX_EXHAUSTIVE, start=None):
        """Best subset of ``size`` candidates (exhaustive or greedy + swaps)."""
        K = self.n_candidates
        if not 1 <= size <= K:
            raise ValueError(f"cannot choose {size} of {K} candidates")
        before = self.evaluations
        if math.comb(K, size) <= max_exhaustive:
            best = self.best(itertools.combinations(range(K), size))
            method = "exhaustive"
        else:
            best = self._swap_refine(start if start is not None else self.greedy(size))
            method = "greedy forward selection and swaps"
        return SubsetChoice(tuple(best), self.score(best), method, self.evaluations - before)

    def greedy(self, size):
        """Forward selection: add the candidate that lowers the judged error most."""
        chosen = []
        for _ in range(size):
            rest = [c for c in range(self.n_candidates) if c not in chosen]
            chosen = list(self.best([chosen + [c] for c in rest]))
        return tuple(sorted(chosen))

    def _swap_refine(self, subset):
        current = tuple(sorted(subset))
        best = self.score(current)
        while True:
            swaps = [tuple(sorted(set(current) - {out} | {new}))
                     for out in current for new in range(self.n_candidates)
                     if new not in current]
            if not swaps:
                return current
            cand = self.best(swaps)
            if self.score(cand) >= best * (1 - 1e-12):
                return current
            current, best = cand, self.score(cand)

    def path(self, max_exhaustive=PATH_MAX_EXHAUSTIVE, sizes=None, patience=3):
        """Best subset of every size in ``sizes`` (default 1..K).

        Without explicit ``sizes`` the path stops once ``patience`` sizes in a row have
        each lowered the judged RMS by less than ``STALL`` (relative): larger sets then
        cannot matter to :func:`choose_size`, which keeps the smallest set within
        ``SIZE_TOLERANCE`` of the best.
        """
        stop_early = sizes is None
        sizes = range(1, self.n_candidates + 1) if sizes is None else sizes
        out = []
        greedy = []
        stalled = 0
        for size in sizes:
            # Greedy path: extend the previous greedy set by one, then refine by swaps.
            rest = [c for c in range(self.n_candidates) if c not in greedy]
            if len(greedy) < size and rest:
                greedy = sorted(self.best([greedy + [c] for c in rest]))
            out.append(self.best_of_size(size, max_exhaustive, start=tuple(greedy)))
            if len(out) > 1 and np.isfinite(out[-2].rms):
                stalled = stalled + 1 if out[-1].rms > out[-2].rms * (1 - STALL) else 0
                if stop_early and stalled >= patience:
                    break
        return out

    def reasons(self, subset):
        """Why each member of ``subset`` is there: the judged RMS without it, and with
        the best replacement from the other candidates."""
        subset = tuple(sorted(subset))
        base = self.score(subset)
        out = []
        for c in subset:
            rest = [i for i in subset if i != c]
            without = self.score(rest) if rest or self.fixed else self._zero_rms()
            others = [i for i in range(self.n_candidates) if i not in subset]
            repl = None
            if others:
                added = set(self.best([rest + [i] for i in others])) - set(rest)
                repl = added.pop()
            out.append({
                "index": c,
                "rms_without": without,
                "increase_without": without - base,
                "best_replacement_index": repl,
                "rms_with_replacement": None if repl is None else self.score(rest + [repl]),
            })
        return out

    def _zero_rms(self):
        return float(np.sqrt(self.judge.dd / self.judge.n))


def choose_size(path):
    """Pick a size from a :meth:`SubsetProblem.path`: the smallest subset whose judged RMS
    is within ``SIZE_TOLERANCE`` (1 %) of the lowest. (An information criterion such as
    BIC would trust every sample as independent; the residuals of a hysteresis fit are
    dominated by smooth model error, so it keeps adding operators.)"""
    finite = [c for c in path if np.isfinite(c.rms)]
    if not finite:
        raise InfeasibleConstraintsError("no subset of the candidate operators satisfies the "
                                         "constraints")
    best = min(c.rms for c in finite)
    return next(c for c in finite if c.rms <= best * (1 + SIZE_TOLERANCE))
