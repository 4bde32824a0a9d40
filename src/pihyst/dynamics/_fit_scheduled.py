"""One amplitude-scheduled model from periodic multisine records at several levels
(:mod:`._scheduled`; docs/theory/hammerstein.md).

1. *Common modes.* One linear state-space model of all levels' records together
   (:func:`~pihyst.dynamics.fit_state_space`, or the one given): its modes are the
   starting point of every level, so that mode q means the same resonance at each.
2. *Each level's modes.* Per level l, the BLA G_l(k) of its records
   (:func:`~pihyst.dynamics.estimate_bla`) and, from the common modes, the modal
   parameters theta_l fitted to it by Levenberg-Marquardt (:mod:`._refine`):

       min_theta sum_k || G(z_k; theta) - G_l(k) ||_F^2
                 + mu (e_0 / n) sum_j ((theta_j - theta_0j) / s_j)^2,

   theta_0 the common modes, e_0 their error on G_l, n the number of parameters and s_j
   the size of a unit change (a pole's bandwidth, a mode's |c| or |b|; ``penalty`` mu,
   1 by default: a unit change of every parameter costs as much as the common modes'
   misfit), kept only if it lowers the error (otherwise the common modes stand for the
   level). The penalty keeps modes that the level's data barely see where they were,
   so that mode q stays the same resonance at every level (without it, on the FSM,
   weak modes jumped by hundreds of Hz between the levels' fits).
3. *Anchors.* The level's amplitude a_l is the mean of its steady-state schedule
   (:func:`~pihyst.dynamics.running_amplitude` over each record played twice, the
   second pass kept): the value the model will see on the same drive.
4. *Gauge.* A mode's c b^T is unchanged by c -> s c, b -> b / s; each level's (c_q,
   b_q) is rescaled to the b_q of the lowest level (s = <b_l, b_1> / |b_1|^2), so that
   interpolating c and b separately interpolates their product.
"""

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from pihyst.dynamics._bla import estimate_bla, periodic_records
from pihyst.dynamics._fit_state_space import fit_state_space
from pihyst.dynamics._refine import fit_modes, modal_parameters
from pihyst.dynamics._scheduled import ScheduledStateSpace, running_amplitude
from pihyst.dynamics._statespace import StateSpace
from pihyst.exceptions import InvalidArgumentError


