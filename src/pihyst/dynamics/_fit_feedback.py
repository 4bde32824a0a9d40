"""One model for several drive amplitudes whose amplitude dependence is a feedback
loop: fixed linear dynamics G_0, the output fed back to the input through a gain that
grows linearly with the running input amplitude (docs/theory/hammerstein.md).

A piezo's compliance grows about linearly with its excursion (Rayleigh's law): the
actuator pushes back less, in proportion to the amplitude, i.e. a stiffness change fed
back from the displacement to the actuator's own force, and its free stroke grows, an
input gain. In the describing-function view, at running amplitude a (the schedule of
:mod:`._scheduled`),

    y = G(a) u,   G(a) = (I + delta G_0 K)^-1 G_0 (I + delta M),
    delta = (a - a_1) / (a_L - a_1),

G_0 (p x m) the linear system at the lowest level's amplitude a_1, K (m x p) the output
feedback and M (m x m) the input gain reached at the highest level a_L. Whatever the
levels, the amplitude dependence has m p + m^2 parameters (18 for the 3 x 3 mirror), and
G_0 is fitted on every level's records at once; the resonances move, as they do on the
actuator, because the loop moves them, all through the same K. (The scheduled model of
:mod:`._fit_scheduled` gives every mode of every level its own parameters instead.)

The fit, on the levels' best linear approximations G_l(k):

1. G_0 starts from the given linear model (e.g. the lowest level's own fit);
2. K, M start from the equation error, linear in them:
   (I + delta_l G_0 K) G_l = G_0 (I + delta_l M)  <=>
   delta_l (G_0 K G_l - G_0 M) = G_0 - G_l, least squares over lines and levels;
3. G_0's modal parameters (:mod:`._refine`), K and M together by Levenberg-Marquardt on
   sum_l sum_k || G(z_k; delta_l) - G_l(k) ||_F^2, analytic Jacobian:
   dG = S dG_0 (N - delta K G),  dG = -delta S G_0 dK G,  dG = delta S G_0 dM,
   S = (I + delta G_0 K)^-1, N = I + delta M.

With the output y = C x + D v and the input v = N u - delta K y, the closed loop at
delta is the state-space model

    E = (I + delta D K)^-1,
    A_d = A - delta B K E C,  B_d = B (I - delta K E D) N,  C_d = E C,  D_d = E D N,

returned at ``n_anchors`` amplitudes evenly spaced from a_1 to a_L as a
:class:`~pihyst.dynamics.ScheduledStateSpace` (its modes matched from one anchor to the
next by their poles), which simulates, inverts and saves it; between those anchors its
modes are interpolated linearly, which follows the loop's own dependence on delta
closely when the anchors are dense.
"""

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from pihyst.dynamics._bla import estimate_bla, periodic_records
from pihyst.dynamics._fit_scheduled import gauge_to, steady_amplitude
from pihyst.dynamics._refine import (
    _Layout,
    _modes,
    _pack,
    modal_jacobian,
    modal_parameters,
    modal_response,
    real_modal_state_space,
)
from pihyst.dynamics._scheduled import ScheduledStateSpace
from pihyst.dynamics._statespace import StateSpace
from pihyst.exceptions import FitError, InvalidArgumentError


def feedback_response(G0, K, M, delta):
    """(I + delta G_0 K)^-1 G_0 (I + delta M) on every line of G0 (L, p, m)."""
    G0 = np.asarray(G0)
    p, m = G0.shape[1:]
    S = np.linalg.inv(np.eye(p) + delta * G0 @ K)
    return S @ G0 @ (np.eye(m) + delta * M)


def closed_loop(model: StateSpace, K, M, delta) -> StateSpace:
    """The state-space model of the loop at ``delta`` (module notes)."""
    p, m = model.D.shape
    K, M = np.asarray(K, dtype=float), np.asarray(M, dtype=float)
    N = np.eye(m) + delta * M
    E = np.linalg.inv(np.eye(p) + delta * model.D @ K)
    return StateSpace(model.A - delta * model.B @ K @ E @ model.C,
                      model.B @ (np.eye(m) - delta * K @ E @ model.D) @ N,
                      E @ model.C, E @ model.D @ N)


