"""Creep of a Bouc-Wen model fitted together with its linear part and its shape
(docs/theory/creep.md, docs/theory/bouc-wen.md).

The model with creep is

    H[t] = c + c_1 x[t] + c_2 x[t]^2 + a z[t]            (Bouc-Wen: the settled output)
    y[t] = H[t] - sum_i g_i psi_i[t],  psi_i = H - z_i   (z_i: lags of H, pihyst.model.Creep)

For a fixed shape (beta, gamma, n), z is known and the lag deficits are linear in H: with
L_i(s) the deficit of lag i driven by a signal s from rest at s's first value,

    psi_i = c_1 L_i(x) + c_2 L_i(x^2) + a L_i(z)                               (D)

(a constant has no deficit). y is then linear in (c, c_1, c_2, a) and in the gains
g = B p separately; :func:`joint_linear_fit` solves the bounded QP in (v, c, p) — v the
monotone case's (q_0, q_1, p_a) >= 0 of identify/_boucwen.py, 0 <= p <= G/(2n) — with psi
from the previous estimate of (c_1, c_2, a), for both monotone cases, until H stops
changing (as the PI families' joint QP, identify/_creep.py).

The shape is not left to the fit without creep: a shape chosen on a record whose creep
was estimated with another shape absorbs part of the creep, and alternating shape search
and creep estimate converges slowly (measured on a Bouc-Wen actuator with 5.5 % creep:
fitted creep 2.7, 3.3, 3.6, 3.7, 3.9 % in five rounds). :func:`fit_shape_and_creep`
therefore searches the shape with the joint fit inside the criterion (Nelder-Mead on
(log beta, atanh(gamma / beta), n), from the shape given), which is cheap: L_i(x) and
L_i(x^2) do not depend on the shape, and each shape costs one C-core run of z and of its
lags.
"""

import math

import numpy as np

from pihyst import _core
from pihyst.identify._boucwen import boucwen_coefficients, boucwen_columns, searched_shape
from pihyst.identify._qp import solve_qp
from pihyst.model._creep import MAX_TOTAL_GAIN

CHUNK = 1 << 15
MAX_PASSES = 6
#: Nelder-Mead evaluations of the shape search with creep (it starts from the shape
#: fitted without creep); its QPs run on at most about SEARCH_ROWS of the fitted
#: samples (evenly spaced; the lags run on every sample), the chosen shape's on all.
#: On four random Bouc-Wen actuators with creep (benchmarks/bench_population.py seeds
#: 1, 8, 25, 27) 60 and 2000 instead of 150 and 5000 kept the family, and the
#: validation / tracking errors moved by -14 ... +6 % (0.033 -> 0.035 % of range the
#: worst), in a third of the time
MAX_EVALUATIONS = 60
SEARCH_ROWS = 2000


def lag_deficits(s, s0, dt, tau):
    """L_i(s)[t] = s[t] - z_i[t] (N x n) for lags driven by ``s`` from rest at ``s0``."""
    lags = _core.Creep(tau, np.zeros(tau.size), 1.0, np.full(tau.size, float(s0)))
    out = np.empty((s.size, tau.size))
    for a in range(0, s.size, CHUNK):
        b = min(a + CHUNK, s.size)
        out[a:b] = s[a:b, None] - lags.lag_states(s[a:b], dt[a:b])
    return out


def tied_deficits(s, s0, dt, tau, tie, rows):
    """L(s)[rows] @ tie: the deficits of :func:`lag_deficits` at the rows ``rows`` (a
    boolean mask) only, times the gains' basis ``tie`` (n x p), block by block (the
    lags run over every sample; only the rows a fit sums over are kept, not N x n)."""
    lags = _core.Creep(tau, np.zeros(tau.size), 1.0, np.full(tau.size, float(s0)))
    out = np.empty((int(np.count_nonzero(rows)), tie.shape[1]))
    done = 0
    for a in range(0, s.size, CHUNK):
        b = min(a + CHUNK, s.size)
        sel = rows[a:b]
        states = lags.lag_states(s[a:b], dt[a:b])
        count = int(np.count_nonzero(sel))
        if count:
            out[done:done + count] = (s[a:b][sel, None] - states[sel]) @ tie
            done += count
    return out


class _Record:
    """The record and the shape-independent parts of (D), on the fitted rows."""

    def __init__(self, model, u, y, dt, tau, tie, fitted):
        self.u, self.dt, self.tau, self.tie = u, dt, tau, tie
        self.fitted = fitted
        self.yf = y[fitted]
        self.x = model._x(u)
        self.x0 = model._x(model.initial_state[0])
        x = self.x
        self.xf = x[fitted]
        # deficits of x and x^2 from rest at the initial state's input, times the tie
        self.lx = tied_deficits(x, self.x0, dt, tau, tie, fitted)
        self.lx2 = tied_deficits(x * x, self.x0 * self.x0, dt, tau, tie, fitted)
        n = tau.size
        p = tie.shape[1]
        self.lower = np.r_[np.zeros(3), -np.inf, np.zeros(p)]
        self.upper = np.r_[np.full(4, np.inf), np.full(p, MAX_TOTAL_GAIN / (2 * n))]


