"""Fewer kernels for the same model: a KP basis's final weights reduced to the kernels
the model needs (docs/theory/identification.md, "Fewer kernels"; issue 20 item 5).

The regularized kernel fit (``_family_fit.fit_kernels``) gives almost every kernel of
its grid a weight: the penalty spreads the density smoothly over the Preisach plane,
and that spread is what predicts the minor loops a record of major loops never shows.
A compensator's time grows with its kernels, so once the weights w are final they are
replaced by weights w' on fewer kernels that give the same model: the same output, to
a small share of the model's own error, on the record's fitted samples and on probe
trajectories that cover the whole Preisach plane,

    rms_record(w' - w) <= eps   and   rms_probes(w' - w) <= eps,
    eps = PRUNE_TOLERANCE * (the model's judged RMS),                           (P)

and the judged RMS itself (held back; all samples for the refit) may rise by at most
PRUNE_JUDGED                                                                    (J),

both from Gram matrices: rms_X(w' - w)^2 = (w' - w)^T G_X (w' - w) / n_X. The probes are
first-order reversal curves (from the bottom up to each of 2 (grid - 1) levels and
back, and from the top down to each and back): they determine a Preisach-type model,
so a reduced model that follows them follows its reference on every minor loop, not
only on the loops the record holds, and the judgement needs no minor loops in the
record. (Choosing a smaller grid by the held-back error could not see this: on
Preisach actuators recorded on two-cycle triangles it doubled the validation error.)

PRUNE_TOLERANCE is 0.1: a change of 0.2 of the model's RMS error, uncorrelated with that
error, would raise it by sqrt(1 + 0.2^2) - 1 = 2 %, the choice's rule, but on ramps and
staircases between random levels the change was not uncorrelated (two population
actuators erred 10-25 % more with 0.2); 0.1 bounds even a fully correlated change to a
tenth of the error. A change correlated with the error on the held-back cycles can hand
the choice to a family that was a few percent behind: (J) keeps the judged RMS within a
quarter of the 2 % rule (identify/_constants.py gives the measurements).

The reduction: an order in which to take the kernels away, cheapest first (at each step
the kernel whose removal raises (w' - w)^T H (w' - w) least, H the sum of the two Grams,
the others refitted without bounds: w_k^2 / (H_T^-1)_kk, "optimal brain surgeon"), then
the longest prefix of that order whose removal keeps (P) and (J), the other weights refitted
to the reference under the fit's constraints (w' >= 0, bounds, ``through``; the QP of
``_qp`` on H), found by bisection. Deterministic: the same weights give the same
kernels on every run, and a model as cheap as the record allows, at a cost of a few
tens of milliseconds per fit.
"""

import numpy as np

from pihyst.exceptions import InfeasibleConstraintsError
from pihyst.identify import _constants
from pihyst.identify._gram import accumulate
from pihyst.identify._qp import solve_qp
from pihyst.identify._responses import digest

# probe samples per kernel width along the reversal curves
PROBE_STEPS = 4
# a weight this small against the largest contribution is a bound met to rounding
ROUNDING = 1e-12


