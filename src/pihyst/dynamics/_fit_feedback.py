"""One model for several drive amplitudes whose amplitude dependence is a feedback
loop inside the actuator: fixed linear dynamics G_0 = C (zI - A)^-1 B + D, and a
signal of their state fed back to their own input through a gain that grows linearly
with the running input amplitude (docs/theory/hammerstein.md).

A piezo's compliance grows about linearly with its excursion (Rayleigh's law): the
actuator pushes back less, in proportion to the amplitude, i.e. a force proportional to
its own elongation z = C_z x, applied where the actuator drives the structure (through
B, like the drive). In the describing-function view, at running amplitude a (the
schedule of :mod:`._scheduled`):

    v = u - delta z,   z = C_z x,   x[t+1] = A x + B v,   y = C x + D v,
    delta = (a - a_1) / (a_L - a_1),

so that, with H_z = C_z (zI - A)^-1 B (m x m, G_0's poles and input vectors),

    G(a) = G_0 (I + delta H_z)^-1,

G_0 the system at the lowest level's amplitude a_1 and C_z (m x n) the loop reached at
the highest level a_L. G_0 is fitted on every level's records at once; the amplitude
dependence is the m n numbers of C_z: the resonances move through the one loop, and
each mode's shape (its c, b) changes only as the loop makes it.

The fit, on the levels' best linear approximations G_l(k):

1. G_0 starts from the given linear model (e.g. the lowest level's own fit);
2. C_z starts from the equation error, linear in it: G_l (I + delta_l H_z) = G_0
   <=> delta_l G_l H_z = G_0 - G_l, least squares over lines and levels;
3. G_0's modal parameters (:mod:`._refine`) and C_z's (one complex vector per pole
   pair, a real one per real pole) together by Levenberg-Marquardt on
   sum_l sum_k || G(z_k; delta_l) - G_l(k) ||_F^2, analytic Jacobian:
   dG = dG_0 S - delta G dH_z S,  S = (I + delta H_z)^-1.

The loop at delta is the state-space model

    A_d = A - delta B C_z,  B_d = B,  C_d = C - delta D C_z,  D_d = D,

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


def feedback_response(G0, Hz, delta):
    """G_0 (I + delta H_z)^-1 on every line (G0 (L, p, m), Hz (L, m, m))."""
    Hz = np.asarray(Hz)
    return np.asarray(G0) @ np.linalg.inv(np.eye(Hz.shape[-1]) + delta * Hz)


def closed_loop(model: StateSpace, Cz, delta) -> StateSpace:
    """The state-space model of the loop at ``delta`` (module notes)."""
    Cz = np.asarray(Cz, dtype=float)
    return StateSpace(model.A - delta * model.B @ Cz, model.B,
                      model.C - delta * model.D @ Cz, model.D)


def _loop_layout(layout):
    """The layout of H_z's modal parameters (m outputs), and where each of its columns
    lies among the fit's parameters (G_0's, then C_z's); -1: H_z's D, held at 0."""
    P, R, p, m = layout.shape
    lz = _Layout(P, R, m, m)
    e, ez = layout.edges, lz.edges
    n0 = e[-1]
    own = [np.arange(e[0], e[1]), np.arange(e[1], e[2]),                     # rho, phi
           n0 + np.arange(2 * P * m),                                         # c_z re, im
           np.arange(e[4], e[6]), np.arange(e[6], e[7]),                      # b, sigma
           n0 + 2 * P * m + np.arange(R * m),                                 # real c_z
           np.arange(e[8], e[9]), np.full(ez[10] - ez[9], -1)]                # real b, D
    return lz, np.concatenate(own), n0 + (2 * P + R) * m


def _loop_theta(layout, lz, theta, n0):
    """H_z's packed parameters: G_0's poles and b, the loop's c_z, D = 0."""
    P, R, p, m = layout.shape
    e = layout.edges
    cz = theta[n0:]
    return np.concatenate([theta[e[0]:e[2]], cz[:2 * P * m], theta[e[4]:e[7]],
                           cz[2 * P * m:], theta[e[8]:e[9]], np.zeros(m * m)])


def _start_loop(layout, lz, theta, zs, blas, deltas, n0, where):
    """C_z from the equation error (module notes, step 2)."""
    rows, rhs = [], []
    loop_cols = where >= n0
    for z, G, d in zip(zs, blas, deltas):
        if d == 0:
            continue
        G0 = modal_response(layout, theta[:n0], z)
        # H_z is linear in c_z: its Jacobian columns are the basis
        basis = modal_jacobian(lz, _loop_theta(layout, lz, theta, n0), z)[..., loop_cols]
        A = d * np.einsum("kja,kain->kjin", G, basis).reshape(-1, basis.shape[-1])
        r = (G0 - G).reshape(-1)
        rows.append(np.vstack([A.real, A.imag]))
        rhs.append(np.r_[r.real, r.imag])
    x = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)[0]
    out = np.zeros(where.max() + 1 - n0)
    out[where[loop_cols] - n0] = x
    return out