def steady_amplitude(records, period, discard, window):
    """Mean schedule over the records' steady-state periods, each played twice."""
    values = []
    for u, _ in records:
        start = min(discard, u.shape[0] // period - 1) * period
        steady = u[start:]
        values.append(running_amplitude(np.vstack([steady, steady]), window)[len(steady):])
    return float(np.mean(np.concatenate(values)))


def gauge_to(ref_b, c, b):
    """(c s, b / s) with s = <b, ref_b> / |ref_b|^2 per mode (rows); s = 1 where ref_b
    is zero."""
    num = np.sum(b * np.conj(ref_b), axis=-1)
    den = np.sum(np.abs(ref_b) ** 2, axis=-1)
    s = np.where(den > 0, num / np.where(den > 0, den, 1.0), 1.0)
    s = np.where(np.abs(s) > 0, s, 1.0)
    return c * s[:, None], b / s[:, None]


def fit_scheduled_state_space(levels: Sequence[Iterable[tuple[Any, Any]]], period: int,
                              order: int | None = None, *,
                              linear: StateSpace | None = None, window: float = 1024.0,
                              discard: int = 1, max_nfev: int = 50,
                              penalty: float = 1.0, exponent: float = 1.0,
                              **state_space_options: Any) -> ScheduledStateSpace:
    """One :class:`~pihyst.dynamics.ScheduledStateSpace` for records at several drive
    amplitudes (module notes).

    Parameters
    ----------
    levels : sequence of iterables of (array_like, array_like)
        Per drive level, its ``(u, y)`` records (periodic multisines, at least m per
        level, as for :func:`~pihyst.dynamics.estimate_bla`); at least two levels of
        different amplitudes.
    period : int
        Samples per period.
    order : int, optional
        State dimension of the common modes (None: chosen by
        :func:`~pihyst.dynamics.fit_state_space`'s validation); ignored with ``linear``.
    linear : StateSpace, optional
        The common modes (step 1) already fitted.
    window : float
        W of the schedule, samples.
    discard : int
        Leading periods of each record that are the transient.
    max_nfev : int
        At most this many evaluations of each level's modal fit.
    penalty : float
        mu of the modal fit's penalty on changes from the common modes (module notes;
        0: none, each level's modes fitted freely).
    exponent : float
        p of the model's interpolation shape a^p (0: log a; :mod:`._scheduled`).
    **state_space_options
        Passed to :func:`~pihyst.dynamics.fit_state_space` (step 1).

    Returns
    -------
    ScheduledStateSpace
        Anchored at the levels' amplitudes, in increasing order.

    Raises
    ------
    InvalidArgumentError
        Fewer than two levels, levels of equal amplitude, records that are not whole
        periods, a common model without modal form or of the wrong size.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import StateSpace, fit_scheduled_state_space
    >>> def multisine(seed, scale, t=np.arange(128), k=np.arange(1, 30)):
    ...     phase = np.random.default_rng(seed).uniform(0, 2 * np.pi, k.size)
    ...     return scale * np.cos(2 * np.pi * np.outer(t, k) / 64 + phase).sum(axis=1)
    >>> def plant(pole):
    ...     return StateSpace([[pole]], [[1.0]], [[1.0]], [[0.0]])
    >>> levels = [[(u, plant(p).predict(u)) for u in (multisine(s, g) for s in (1, 2))]
    ...           for g, p in ((1.0, 0.5), (3.0, 0.6))]
    >>> model = fit_scheduled_state_space(levels, 64, order=1, window=64, penalty=0)
    >>> [round(float(model.at(a).A[0, 0]), 3) for a in model.amplitudes]
    [0.5, 0.6]
    """
    groups = [periodic_records(level, period) for level in levels]
    if len(groups) < 2:
        raise InvalidArgumentError(f"a scheduled model needs records at two levels or "
                                   f"more, not {len(groups)}")
    if linear is None:
        linear = fit_state_space([r for g in groups for r in g], period, order,
                                 discard=discard, **state_space_options)
    m, p = groups[0][0][0].shape[1], groups[0][0][1].shape[1]
    if (linear.n_inputs, linear.n_outputs) != (m, p):
        raise InvalidArgumentError(f"the common model has {linear.n_inputs} inputs and "
                                   f"{linear.n_outputs} outputs; the records {m} and {p}")
    amplitudes, params = [], []
    for g in groups:
        frf = estimate_bla(g, period, discard=discard)
        fitted = fit_modes(linear, frf.omega, frf.G, max_nfev=max_nfev, penalty=penalty)
        if fitted is None:
            raise InvalidArgumentError("the common model has no modal form (repeated "
                                       "poles): fit it at another order")
        layout, theta0, theta, cost0, cost = fitted
        lam, c, b, *rest = modal_parameters(layout, theta if cost < cost0 else theta0)
        # a pair may leave the upper half plane: it is then given by its conjugate
        flip = lam.imag < 0
        lam, c, b = (np.where(flip[:, None] if v.ndim > 1 else flip, np.conj(v), v)
                     for v in (lam, c, b))
        params.append((lam, c, b, *rest))
        amplitudes.append(steady_amplitude(g, period, discard, window))
    order_ = np.argsort(amplitudes)
    a = np.asarray(amplitudes)[order_]
    if np.any(np.diff(a) <= 1e-9 * max(a[-1], 1e-300)):
        raise InvalidArgumentError(f"the levels' amplitudes {np.round(a, 6).tolist()} "
                                   f"must differ")
    stacked = [params[i] for i in order_]
    lam, c, b, lr, cr, br, D = (np.stack([s[j] for s in stacked]) for j in range(7))
    for k in range(1, a.size):
        c[k], b[k] = gauge_to(b[0], c[k], b[k])
        cr[k], br[k] = (v.real for v in gauge_to(br[0], cr[k], br[k]))
    return ScheduledStateSpace(a, lam, c, b, lr, cr, br, D, window=float(window),
                               exponent=exponent)