def reversal_curves(grid, S):
    """First-order reversal curves over [0, S] for a kernel grid of ``grid`` centres:
    from the bottom up to each level m S / (2 (grid - 1)) and back, then from the top
    down to each and back, in steps of S / (PROBE_STEPS (grid - 1)).

    Examples
    --------
    >>> v = reversal_curves(2, 1.0)
    >>> float(v.min()), float(v.max()), v.size
    (0.0, 1.0, 25)
    """
    n = PROBE_STEPS * (grid - 1)
    ladder = np.arange(n + 1) * (S / n)
    turns = range(PROBE_STEPS // 2, n + 1, PROBE_STEPS // 2)
    up = [np.r_[np.arange(1, m + 1), np.arange(m - 1, -1, -1)] for m in turns]
    down = [np.r_[np.arange(n - 1, n - m - 1, -1), np.arange(n - m + 1, n + 1)]
            for m in turns]
    return ladder[np.concatenate(up + [[n]] + down)]


def probe_gram(template, state0, grid, S, fit_offset):
    """G / n of ``template``'s operators (and the constant column when ``fit_offset``)
    over :func:`reversal_curves`, from ``state0`` (the cycled state)."""
    v = reversal_curves(grid, S)
    parts, _ = accumulate(template, v, np.zeros_like(v), [(0, v.size, "fit")], state0,
                          offset=True)
    g = parts["fit"]
    keep = g.G.shape[0] if fit_offset else g.G.shape[0] - 1
    return g.G[:keep, :keep] / g.n


def kernel_probes(responses, template, grid, S, fit_offset):
    """:func:`probe_gram` of ``template`` (kernels of v on [0, S]), computed once per
    fit (``responses``: the fit's output-independent results)."""
    corners = np.array([[x[1] for x, _ in template.rising], [x[1] for x, _ in
                                                               template.falling]])
    key = ("kernel probes", digest(corners, np.array([grid, S, fit_offset], float)))
    def compute():
        # from rest at the bottom after a full cycle (_family_fit.cycled_state)
        cycled = template.simulate(np.array([0.0, S, 0.0])).final_state
        return probe_gram(template, cycled, grid, S, fit_offset)
    return responses.get(key, compute)


def prune_kernels(x, n_kernels, record, judge, probes, problem, reference_rms):
    """Weights x (kernels first, then the offset if fitted) on fewer kernels, within
    (P) and (J): ``record`` is the Gram of the record's fitted samples, ``judge`` that
    of the samples the model is judged on, ``probes`` G / n of the probes
    (:func:`kernel_probes`) over the same columns; ``problem`` carries the bounds and
    equality constraints; eps = PRUNE_TOLERANCE * ``reference_rms``.
    Returns the weights, zero on the kernels taken away, and a dict for the report."""
    x = np.asarray(x, dtype=float)
    tolerance = _constants.PRUNE_TOLERANCE * reference_rms
    every = np.arange(x.size)
    judged = judge.rms(every, x) * (1 + _constants.PRUNE_JUDGED)
    record = record.G / max(record.n, 1)
    H = record + probes
    target = H @ x
    scale = np.sqrt(np.maximum(np.diag(H), 0.0))

    def refit(kept):
        cols = np.r_[kept, np.arange(n_kernels, x.size)].astype(int)
        try:
            sol = solve_qp(H[np.ix_(cols, cols)], target[cols], lower=problem.lower[cols],
                           upper=problem.upper[cols], b_eq=problem.b_eq,
                           A_eq=None if problem.A_eq is None else problem.A_eq[:, cols])
        except InfeasibleConstraintsError:
            return None
        w = np.zeros_like(x)
        w[cols] = sol.x
        # a weight the QP left at its bound to rounding is zero
        w[:n_kernels][np.abs(w[:n_kernels] * scale[:n_kernels]) <= ROUNDING *
                      np.abs(w[:n_kernels] * scale[:n_kernels]).max()] = 0.0
        e = w - x
        rms = (float(np.sqrt(max(e @ record @ e, 0.0))),
               float(np.sqrt(max(e @ probes @ e, 0.0))))
        if max(rms) > tolerance or judge.rms(every, w) > judged:
            return None
        return (w, *rms)

    kept = np.flatnonzero(x[:n_kernels] != 0)
    order = _elimination_order(H, x, kept, n_kernels)
    # the longest prefix of that order whose removal keeps (P), by bisection
    best, lo, hi = (x, 0.0, 0.0), 0, order.size
    while lo < hi:
        m = (lo + hi + 1) // 2
        trial = refit(np.setdiff1d(kept, order[:m]))
        if trial is None:
            hi = m - 1
        else:
            best, lo = trial, m
    before, kept = kept.size, np.flatnonzero(best[0][:n_kernels] != 0)
    return best[0], {"kernels_before": int(before), "kernels": int(kept.size),
                     "tolerance": tolerance, "record_rms": best[1], "probe_rms": best[2]}


def _elimination_order(H, x, kept, n_kernels):
    """The kernels ``kept`` in the order they are taken away, cheapest first: at each
    step the kernel whose removal raises (w' - x)^T H (w' - x) least, the others refitted
    without bounds (w_k^2 / (H_T^-1)_kk over the columns T left; the weights and the
    inverse updated by the rank-one identity of the Schur complement). The last kernel
    is never taken away."""
    cols = np.r_[kept, np.arange(n_kernels, H.shape[0])].astype(int)
    d = np.diag(H)[cols]
    s = np.sqrt(np.where(d > 0, d, 1.0))
    Hs = H[np.ix_(cols, cols)] / np.outer(s, s)
    M = np.linalg.inv(Hs + ROUNDING * np.eye(cols.size))
    w = x[cols] * s
    alive = np.ones(kept.size, dtype=bool)
    order = []
    for _ in range(kept.size - 1):
        idx = np.flatnonzero(alive)
        j = idx[np.argmin(w[idx] ** 2 / np.diag(M)[idx])]
        w -= (w[j] / M[j, j]) * M[:, j]
        M -= np.outer(M[:, j], M[j, :]) / M[j, j]
        alive[j] = False
        order.append(kept[j])
    return np.array(order, dtype=int)