def _match_modes(prev, lam, c, b):
    """Order the pairs (lam, c, b) like the poles ``prev`` (nearest, one to one)."""
    from scipy.optimize import linear_sum_assignment

    _, col = linear_sum_assignment(np.abs(prev[:, None] - lam[None, :]))
    return lam[col], c[col], b[col]


def feedback_scheduled(linear: StateSpace, Cz, amplitudes, window: float,
                       n_anchors: int = 9) -> ScheduledStateSpace:
    """The loop of ``linear`` with ``Cz`` (module notes) at ``n_anchors`` amplitudes
    from ``amplitudes[0]`` (delta 0) to ``amplitudes[1]`` (delta 1), as a
    :class:`~pihyst.dynamics.ScheduledStateSpace`.

    Raises
    ------
    FitError
        The loop is unstable at some anchor, or its poles change kind (real or pair)
        between the anchors.
    """
    a1, a2 = float(amplitudes[0]), float(amplitudes[1])
    params: list[tuple[np.ndarray, ...]] = []
    for delta in np.linspace(0.0, 1.0, n_anchors):
        ss = closed_loop(linear, Cz, delta)
        radius = np.abs(np.linalg.eigvals(ss.A)).max() if ss.order else 0.0
        if not radius < 1:
            raise FitError(f"the feedback loop is unstable at delta {delta:.3f} "
                           f"(spectral radius {radius:.6f})")
        (lam, c, b), (lr, cr, br) = _modes(ss)
        if params and (lam.size != params[0][0].size or lr.size != params[0][3].size):
            raise FitError(f"the loop's poles change kind (real or pair) at delta "
                           f"{delta:.3f}")
        if params:
            lam, c, b = _match_modes(params[-1][0], lam, c, b)
        order = np.argsort(lr)
        params.append((lam, c, b, lr[order], cr[order], br[order], ss.D))
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
    """One model of records at several drive amplitudes: fixed dynamics with a signal
    of their state fed back to their input through a gain linear in the amplitude
    (module notes).

    Parameters
    ----------
    levels : sequence of iterables of (array_like, array_like)
        Per drive level, its ``(u, y)`` periodic multisine records (at least m per
        level); at least two levels of different amplitudes, the same lines excited.
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
    lz, where, n_theta = _loop_layout(layout)
    n0 = layout.edges[-1]
    kept = where >= 0
    zs = [np.exp(1j * f.omega) for f in frfs]
    theta0 = np.r_[_pack(pairs, reals, linear.D), np.zeros(n_theta - n0)]
    theta0[n0:] = _start_loop(layout, lz, theta0, zs, [f.G for f in frfs], deltas, n0,
                              where)

    def residual(theta):
        e = []
        for z, f, d in zip(zs, frfs, deltas):
            Hz = modal_response(lz, _loop_theta(layout, lz, theta, n0), z)
            e.append((feedback_response(modal_response(layout, theta[:n0], z), Hz, d)
                      - f.G).ravel())
        e = np.concatenate(e)
        return np.r_[e.real, e.imag]

    def jacobian(theta):
        blocks = []
        tz = _loop_theta(layout, lz, theta, n0)
        for z, d in zip(zs, deltas):
            G0 = modal_response(layout, theta[:n0], z)
            S = np.linalg.inv(np.eye(m) + d * modal_response(lz, tz, z))
            G = G0 @ S
            J = np.zeros((z.size, p, m, n_theta), complex)
            # dG = dG_0 S - delta G dH_z S
            J[..., :n0] = np.einsum("kjan,kai->kjin", modal_jacobian(layout, theta[:n0], z), S)
            if d != 0:
                Jz = modal_jacobian(lz, tz, z)[..., kept]
                J[..., where[kept]] -= d * np.einsum(
                    "kja,kabn,kbi->kjin", G, Jz, S, optimize=True)
            blocks.append(J.reshape(z.size * p * m, -1))
        J = np.vstack(blocks)
        return np.vstack([J.real, J.imag])

    cost0 = float(np.sum(residual(theta0) ** 2))
    res = least_squares(residual, theta0, jac=jacobian, method="lm", max_nfev=max_nfev)
    theta = res.x if float(np.sum(res.fun ** 2)) < cost0 else theta0
    G0 = real_modal_state_space(*modal_parameters(layout, theta[:n0]))
    Cz = real_modal_state_space(*modal_parameters(lz, _loop_theta(layout, lz, theta, n0))).C
    return feedback_scheduled(G0, Cz, (amps[0], amps[-1]), window, n_anchors)