def joint_linear_fit(model, rec):
    """(rss, model without creep, gains, passes): the linear part of the Bouc-Wen
    ``model`` (its shape fixed) and the creep gains by repeated joint QPs (module notes)
    on the fitted rows of ``rec``."""
    hyst = model.replace(creep=None)
    z = hyst._core(hyst.initial_state).trajectory(rec.u)[1]
    lz = tied_deficits(z, hyst.initial_state[1], rec.dt, rec.tau, rec.tie, rec.fitted)
    zf = z[rec.fitted]
    spread = 2.0 * hyst.beta / (hyst.beta + hyst.gamma)          # D
    c1, c2, a = hyst.linear, hyst.quadratic, hyst.hysteretic
    h = c1 * rec.xf + c2 * rec.xf ** 2 + a * zf
    span = max(float(np.ptp(rec.yf)), 1e-300)
    names = ["q_0", "q_1", "p", "offset", "creep per lag", "creep rise toward slow lags"]
    base = {neg: boucwen_columns(rec.xf, zf, spread, neg) for neg in (False, True)}
    ones = np.ones(rec.xf.size)
    best, passes = None, 0
    while passes < MAX_PASSES:
        passes += 1
        psi = c1 * rec.lx + c2 * rec.lx2 + a * lz                      # (D), times B
        best = None
        for negative in (False, True):
            X = np.column_stack([base[negative], ones, -psi])
            sol = solve_qp(X.T @ X, X.T @ rec.yf, lower=rec.lower, upper=rec.upper,
                           warn=False, names=names).x
            r = X @ sol - rec.yf
            rss = float(r @ r)
            if best is None or rss < best[0]:
                best = (rss, negative, sol)
        rss, negative, sol = best
        c1, c2, a = boucwen_coefficients(sol[:3], spread, negative)
        h_new = c1 * rec.xf + c2 * rec.xf ** 2 + a * zf
        change = float(np.max(np.abs(h_new - h), initial=0.0))
        h = h_new
        if change <= 1e-6 * span:
            break
    gains = np.clip(rec.tie @ sol[4:], 0.0, None)
    hyst = hyst.replace(offset=float(sol[3]), linear=c1, quadratic=c2, hysteretic=a)
    return rss, hyst, gains, passes


def fit_shape_and_creep(model, u, y, dt, tau, tie, fitted, *, fixed_n=None, search=True):
    """(model without creep, gains, passes, evaluations): shape, linear part and creep
    gains of a Bouc-Wen model fitted together on the rows ``fitted`` (a boolean mask),
    the shape searched from ``model``'s (module notes) unless ``search`` is False;
    ``fixed_n`` keeps the exponent."""
    rec = _Record(model, u, y, dt, tau, tie, fitted)
    if not search:
        _, hyst, gains, passes = joint_linear_fit(model, rec)
        return hyst, gains, passes, 1
    from scipy.optimize import minimize

    rows = np.flatnonzero(fitted)
    sparse = np.zeros_like(fitted)
    sparse[rows[::max(1, rows.size // SEARCH_ROWS)]] = True
    full, rec = rec, _Record(model, u, y, dt, tau, tie, sparse)
    best = joint_linear_fit(model, rec)

    evaluations = 0

    def objective(p):
        nonlocal best, evaluations
        evaluations += 1
        shape = searched_shape(p, fixed_n)
        if shape is None:
            return math.inf
        beta, gamma, nn = shape
        candidate = joint_linear_fit(model.replace(beta=beta, gamma=gamma, n=nn), rec)
        if candidate[0] < best[0]:
            best = candidate
        return math.sqrt(candidate[0] / max(rec.yf.size, 1))

    ratio = float(np.clip(model.gamma / model.beta, -0.95, 0.95))
    p0 = np.array([math.log(model.beta), math.atanh(ratio), model.n])
    minimize(objective, p0, method="Nelder-Mead",
             options={"xatol": 1e-4, "fatol": 1e-7 * max(float(np.ptp(rec.yf)), 1e-300),
                      "maxfev": MAX_EVALUATIONS,
                      "initial_simplex": p0 + np.vstack([np.zeros(3),
                                                         np.diag([0.2, 0.2, 0.15])])})
    _, hyst, gains, passes = joint_linear_fit(best[1], full)
    return hyst, gains, passes, evaluations