def _start_feedback(G0s, blas, deltas):
    """K, M from the equation error (module notes, step 2); G0s: G_0 on each level's
    lines."""
    rows, rhs = [], []
    for G0, G, d in zip(G0s, blas, deltas):
        if d == 0:
            continue
        L, p, m = G0.shape
        # vec(G0 K G) = (G^T kron G0) vec(K), column-major vec, per line
        AK = np.einsum("kbi,kja->kjiab", G, G0).reshape(L, p * m, m * p)
        AM = -np.einsum("kja,bi->kjiab", G0, np.eye(m)).reshape(L, p * m, m * m)
        A = d * np.concatenate([AK, AM], axis=2).reshape(L * p * m, -1)
        r = (G0 - G).reshape(-1)
        rows.append(np.vstack([A.real, A.imag]))
        rhs.append(np.r_[r.real, r.imag])
    x = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)[0]
    return x[:m * p].reshape(m, p), x[m * p:].reshape(m, m)


def _match_modes(prev, lam, c, b):
    """Order the pairs (lam, c, b) like the poles ``prev`` (nearest, one to one)."""
    from scipy.optimize import linear_sum_assignment

    _, col = linear_sum_assignment(np.abs(prev[:, None] - lam[None, :]))
    return lam[col], c[col], b[col]


def feedback_scheduled(linear: StateSpace, K, M, amplitudes, window: float,
                       n_anchors: int = 9) -> ScheduledStateSpace:
    """The loop of ``linear`` with ``K``, ``M`` (module notes) at ``n_anchors``
    amplitudes from ``amplitudes[0]`` (delta 0) to ``amplitudes[1]`` (delta 1), as a
    :class:`~pihyst.dynamics.ScheduledStateSpace`.

    Raises
    ------
    FitError
        The loop is unstable at some anchor, or its poles change kind (real or pair)
        between the anchors.
    """
    a1, a2 = float(amplitudes[0]), float(amplitudes[1])
    params = []
    for delta in np.linspace(0.0, 1.0, n_anchors):
        ss = closed_loop(linear, K, M, delta)
        radius = np.abs(np.linalg.eigvals(ss.A)).max() if ss.order else 0.0
        if not radius < 1:
            raise FitError(f"the feedback loop is unstable at delta {delta:.3f} "
                           f"(spectral radius {radius:.6f})")
        (lam, c, b), (lr, cr, br) = _modes(ss)
        if params:
            if lam.size != params[0][0].size or lr.size != params[0][3].size:
                raise FitError(f"the loop's poles change kind (real or pair) at delta "
                               f"{delta:.3f}")
            lam, c, b = _match_modes(params[-1][0], lam, c, b)
            order = np.argsort(lr)
            lr, cr, br = lr[order], cr[order], br[order]
        else:
            order = np.argsort(lr)
            lr, cr, br = lr[order], cr[order], br[order]
        params.append((lam, c, b, lr, cr, br, ss.D))
    lam, c, b, lr, cr, br, D = (np.stack([s[j] for s in params]) for j in range(7))
    for k in range(1, n_anchors):
        c[k], b[k] = gauge_to(b[0], c[k], b[k])
        cr[k], br[k] = (v.real for v in gauge_to(br[0], cr[k], br[k]))
    return ScheduledStateSpace(np.linspace(a1, a2, n_anchors), lam, c, b, lr, cr, br, D,
                               window=float(window))


