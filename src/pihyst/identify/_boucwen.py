"""Identification of the Bouc-Wen model (docs/theory/bouc-wen.md).

For a fixed shape (beta, gamma, n) the Bouc-Wen variable z[t] is a known function of the
input, and the output

    y = offset + c_1 x + c_2 x^2 + a z

is linear in (offset, c_1, c_2, a). Monotonicity on every reachable state,
min(c_1, c_1 + 2 c_2) + min(a, 0) D >= 0 with D = 2 beta / (beta + gamma), becomes plain
bounds in two cases, each a non-negative least-squares problem with a free offset:

- a >= 0:  c_1 = q_0, c_1 + 2 c_2 = q_1, a = p,                  q_0, q_1, p >= 0;
- a <= 0:  c_1 = q_0 + p D, c_1 + 2 c_2 = q_1 + p D, a = -p,      q_0, q_1, p >= 0.

The offset is eliminated by centring (the exact minimizer over it), and each 3-variable
problem is solved exactly on its 3 x 3 Gram matrix by trying every active set (the best
feasible stationary point of a convex QP is its minimum). The shape is the outer search:
a grid of shapes run all at once (NumPy over the shapes, one pass over the record,
decimated but keeping every reversal), then a Nelder-Mead refinement of (log beta,
atanh(gamma / beta), n) from the best grid point on the fitted samples. The record is
cut into settle/fit/held-back cycles as for the PI families (:mod:`._cycles`); the
held-back RMS is what the choice between families compares.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from pihyst.exceptions import FitError
from pihyst.identify._constants import REFINE_REACH
from pihyst.identify._cycles import checked_signals, layout, starts_at_rest
from pihyst.identify._responses import Responses, digest
from pihyst.model._boucwen import (
    MAX_EXPONENT,
    MAX_SHAPE,
    MIN_SPREAD,
    BoucWenModel,
    cycled_z,
    trajectory,
)

#: The shape grid of the outer search (normalized input): beta, gamma / beta, n.
GRID_BETA = tuple(np.geomspace(0.5, 60.0, 12).tolist())
GRID_RATIO = (-0.8, -0.5, -0.25, 0.0, 0.25, 0.5, 0.8)
GRID_N = (1.0, 1.5, 2.0, 3.0)
SEARCH_SAMPLES = 600    # the shape search runs on about this many samples (+ reversals)
# ... and on the record's first SEARCH_PATH ranges of input travel (3 full cycles of a
# triangle): z is integrated in substeps of the input's travel, so the search's cost
# grows with the path, not the samples; a longer record's later cycles repeat what the
# first ones show (the P-885 identification record: 40 cycles, 80 ranges; the shape
# found on its first 6 holds back 0.212 um on all 20 held-back cycles, the search on
# all 40 0.210 um, in a third of the time). The linear parameters are fitted on the
# whole record; fewer than MIN_SEARCH_FITTED fitted samples there: twice the path.
SEARCH_PATH = 6.0
# Nelder-Mead's stop: (log beta, atanh(gamma/beta), n) within SEARCH_XATOL, the fitted
# RMS within SEARCH_FATOL of the output's span, or SEARCH_EVALUATIONS evaluations. On
# 7 records (P-885, two simulated beams, four random actuators) 1e-3 / 1e-6 / 100 held
# back within 0.3 % of 1e-4 / 1e-7 / 200, in half the evaluations
SEARCH_XATOL = 1e-3
SEARCH_FATOL = 1e-6
SEARCH_EVALUATIONS = 100
MIN_SEARCH_FITTED = 100
# How sharp a shape the search may try: the model integrates z in substeps of
# 1/(32 (beta + |gamma|)) of the range (model._boucwen.substep), so its cost, in the fit
# and in every compensator step, grows with beta + |gamma|. Beyond 200 (for n = 1: z
# saturating within 0.5 % of the range after a reversal, a corner no piezo actuator's
# loop has) only searches on records of other hysteresis go (measured: 500 on a
# Preisach beam, 70 s per fit); the sharpest shape identified on the simulated
# Bouc-Wen beams has 150 (n = 3.5, docs/theory/bouc-wen.md)
MAX_SHARPNESS = 200.0


def searched_shape(p, n=None):
    """(beta, gamma, n) of a point p = (log beta, atanh(gamma / beta), n) of the shape
    search (``n`` fixes the exponent), or None where a model would refuse it.

    beta + |gamma| is capped at MAX_SHARPNESS (flat beyond: an inf stalls Nelder-Mead);
    tanh rounds to exactly +-1 beyond |p[1]| of about 19, where gamma = +-beta gives
    unbounded loops (beta > |gamma| fails) or no bound of z (beta + gamma < MIN_SPREAD)."""
    ratio = float(np.tanh(p[1]))
    nn = float(np.clip(p[2], 1.0, MAX_EXPONENT)) if n is None else float(n)
    beta = min(float(np.exp(min(p[0], 50.0))), MAX_SHARPNESS / (1.0 + abs(ratio)))
    gamma = beta * ratio
    if not (abs(gamma) < beta and beta + abs(gamma) <= MAX_SHAPE
            and beta + gamma >= MIN_SPREAD):
        return None
    return beta, gamma, nn


def first_reversal(v):
    """Index of the first sample after the input's first change of direction (v.size if
    it never turns): the end of the first sweep."""
    d = np.diff(v)
    moving = np.flatnonzero(d != 0)
    if moving.size == 0:
        return v.size
    turns = np.flatnonzero(np.sign(d[moving]) != np.sign(d[moving[0]]))
    return int(moving[turns[0]]) + 1 if turns.size else v.size


# the family in fit()'s comparison runs on at most this many samples plus every input
# extremum: z at a kept sample depends only on the extrema before it (rate-independent),
# so the kept samples' errors are exact; each sample costs a few microseconds in Python
FAMILY_SAMPLES = 20_000
# ... and on its first cycles within this many ranges of input travel: z is integrated
# in substeps of the travel, so a model's every pass costs in proportion to it (a 10^6-
# sample record of level ramps travels 1,700 ranges: 0.9 s per prediction of a shape
# there, 4 s per fit). Every record the population and the measured sets judge the fit
# on travels at most 100 ranges (P-885 80, SmartHysteresis 69, the population 6) and is
# fitted whole; the cut keeps fitted and held-back cycles (else the whole record).
FAMILY_TRAVEL = 200.0


def _nnls(X, y):
    """min |X v - y| over v >= 0 (a few columns): Lawson-Hanson (scipy.optimize.nnls) on
    the columns scaled to unit norm (a zero column keeps v = 0)."""
    from scipy.optimize import nnls  # lazy, like every SciPy import of pihyst.identify

    norm = np.sqrt(np.einsum("ij,ij->j", X, X))
    scale = np.where(norm > 0, 1.0 / np.where(norm > 0, norm, 1.0), 0.0)
    return nnls(X * scale, y)[0] * scale


def boucwen_columns(x, z, d, negative):
    """Regressors of (q_0, q_1, p) for one case (module notes): y - offset = X @ v."""
    # c_1 x + c_2 x^2 = q_0 (x - x^2 / 2) + q_1 x^2 / 2 (+ p D x for the a <= 0 case)
    base0, base1 = x - 0.5 * x * x, 0.5 * x * x
    hyst = d * x - z if negative else z
    return np.stack([base0, base1, hyst], axis=-1)


def _solve_linear(x, z, y, d, s=None):
    """((offset, c_1, c_2, a), b) of the best monotone fit y = offset + c_1 x + c_2 x^2
    + a z + b s for a fixed z; ``s`` (optional, else b = 0) is a free column: the
    sensitivity of z to its unknown starting value (:func:`start_sensitivity`).

    The free columns (the constant, and s) are eliminated exactly: X and y are replaced
    by their residuals after least squares on [1, s], the bounded problem is solved on
    those, and (offset, b) are the least squares of what remains."""
    F = np.ones((x.size, 1)) if s is None else np.column_stack([np.ones(x.size), s])
    pinv = np.linalg.pinv(F)

    def free_part(A):
        return A - F @ (pinv @ A)

    best = None
    for negative in (False, True):
        X = boucwen_columns(x, z, d, negative)
        Xc, yc = free_part(X), free_part(y)
        v = _nnls(Xc, yc)
        rss = float(np.sum((yc - Xc @ v) ** 2))
        if best is None or rss < best[0]:
            f = pinv @ (y - X @ v)
            best = (rss, (float(f[0]), *boucwen_coefficients(v, d, negative)),
                    0.0 if s is None else float(f[1]))
    return best[1], best[2]


def start_sensitivity(x, x0, z0, z, beta, gamma, n):
    """s[t] = dz[t] / dz0: how z along the input x follows a change of its starting value
    z0. A record assumed to start at rest after a full cycle rarely does exactly (a
    partial cycle before it, a supply switched on): the fit then takes z0 + b/a as the
    start, the linear column b s(t), which fades as the input sweeps the range (measured
    on random Bouc-Wen actuators after a partial cycle to 20-50 % of the range: 2-3 % of
    range on ramps and staircases without it).

    Between two samples the input moves one way (s = +-1) and dz/dx = g_s(z), an
    autonomous equation, whose variational solution is exact:

        dz(x_t) / dz(x_{t-1}) = g_s(z_t) / g_s(z_{t-1}),

    so s[t] is the running product of these ratios along the computed z (each ratio in
    [0, 1]: a monotone sweep only draws z towards its bound)."""
    x = np.asarray(x, dtype=float)
    xp = np.r_[x0, x[:-1]]
    zp = np.r_[z0, z[:-1]]
    step = np.sign(x - xp)

    def g(zz):
        return 1.0 - np.abs(zz) ** n * (step * beta * np.sign(zz) + gamma)

    before, after = g(zp), g(z)
    ratio = np.where(step == 0, 1.0,
                     np.clip(after / np.where(before > 0, before, np.inf), 0.0, 1.0))
    return np.cumprod(ratio)


def boucwen_coefficients(v, d, negative):
    """(c_1, c_2, a) from the bounded variables v = (q_0, q_1, p) of one case (module
    notes): c_1 = q_0 (+ p D), c_1 + 2 c_2 = q_1 (+ p D), a = p (or -p)."""
    q0, q1, p = (float(e) for e in v)
    c1 = q0 + p * d if negative else q0
    c2 = 0.5 * (q1 - q0)
    return c1, c2, (-p if negative else p)


@dataclass(frozen=True)
class BoucWenReport:
    """What :func:`fit_boucwen` did: errors on the fitted and held-back samples, the shape
    search and the data layout. ``str(report)`` is a readable summary."""

    chosen: str
    errors: dict
    final_errors: dict
    search: dict
    data: dict
    families: list = field(default_factory=list)

    def family(self, name):
        for f in self.families:
            if f["family"] == name:
                return f
        raise KeyError(name)

    def to_dict(self):
        return {"chosen": self.chosen, "errors": self.errors,
                "final_errors": self.final_errors, "search": self.search,
                "data": self.data, "families": self.families}

    def __str__(self):
        e = self.errors
        lines = [f"Bouc-Wen fit: {self.search['summary']}",
                 f"  fitted samples {self.data['fit_samples']}, held back "
                 f"{self.data['held_back_samples']}, settle {self.data['settle_samples']}",
                 f"  RMS error: fitted {e['fit']['rms']:.4g}, held back "
                 + (f"{e['held_back']['rms']:.4g}" if e.get("held_back") else "-")]
        return "\n".join(lines)


def _errors(r):
    return {"rms": float(np.sqrt(np.mean(r * r))), "mean_abs": float(np.mean(np.abs(r))),
            "max_abs": float(np.max(np.abs(r)))} if r.size else None


def _keep(u, target, path=None):
    """Sample indices to search on: every k-th sample plus every reversal (a skipped
    reversal would change the hysteresis memory), and the last; with ``path``, only the
    first samples whose input travel (cumulative |du|, in ranges) is within it."""
    if path is not None:
        travel = np.r_[0.0, np.cumsum(np.abs(np.diff(u)))] / max(np.ptp(u), 1e-300)
        u = u[:max(int(np.searchsorted(travel, path, side="right")), 2)]
    n = u.size
    k = max(1, n // target)
    du = np.sign(np.diff(u))
    nz = np.flatnonzero(du)
    rev = nz[1:][du[nz[1:]] != du[nz[:-1]]]       # index of the sample before a reversal
    keep = np.zeros(n, dtype=bool)
    keep[::k] = True
    keep[rev] = True
    keep[-1] = True
    return np.flatnonzero(keep)


def fit_boucwen(u, y, *, input_range=None, initial_state="auto", holdout="alternate",
                refit=True, n=None, shape=None, layout_=None, refine_below=None,
                responses=None):
    """Fit a :class:`pihyst.model.BoucWenModel` to a record (module notes).

    Parameters
    ----------
    u, y : array_like
        Input and measured output.
    input_range : (min, max), optional
        The model's input range; default the data's span.
    initial_state : "auto", "cycled" or "settle"
        "cycled": the record starts at rest at the bottom after a full cycle; "settle":
        unknown, the first full sweep settles z and is not fitted; "auto": "cycled" if the
        record starts at the bottom of its range.
    holdout : "alternate", float or None
        Held-back cycles, as for :func:`pihyst.fit`.
    refit : bool
        Refit (offset, c_1, c_2, a) on fitted and held-back samples once the shape is
        chosen.
    n : float, optional
        Fix the exponent (default: searched over 1 ... 3 and refined).
    shape : dict, optional
        {"beta", "gamma", "n"}: skip the search and use this shape; with
        "start_of_z_fitted": True, also fit the start of z (the report's
        ``data["start_of_z_fitted"]`` of the fit that found the shape).
    layout_ : Layout, optional
        The settle/fit/held-back cut of the record, when the caller has made it (the
        comparison of families in :func:`pihyst.fit`).
    refine_below : float, optional
        Refine the best shape of the grid by Nelder-Mead only if its fitted RMS is
        below this (the comparison of families: ``REFINE_REACH`` times the best other
        family's judged RMS); else the grid's shape is kept.
    responses : Responses, optional
        Where the shape grid's z trajectories, which depend on the input only, are kept
        for the other fits of the same input (identify/_responses.py).

    Returns
    -------
    (BoucWenModel, BoucWenReport)
    """
    u, y = checked_signals(u, y)
    lo, hi = (float(u.min()), float(u.max())) if input_range is None else map(float,
                                                                               input_range)
    if not (lo < hi and u.min() >= lo and u.max() <= hi):
        raise FitError(f"input_range {[lo, hi]} must contain the input's span "
                       f"[{u.min():g}, {u.max():g}]")
    span = hi - lo
    v = u - lo
    if initial_state == "auto":
        initial_state = "cycled" if starts_at_rest(v, span) else "settle"
    if initial_state not in ("cycled", "settle"):
        raise FitError(f"initial_state must be 'auto', 'cycled' or 'settle', got "
                       f"{initial_state!r:.40}")
    settle = initial_state == "settle"
    lay = layout(v, span, settle=settle, holdout=holdout) if layout_ is None else layout_
    fit_i, held_i = lay.indices("fit"), lay.indices("held_back")
    if fit_i.size < 5:
        raise FitError("too few fitted samples for a Bouc-Wen model (5 parameters)")
    search = _ShapeSearch(v / span, y, fit_i, settle, n, shape, refine_below,
                          Responses() if responses is None else responses)
    shape_found, lin = search.shape_and_start(held_i, first_reversal(v))
    beta, gamma, nn = shape_found
    z, sens, (coef, b) = lin
    errors = {"fit": _errors(search.residual(z, sens, coef, b, fit_i)),
              "held_back": _errors(search.residual(z, sens, coef, b, held_i))}
    final = errors
    if refit and held_i.size:
        both = np.sort(np.r_[fit_i, held_i])
        coef, b = _solve_linear(search.x[both], z[both], y[both], 2 * beta / (beta + gamma),
                                None if sens is None else sens[both])
        final = {"all": _errors(search.residual(z, sens, coef, b, both))}
    off, c1, c2, a = coef
    model = BoucWenModel(beta=beta, gamma=gamma, n=nn, hysteretic=a, linear=c1,
                         quadratic=c2, offset=off, input_range=(lo, hi))
    data = {"samples": int(v.size), "fit_samples": int(fit_i.size),
            "held_back_samples": int(held_i.size), "settle_samples": int(lay.settle_end),
            "holdout": lay.holdout, "initial_state": initial_state,
            "start_of_z_fitted": search.start_free}
    report = BoucWenReport(
        chosen="bouc-wen", errors=errors, final_errors=final,
        search={"summary": search.summary(shape_found), "beta": beta, "gamma": gamma,
                "n": nn, "evaluations": search.evaluations},
        data=data,
        families=[{"family": "bouc-wen", "chosen": True, "n_params": 7, "errors": errors}])
    fit_meta = {"family": "bouc-wen", "errors": errors, "search": report.search,
                "data": data}
    # the state [u, z] the record itself started from, as fitted: the free start of z
    # (z0 + b / a: the start column b s is the first-order change of z0), or z = 0 at
    # the first sample when the first sweep settles it; what the model predicts the
    # record from (the check of the record's creep start, identify/_creep.py)
    x0, z0 = search.start(beta, gamma, nn)
    if search.start_free and coef[3] != 0.0:
        fit_meta["record_start"] = [float(lo + x0 * span), float(z0 + b / coef[3])]
    elif settle:
        fit_meta["record_start"] = [float(lo + x0 * span), float(z0)]
    if settle:
        fit_meta["settled"] = {"sample": int(lay.settle_end),
                               "state": [float(u[lay.settle_end - 1]),
                                         float(z[lay.settle_end - 1])]}
    return model.replace(metadata={"fit": fit_meta}), report


class _ShapeSearch:
    """The search for a Bouc-Wen shape (beta, gamma, n) on the normalized input ``x``:
    a grid of shapes on a decimated record, then Nelder-Mead from the best of them
    (module notes), with the linear part fitted by :func:`_solve_linear` for each."""

    def __init__(self, x, y, fit_i, settle, n, shape, refine_below, responses):
        self.x, self.y, self.fit_i, self.settle = x, y, fit_i, settle
        self.responses = responses
        self.n, self.shape, self.refine_below = n, shape, refine_below
        self.rest_z = {}
        self.free_start = False      # the start of z a free column (start_sensitivity)
        self.start_free = False      # the shape kept was found with it
        self.evaluations = 0
        where = np.zeros(x.size, dtype=bool)
        where[fit_i] = True
        # the first cycles hold too few fitted samples: twice the path, until they do
        # (the whole record at once took 100 s on 10^6 samples of level ramps, every one
        # of its 5,000 reversals kept)
        path = SEARCH_PATH
        keep = _keep(x, SEARCH_SAMPLES, path)
        while np.count_nonzero(where[keep]) < MIN_SEARCH_FITTED and keep[-1] < x.size - 1:
            path *= 2
            keep = _keep(x, SEARCH_SAMPLES, path)
        self.kfit = np.flatnonzero(where[keep])
        self.ns = GRID_N if n is None else (float(n),)
        self.xk, self.yk = x[keep], y[keep]
        self.grid = [(b, r * b, e) for b in GRID_BETA for r in GRID_RATIO for e in self.ns]
        self.skipped_refinement = []     # the grid's best fitted RMS, where not refined
        self.skipped_free_start = None   # the held-back RMS from rest, where not searched

    def start(self, beta, gamma, nn):
        """(x, z) before the first sample: the cycled rest state, or z = 0 at x[0] (then
        settled by the first sweep)."""
        if self.settle:
            return self.x[0], 0.0
        if (beta, gamma, nn) not in self.rest_z:
            self.rest_z[beta, gamma, nn] = cycled_z(beta, gamma, nn)
        return 0.0, self.rest_z[beta, gamma, nn]

    def grid_z(self):
        """Each grid shape's z along the decimated input: it depends on the input only,
        so it is computed once per input (the searches with a free start, and the fits
        of the same input with creep removed, share it)."""
        key = ("bouc-wen grid z", digest(self.xk), self.settle,
               float(self.x[0]) if self.settle else None, self.ns)
        return self.responses.get(key, lambda: [trajectory(self.xk, *self.start(*g), *g)
                                                for g in self.grid])

    def with_sensitivity(self, xs, z, beta, gamma, nn):
        """(z, its sensitivity to z0 with free_start, else None)."""
        if not self.free_start:
            return z, None
        return z, start_sensitivity(xs, *self.start(beta, gamma, nn), z, beta, gamma, nn)

    def z_and_sensitivity(self, xs, beta, gamma, nn):
        """z along xs from the start (the model's own arithmetic, in the C core), and
        (with free_start) its sensitivity to z0."""
        return self.with_sensitivity(
            xs, trajectory(xs, *self.start(beta, gamma, nn), beta, gamma, nn),
            beta, gamma, nn)

    def fitted_rms(self, beta, gamma, nn, zk, sk):
        kfit = self.kfit
        xf, zf, yf = self.xk[kfit], zk[kfit], self.yk[kfit]
        sf = None if sk is None else sk[kfit]
        (off, c1, c2, a), b = _solve_linear(xf, zf, yf, 2 * beta / (beta + gamma), sf)
        r = yf - (off + c1 * xf + c2 * xf * xf + a * zf + (0 if sf is None else b * sf))
        return float(np.sqrt(np.mean(r * r)))

    def objective(self, p):
        """The fitted RMS on the decimated record (reversals kept: z is that of the
        full one)."""
        self.evaluations += 1
        shape_ = searched_shape(p, self.n)
        if shape_ is None:
            return math.inf
        return self.fitted_rms(*shape_, *self.z_and_sensitivity(self.xk, *shape_))

    def search(self):
        """(beta, gamma, n): 1. a grid of shapes on the decimated record, 2. Nelder-Mead
        from the best of them on the fitted samples."""
        from scipy.optimize import minimize

        shape, n = self.shape, self.n
        if shape is None:
            rms = [self.fitted_rms(*g, *self.with_sensitivity(self.xk, zk, *g))
                   for g, zk in zip(self.grid, self.grid_z())]
            b0, g0, n0 = self.grid[int(np.argmin(rms))]
        else:
            b0, g0, n0 = (float(shape["beta"]), float(shape["gamma"]),
                          float(shape.get("n", 1)))
        p0 = np.array([math.log(b0), math.atanh(np.clip(g0 / b0, -0.95, 0.95)), n0])
        p_best = p0
        if shape is None and self.refine_below is not None and min(rms) > self.refine_below:
            self.skipped_refinement.append(min(rms))
        elif shape is None:
            res = minimize(self.objective, p0, method="Nelder-Mead",
                           options={"xatol": SEARCH_XATOL,
                                    "fatol": SEARCH_FATOL * np.ptp(self.y),
                                    "maxfev": SEARCH_EVALUATIONS,
                                    "initial_simplex": p0 + np.vstack(
                                        [np.zeros(3), np.diag([0.3, 0.3, 0.25])])})
            p_best = res.x if res.fun <= self.objective(p0) else p0
        return searched_shape(p_best, n) or searched_shape(p0, n)

    def linear_fit(self, beta, gamma, nn, rows):
        """(z, its sensitivity or None, ((offset, c_1, c_2, a), b)) on ``rows``."""
        x, y = self.x, self.y
        z, sens = self.z_and_sensitivity(x, beta, gamma, nn)
        d = 2 * beta / (beta + gamma)
        return z, sens, _solve_linear(x[rows], z[rows], y[rows], d,
                                      None if sens is None else sens[rows])

    def rms_from_rest(self, z, coef, rows):
        off, c1, c2, a = coef
        x, y = self.x, self.y
        r = y[rows] - (off + c1 * x[rows] + c2 * x[rows] ** 2 + a * z[rows])
        return float(np.sqrt(np.mean(r * r))) if rows.size else math.inf

    def shape_and_start(self, held_i, first_turn):
        """(shape, linear fit) searched from rest (or settled) and, for a record taken
        to start at rest that may not (a partial cycle before it), searched again with
        the start of z free, kept if the actuator, predicted from rest, then holds back
        better (after its first sweep, without held-back cycles)."""
        fit_i = self.fit_i
        self.start_free = self.free_start = bool(
            self.shape is not None and self.shape.get("start_of_z_fitted")) and not self.settle
        shape = self.search()
        lin = self.linear_fit(*shape, fit_i)
        later = fit_i[fit_i >= first_turn]
        if not self.settle and self.shape is None and (held_i.size or later.size):
            judge = held_i if held_i.size else later
            from_rest = self.rms_from_rest(lin[0], lin[2][0], judge)
            if self.refine_below is not None and from_rest > self.refine_below:
                # as the refinement: a start searched free lowered the held-back RMS
                # by at most 3.65 times on the population (REFINE_REACH)
                self.skipped_free_start = from_rest
                return shape, lin
            self.free_start = True
            shape2 = self.search()
            lin2 = self.linear_fit(*shape2, fit_i)
            if self.rms_from_rest(lin2[0], lin2[2][0], judge) < from_rest:
                shape, lin = shape2, lin2
                self.start_free = True
            self.free_start = False
        return shape, lin

    def residual(self, z, sens, coef, b, rows):
        """The record's residual on ``rows``, with its own start (b s: z0 other than at
        rest); the model starts at rest."""
        off, c1, c2, a = coef
        xr = self.x[rows]
        start_term = 0.0 if sens is None else b * sens[rows]
        return self.y[rows] - (off + c1 * xr + c2 * xr * xr + a * z[rows] + start_term)

    def summary(self, shape):
        """The report's sentence on the shape and how it was found."""
        beta, gamma, nn = shape
        how = (f"grid of {len(GRID_BETA) * len(GRID_RATIO) * len(self.ns)} shapes + "
               f"{self.evaluations} Nelder-Mead evaluations" if self.shape is None
               else "shape given")
        if self.skipped_refinement:
            how = (f"grid of {len(self.grid)} shapes, not refined: its best fitted RMS, "
                   f"{self.skipped_refinement[0]:.4g}, is more than {REFINE_REACH:g} times "
                   f"the best other family's judged RMS")
        out = f"beta {beta:.4g}, gamma {gamma:.4g}, n {nn:.3g} on the normalized input ({how})"
        if self.start_free:
            out += ("; shape found with the start of z unknown (the record does not start "
                    "at rest: predicted from rest, it holds back better)")
        if self.skipped_free_start is not None:
            out += (f"; the start of z not searched free: from rest it holds back "
                    f"{self.skipped_free_start:.4g}, more than {REFINE_REACH:g} times the "
                    f"best other family's judged RMS")
        return out


def travel_window(rec, travel):
    """The end of the first cycles of the framed record ``rec`` within ``travel`` ranges
    of input travel, when its input travels further and those cycles include every role
    of the record (fitted, held back); else None (the whole record)."""
    path = np.cumsum(np.abs(np.diff(rec.v))) / rec.S
    if path.size == 0 or path[-1] <= travel:
        return None
    reach = int(np.searchsorted(path, travel)) + 1
    stop = next((z for a, z, role in rec.layout.segments if z >= reach), None)
    if stop is None or stop >= rec.u.size:
        return None
    inside = {r for a, z, r in rec.layout.segments if z <= stop} - {"settle"}
    everywhere = {r for *_, r in rec.layout.segments} - {"settle"}
    return stop if inside == everywhere else None


def family_fit(family, fitter, rival_rms=None):
    """The Bouc-Wen family fitted on ``fitter``'s record, cut as for every family: a
    :class:`~pihyst.identify._family_result.FamilyFit` for the comparison in
    :func:`pihyst.fit` (docs/theory/bouc-wen.md)."""
    from pihyst.identify._family_result import FamilyFit
    rec = fitter.rec
    # the zero state chosen from the data (identify/_start_state.py): a Bouc-Wen fit
    # takes the start of z as unknown anyway (fit_boucwen)
    from_data = rec.state_choice is not None
    unsupported = [name for name, given in (
        ("thresholds", fitter.thresholds is not None),
        ("candidates", fitter.candidates is not None),
        ("n_operators", fitter.n_operators is not None),
        ("bounds", fitter.bounds is not None), ("nonnegative=False", not fitter.nonnegative),
        ("a fixed offset", not rec.fit_offset), ("through", len(rec.through) > 0),
        ("an explicit or zero initial_state",
         rec.state_mode not in ("cycled", "settle", "rise", "fall") and not from_data))
        if given]
    if unsupported:
        raise FitError(f"bouc-wen has no operators to choose and fits its own offset and "
                       f"state: drop {', '.join(unsupported)}")
    # a long record: fitted and judged on its first FAMILY_TRAVEL ranges of input travel,
    # on FAMILY_SAMPLES samples and every input extremum (the PI families are judged on all)
    stop = travel_window(rec, FAMILY_TRAVEL)
    if stop is not None:
        fitter = fitter.windowed(stop, note=lambda kept, n: (
            f"fitted and judged on the first {kept} of {n} samples ({FAMILY_TRAVEL:g} ranges "
            f"of input travel)"))
    on = fitter.subsampled(FAMILY_SAMPLES, note=lambda kept, n: (
        f"fitted on {kept} of {n} samples (evenly spaced, and every input extremum); "
        f"errors on those samples"))
    rec = on.rec
    kwargs = dict(input_range=(rec.lo, rec.lo + rec.S),
                  # rise, fall: z rises from rest at the bottom to the first sample,
                  # and its start is then fitted as unknown (fit_boucwen)
                  initial_state=("cycled" if from_data or rec.state_mode in ("rise", "fall")
                                 else rec.state_mode),
                  n=family.n, layout_=rec.layout, responses=fitter.responses)
    model, report = fit_boucwen(rec.u, rec.y, refit=False, refine_below=(
        None if rival_rms is None else REFINE_REACH * rival_rms), **kwargs)

    def refit():
        shape = {k: report.search[k] for k in ("beta", "gamma", "n")}
        shape["start_of_z_fitted"] = report.data["start_of_z_fitted"]
        return fit_boucwen(rec.u, rec.y, refit=True, shape=shape, **kwargs)[0]

    errors = on.errors(model)
    judged = errors["held_back"]["rms"] if rec.has_held_back else errors["fit"]["rms"]
    return FamilyFit(family=family, model=model, operators=(),
                     weights=np.array([model.linear, model.quadratic, model.hysteretic]),
                     offset=model.offset, errors=errors, judged_rms=judged, n_params=7,
                     notes=(report.search["summary"], *fitter.notes), refit=refit,
                     judged_on=on)