def fit_feedback_state_space(levels: Sequence[Iterable[tuple[Any, Any]]], period: int,
                             linear: StateSpace, *, window: float = 1024.0,
                             discard: int = 1, max_nfev: int = 30,
                             n_anchors: int = 9) -> ScheduledStateSpace:
    """One model of records at several drive amplitudes: fixed dynamics with their
    output fed back through a gain linear in the amplitude (module notes).

    Parameters
    ----------
    levels : sequence of iterables of (array_like, array_like)
        Per drive level, its ``(u, y)`` periodic multisine records (at least m per
        level); at least two levels of different amplitudes.
    period : int
        Samples per period.
    linear : StateSpace
        The start of G_0, the system at the lowest level (e.g. fitted on its records).
    window : float
        W of the schedule, samples.
    discard : int
        Leading periods of each record that are the transient.
    max_nfev : int
        At most this many evaluations of the joint Levenberg-Marquardt fit.
    n_anchors : int
        Anchors of the returned model between the lowest and the highest level.

    Returns
    -------
    ScheduledStateSpace
        The loop at ``n_anchors`` amplitudes from the lowest level's to the highest's.

    Raises
    ------
    InvalidArgumentError
        Fewer than two levels, levels of equal amplitude, records that are not whole
        periods, a start of the wrong size or without modal form, fewer than 2 anchors.
    FitError
        The fitted loop is unstable between the levels.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import StateSpace, fit_feedback_state_space
    >>> def multisine(seed, scale, t=np.arange(128), k=np.arange(1, 30)):
    ...     phase = np.random.default_rng(seed).uniform(0, 2 * np.pi, k.size)
    ...     return scale * np.cos(2 * np.pi * np.outer(t, k) / 64 + phase).sum(axis=1)
    >>> def plant(pole):
    ...     return StateSpace([[pole]], [[1.0]], [[1.0]], [[0.0]])
    >>> levels = [[(u, plant(p).predict(u)) for u in (multisine(s, g) for s in (1, 2))]
    ...           for g, p in ((1.0, 0.5), (3.0, 0.6))]
    >>> model = fit_feedback_state_space(levels, 64, plant(0.5), window=64)
    >>> [round(float(model.at(a).A[0, 0]), 3) for a in model.amplitudes[[0, -1]]]
    [0.5, 0.6]
    """
    from scipy.optimize import least_squares

    groups = [periodic_records(level, period) for level in levels]
    if len(groups) < 2:
        raise InvalidArgumentError(f"a model of several amplitudes needs records at two "
                                   f"levels or more, not {len(groups)}")
    if not n_anchors >= 2:
        raise InvalidArgumentError(f"n_anchors must be at least 2, not {n_anchors!r}")
    m, p = groups[0][0][0].shape[1], groups[0][0][1].shape[1]
    if (linear.n_inputs, linear.n_outputs) != (m, p):
        raise InvalidArgumentError(f"the start has {linear.n_inputs} inputs and "
                                   f"{linear.n_outputs} outputs; the records {m} and {p}")
    amps = np.array([steady_amplitude(g, period, discard, window) for g in groups])
    order = np.argsort(amps)
    amps = amps[order]
    if np.any(np.diff(amps) <= 1e-9 * max(amps[-1], 1e-300)):
        raise InvalidArgumentError(f"the levels' amplitudes {np.round(amps, 6).tolist()} "
                                   f"must differ")
    frfs = [estimate_bla(groups[i], period, discard=discard) for i in order]
    deltas = (amps - amps[0]) / (amps[-1] - amps[0])
    pairs, reals = _modes(linear)
    if 2 * pairs[0].size + reals[0].size != linear.order:
        raise InvalidArgumentError("the start has no modal form (repeated poles): fit it "
                                   "at another order")
    layout = _Layout(pairs[0].size, reals[0].size, p, m)
    zs = [np.exp(1j * f.omega) for f in frfs]
    n_theta = _pack(pairs, reals, linear.D).size
    K0, M0 = _start_feedback([linear.response(f.omega) for f in frfs], [f.G for f in frfs],
                             deltas)
    theta0 = np.r_[_pack(pairs, reals, linear.D), K0.ravel(), M0.ravel()]

    def unpack(theta):
        return (theta[:n_theta], theta[n_theta:n_theta + m * p].reshape(m, p),
                theta[n_theta + m * p:].reshape(m, m))

    def residual(theta):
        modal, K, M = unpack(theta)
        e = [(feedback_response(modal_response(layout, modal, z), K, M, d) - f.G).ravel()
             for z, f, d in zip(zs, frfs, deltas)]
        e = np.concatenate(e)
        return np.r_[e.real, e.imag]

    def jacobian(theta):
        modal, K, M = unpack(theta)
        blocks = []
        for z, d in zip(zs, deltas):
            G0 = modal_response(layout, modal, z)
            S = np.linalg.inv(np.eye(p) + d * G0 @ K)
            G = S @ G0 @ (np.eye(m) + d * M)
            R = np.eye(m) + d * M - d * K @ G
            J0 = modal_jacobian(layout, modal, z)
            Jm = np.einsum("kjq,kqin->kjin", S, np.einsum("kqrn,kri->kqin", J0, R))
            SG0 = S @ G0
            JK = -d * np.einsum("kja,kbi->kjiab", SG0, G).reshape(z.size, p, m, m * p)
            JM = d * np.einsum("kja,bi->kjiab", SG0, np.eye(m)).reshape(z.size, p, m, m * m)
            blocks.append(np.concatenate([Jm, JK, JM], axis=3).reshape(z.size * p * m, -1))
        J = np.vstack(blocks)
        return np.vstack([J.real, J.imag])

    cost0 = float(np.sum(residual(theta0) ** 2))
    res = least_squares(residual, theta0, jac=jacobian, method="lm", max_nfev=max_nfev)
    theta = res.x if float(np.sum(res.fun ** 2)) < cost0 else theta0
    modal, K, M = unpack(theta)
    G0 = real_modal_state_space(*modal_parameters(layout, modal))
    return feedback_scheduled(G0, K, M, (amps[0], amps[-1]), window, n_anchors)

