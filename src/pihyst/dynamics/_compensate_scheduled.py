"""Feedforward compensation of an amplitude-scheduled state-space model for a periodic
trajectory (:class:`ScheduledStateSpace`; docs/theory/hammerstein.md).

The convention is :func:`compensate_mimo`'s: one period r (N, p) of a trajectory that
repeats, one period of voltages u (N, m) back, square models (m = p), the whole period as
preview, so that zeros outside the unit circle are inverted without approximation.

**Periodic steady state.** Played over and over, a period u gives a periodic schedule
a[t] (the running amplitude of the module :mod:`._scheduled`, its first-order filters
in their periodic solution) and, for that schedule, the modes' periodic solution: with
x^0 the recursion x[t+1] = lambda[t] x[t] + v[t] (v[t] = b(a[t])^T u[t]) run over one
period from x = 0 and Phi = prod_t lambda[t] (each mode on its own, the model being
modal),

    x[0] = x^0[N] / (1 - Phi),     x[t] = x^0[t] + (prod_{s<t} lambda[s]) x[0],

and y[t] = C(a[t]) x[t] + D(a[t]) u[t]. Write y = L_a u: for a fixed schedule the map is
linear (periodically time-varying), and the model's output for u is F(u) = L_{a(u)} u.

**The inverse.** F(u) = r is solved by a fixed point on the schedule,

    u_0 = G_abar^-1 r,                       abar = mean a(u_0) (itself a fixed point),
    u_{k+1} = T(u_k) = L_{a(u_k)}^-1 r,

each linear solve exact (GMRES on L_a G_abar^-1 w = r, u = G_abar^-1 w, from u_k), where
G_abar^-1 is the inverse per harmonic of the linear model at the mean amplitude,
``model.at(abar)``, as :func:`compensate_mimo` inverts a linear model (least squares
where G is singular): U(k) = G(z_k)^-1 R(k), z_k = exp(2 pi i k / N). The iteration
stops when |F(u) - r| is below ``tol`` of r's RMS. The plain iteration converges when
the schedule's effect is a contraction (the gain changing less than in proportion to
the amplitude: on the FSM a few per cent from 100 to 300 mV); it is Anderson-mixed,

    f_k = T(u_k) - u_k,   gamma = argmin |f_k - dF gamma|,
    u_{k+1} = u_k + f_k - (dU + dF) gamma,

dU, dF the differences of the last ANDERSON_DEPTH + 1 iterates and f's, which also
converges where the plain iteration oscillates (a gain rising 8x and 20x across a 6x
range of amplitude, in the tests); the result says whether it converged.

**Limits.** The voltages never leave [u_min, u_max] (per input). Where the exact u
would, it is clipped and improved by projected steps,

    u <- clip(u + G_abar^-1 (r - F(u)), u_min, u_max),

keeping the best; the result says ``saturated`` and its ``rms_error``. A desired output
that no voltages within the limits can produce, by the bound

    |y_j| <= sum_i (sum_q 2 |c_qj|* |b_qi|* / (1 - |lambda_q|*) + |D_ji|*) U_i,

(* the largest over the anchors, U_i = max(|u_min_i|, |u_max_i|); valid at every
amplitude, the parameters being interpolated between anchors), is refused with a
one-line error, as are NaN or infinite entries.
"""

import inspect
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst.dynamics._scheduled import ScheduledStateSpace
from pihyst.exceptions import InvalidArgumentError

TOLERANCE = 1e-10        # |F(u) - r| / RMS(r) at which the iteration stops
MAX_ITERATIONS = 30      # of the schedule's fixed point, and of the projected steps
AMPLITUDE_ITERATIONS = 20
ANDERSON_DEPTH = 3       # earlier steps the fixed point's mixing uses


@dataclass(frozen=True)
class ScheduledCompensation:
    """What :func:`compensate_scheduled` returns.

    Parameters
    ----------
    voltage : ndarray
        (N, m) one period of voltages, within the limits.
    schedule : ndarray
        (N,) the periodic schedule a[t] of those voltages.
    output : ndarray
        (N, p) the model's periodic output for them.
    rms_error : float
        RMS of ``output - desired``.
    amplitude : float
        abar, the mean amplitude of the first pass.
    iterations : int
        Steps of the schedule's fixed point (and projected steps, when saturated).
    converged : bool
        ``rms_error`` reached ``tol`` of the desired's RMS.
    saturated : bool
        The exact voltages would leave the limits: clipped, tracking not exact.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import ScheduledStateSpace, compensate_scheduled
    >>> m = ScheduledStateSpace([2.0], [[0.5j]], [[[1.0]]], [[[1.0]]], np.zeros((1, 0)),
    ...                         np.zeros((1, 0, 1)), np.zeros((1, 0, 1)), [[[0.0]]],
    ...                         window=20)
    >>> r = 3 * np.sin(2 * np.pi * np.arange(50) / 50)[:, None]
    >>> res = compensate_scheduled(m, r, u_min=-1.0, u_max=1.0)   # needs more than 1 V
    >>> res.saturated, bool(np.abs(res.voltage).max() <= 1.0), res.rms_error > 0.1
    (True, True, True)
    """

    voltage: NDArray[np.float64]
    schedule: NDArray[np.float64]
    output: NDArray[np.float64]
    rms_error: float
    amplitude: float
    iterations: int
    converged: bool
    saturated: bool


def _periodic_first_order(x, g):
    """The periodic solution of y[t] = (1 - g) y[t-1] + g x[t] along axis 0."""
    from scipy.signal import lfilter
    rho = 1.0 - g
    y0 = lfilter([g], [1.0, -rho], x, axis=0)
    n = x.shape[0]
    decay = rho ** np.arange(1, n + 1)
    if x.ndim > 1:
        decay = decay.reshape((-1,) + (1,) * (x.ndim - 1))
    return y0 + decay * (y0[-1] / (1.0 - rho ** n))


def periodic_schedule(model: ScheduledStateSpace, u: ArrayLike) -> NDArray[np.float64]:
    """The schedule a[t] of one period ``u`` (N, m) repeated for ever (module notes).

    Parameters
    ----------
    model : ScheduledStateSpace
        The model (its ``window``).
    u : array_like
        (N, m) one period of inputs.

    Returns
    -------
    ndarray
        (N,) the periodic schedule, what ``model.schedule`` gives after many periods.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import ScheduledStateSpace
    >>> from pihyst.dynamics._compensate_scheduled import periodic_schedule
    >>> m = ScheduledStateSpace([2.0], [[0.5j]], [[[1.0]]], [[[1.0]]], np.zeros((1, 0)),
    ...                         np.zeros((1, 0, 1)), np.zeros((1, 0, 1)), [[[0.0]]],
    ...                         window=20)
    >>> u = np.sin(2 * np.pi * np.arange(50) / 50)[:, None]
    >>> a = periodic_schedule(m, u)
    >>> bool(np.allclose(a, m.schedule(np.tile(u, (40, 1)))[-50:]))
    True
    """
    u = np.asarray(u, dtype=float)
    g = 1.0 / float(model.window)
    mu = _periodic_first_order(u, g)
    s = _periodic_first_order(np.mean((u - mu) ** 2, axis=1), g)
    return np.sqrt(np.maximum(s, 0.0))


def periodic_response(model: ScheduledStateSpace, u: ArrayLike,
                      schedule: ArrayLike | None = None) -> NDArray[np.float64]:
    """y = L_a u of the module notes: the periodic output for one period ``u`` repeated,
    with the schedule ``a`` (default: u's own, :func:`periodic_schedule`).

    Parameters
    ----------
    model : ScheduledStateSpace
        The model.
    u : array_like
        (N, m) one period of inputs.
    schedule : array_like, optional
        (N,) a periodic schedule to hold fixed.

    Returns
    -------
    ndarray
        (N, p) one period of the periodic output.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import ScheduledStateSpace
    >>> from pihyst.dynamics._compensate_scheduled import periodic_response
    >>> m = ScheduledStateSpace([0.1, 1.0], [[0.5j], [0.8j]], [[[1.0]], [[2.0]]],
    ...                         [[[1.0]], [[1.0]]], np.zeros((2, 0)), np.zeros((2, 0, 1)),
    ...                         np.zeros((2, 0, 1)), [[[0.0]], [[0.1]]], window=20)
    >>> u = np.sin(2 * np.pi * np.arange(50) / 50)[:, None]
    >>> y = periodic_response(m, u)
    >>> bool(np.allclose(y, m.predict(np.tile(u, (40, 1)))[-50:]))
    True
    """
    u = np.asarray(u, dtype=float)
    a = periodic_schedule(model, u) if schedule is None else np.asarray(schedule, float)
    return _FixedSchedule(model, a)(u)


class _FixedSchedule:
    """L_a of the module notes for one schedule: the parameters and the products of the
    poles computed once, applied to many inputs (GMRES)."""

    def __init__(self, model, a):
        lam, self.c, b, lr, self.cr, br, self.D = model._parameters(a)
        self.pairs = lam.shape[1]
        # pairs and real modes in one complex recursion
        self.lam = np.concatenate([lam, lr.astype(complex)], axis=1)
        self.b = np.concatenate([b, br.astype(complex)], axis=1)
        n = a.shape[0]
        self.phi = np.ones((n + 1, self.lam.shape[1]), complex)
        for t in range(n):
            self.phi[t + 1] = self.lam[t] * self.phi[t]

    def __call__(self, u):
        v = np.einsum("tqi,ti->tq", self.b, u)
        n = u.shape[0]
        x = np.zeros((n + 1, v.shape[1]), complex)
        lam = self.lam
        for t in range(n):
            x[t + 1] = lam[t] * x[t] + v[t]
        # x[0] = x^0[N] / (1 - Phi); x[t] = x^0[t] + prod_{s<t} lambda[s] x[0]
        x = x[:n] + self.phi[:n] * (x[n] / (1.0 - self.phi[n]))
        P = self.pairs
        return (2 * np.einsum("tqj,tq->tj", self.c, x[:, :P]).real
                + np.einsum("tqj,tq->tj", self.cr, x[:, P:].real)
                + np.einsum("tji,ti->tj", self.D, u))


def _harmonic_inverse(model, amplitude, n):
    """G_abar(z_k)^-1 per rfft line, (n // 2 + 1, m, p): the pseudo-inverse where singular."""
    w = 2 * np.pi * np.arange(n // 2 + 1) / n
    return np.linalg.pinv(model.at(amplitude).response(w), rcond=1e-12)


def _apply(Ginv, r):
    """irfft(Ginv(k) rfft(r)(k)) along axis 0."""
    R = np.fft.rfft(r, axis=0)
    return np.fft.irfft(np.einsum("kij,kj->ki", Ginv, R), n=r.shape[0], axis=0)


def _per_input(value, m, name):
    if value is None:
        raise InvalidArgumentError(f"{name} is needed: a ScheduledStateSpace has no input "
                                   f"range (one value or one per input)")
    try:
        values = np.atleast_1d(np.asarray(value, dtype=float))
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"{name}: one number or one per input ({m})") from None
    if values.size == 1:
        values = np.repeat(values.ravel(), m)
    if values.shape != (m,):
        raise InvalidArgumentError(f"{name}: one value or one per input ({m}), got "
                                   f"{values.size}")
    if not np.all(np.isfinite(values)):
        raise InvalidArgumentError(f"{name} must be finite, got {values.tolist()}")
    return values


def output_bound(model: ScheduledStateSpace, u_min: ArrayLike,
                 u_max: ArrayLike) -> NDArray[np.float64]:
    """The bound of the module notes on |y_j| for any voltages within the limits, at any
    schedule: (p,).

    Parameters
    ----------
    model : ScheduledStateSpace
        The model.
    u_min, u_max : array_like
        (m,) the limits.

    Returns
    -------
    ndarray
        (p,) no output of the model exceeds it in magnitude.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import ScheduledStateSpace
    >>> from pihyst.dynamics._compensate_scheduled import output_bound
    >>> m = ScheduledStateSpace([2.0], [[0.5j]], [[[1.0]]], [[[1.0]]], np.zeros((1, 0)),
    ...                         np.zeros((1, 0, 1)), np.zeros((1, 0, 1)), [[[0.0]]],
    ...                         window=20)
    >>> output_bound(m, [-1.0], [1.0]).tolist()     # 2 |c| |b| / (1 - 0.5)
    [4.0]
    """
    U = np.maximum(np.abs(np.asarray(u_min, float)), np.abs(np.asarray(u_max, float)))
    top = np.max(np.abs(model.poles), axis=0, initial=0.0)
    top_r = np.max(np.abs(model.real_poles), axis=0, initial=0.0)
    c, b = np.max(np.abs(model.c), axis=0), np.max(np.abs(model.b), axis=0)
    cr, br = np.max(np.abs(model.real_c), axis=0), np.max(np.abs(model.real_b), axis=0)
    gain = (2 * np.einsum("qj,qi,q->ji", c, b, 1.0 / (1.0 - top))
            + np.einsum("qj,qi,q->ji", cr, br, 1.0 / (1.0 - top_r))
            + np.max(np.abs(model.D), axis=0))
    return gain @ U


def _check_desired(desired, p, bound):
    try:
        r = np.asarray(desired, dtype=float)
    except (TypeError, ValueError):
        raise InvalidArgumentError("desired must be an (N, p) array of numbers") from None
    if r.ndim != 2 or r.shape[1] != p or r.shape[0] < 2:
        raise InvalidArgumentError(f"desired must be (N, {p}): one column per output, "
                                   f"N >= 2, got shape {r.shape}")
    bad = np.argwhere(~np.isfinite(r))
    if bad.size:
        t, j = bad[0]
        raise InvalidArgumentError(f"desired[{t}, {j}] is {r[t, j]}: every entry must be "
                                   f"finite")
    over = np.argwhere(np.abs(r) > bound * (1 + 1e-9))
    if over.size:
        t, j = over[0]
        raise InvalidArgumentError(f"desired[{t}, {j}] = {r[t, j]:.6g} is beyond what the "
                                   f"model can reach within the limits (|y_{j}| <= "
                                   f"{bound[j]:.6g})")
    return r


def _gmres(matvec, rhs, x0, atol, size):
    from scipy.sparse.linalg import LinearOperator, gmres
    op = LinearOperator((size, size), matvec=matvec, dtype=float)
    rel = "rtol" if "rtol" in inspect.signature(gmres).parameters else "tol"
    w, _ = gmres(op, rhs, x0=x0, atol=atol, restart=60, maxiter=20, **{rel: 0.0})
    return w


def compensate_scheduled(model: ScheduledStateSpace, desired: ArrayLike, *,
                         u_min: ArrayLike, u_max: ArrayLike, tol: float = TOLERANCE,
                         max_iterations: int = MAX_ITERATIONS) -> ScheduledCompensation:
    """Voltages that make a square :class:`ScheduledStateSpace` follow one period of a
    repeated trajectory, within per-input limits (module notes).

    Parameters
    ----------
    model : ScheduledStateSpace
        As many inputs as outputs.
    desired : array_like
        (N, p) one period of every output's trajectory.
    u_min, u_max : float or array_like
        Voltage limits: one value or one per input (required: the model has no input
        range).
    tol : float
        Stop when the RMS tracking error is below ``tol`` of the desired's RMS.
    max_iterations : int
        At most this many steps of the schedule's fixed point (and as many projected
        steps when the limits bind).

    Returns
    -------
    ScheduledCompensation
        ``voltage`` (N, m), and how well the model follows it.

    Raises
    ------
    InvalidArgumentError
        A model that is not square; ``desired`` of the wrong shape, with NaN or infinite
        entries, or beyond what the limits can reach (the bound of the module notes);
        limits missing, of the wrong size, not finite or not u_min < u_max.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import ScheduledStateSpace, compensate_scheduled
    >>> m = ScheduledStateSpace([0.1, 1.0], [[0.5j], [0.8j]], [[[1.0]], [[2.0]]],
    ...                         [[[1.0]], [[1.0]]], np.zeros((2, 0)), np.zeros((2, 0, 1)),
    ...                         np.zeros((2, 0, 1)), [[[0.0]], [[0.1]]], window=20)
    >>> r = np.sin(2 * np.pi * np.arange(50) / 50)[:, None]
    >>> res = compensate_scheduled(m, r, u_min=-5.0, u_max=5.0)
    >>> y = m.predict(np.tile(res.voltage, (40, 1)))[-50:]
    >>> bool(np.allclose(y, r)), res.saturated
    (True, False)
    """
    if not isinstance(model, ScheduledStateSpace):
        raise InvalidArgumentError(f"compensate_scheduled needs a ScheduledStateSpace, got "
                                   f"{type(model).__name__}")
    m, p = model.n_inputs, model.n_outputs
    if m != p:
        raise InvalidArgumentError(f"compensate_scheduled needs as many inputs as outputs, "
                                   f"got {m} input(s) and {p} output(s)")
    lo, hi = _per_input(u_min, m, "u_min"), _per_input(u_max, m, "u_max")
    if np.any(lo >= hi):
        raise InvalidArgumentError(f"u_min must be below u_max on every input, got "
                                   f"{lo.tolist()} and {hi.tolist()}")
    if not (isinstance(max_iterations, int) and max_iterations >= 1):
        raise InvalidArgumentError(f"max_iterations must be an integer >= 1, not "
                                   f"{max_iterations!r}")
    if not 0 < tol < 1:
        raise InvalidArgumentError(f"tol must be in (0, 1), not {tol!r}")
    r = _check_desired(desired, p, output_bound(model, lo, hi))
    n = r.shape[0]
    scale = float(np.sqrt(np.mean(r ** 2)))
    if scale == 0.0:
        u = np.clip(np.zeros((n, m)), lo, hi)
        return _result(model, r, u, 0.0, 0, True, bool(np.any(u != 0)))
    # first pass: the linear model at its own voltages' mean amplitude (a fixed point)
    abar = float(np.mean(model.amplitudes))
    for _ in range(AMPLITUDE_ITERATIONS):
        Ginv = _harmonic_inverse(model, abar, n)
        u = _apply(Ginv, r)
        new = float(np.mean(periodic_schedule(model, u)))
        done = abs(new - abar) <= 1e-9 * max(abar, 1e-300)
        abar = new
        if done:
            break
    Ginv = _harmonic_inverse(model, abar, n)
    G = model.at(abar).response(2 * np.pi * np.arange(n // 2 + 1) / n)
    u = _apply(Ginv, r)

    def error(v):
        return float(np.sqrt(np.mean((periodic_response(model, v) - r) ** 2)))

    # the schedule's fixed point T(u) = L_{a(u)}^-1 r, each solve exact, Anderson-mixed
    best, best_err, iterations = u, error(u), 0
    us: list[NDArray[np.float64]] = []
    fs: list[NDArray[np.float64]] = []
    while best_err > tol * scale and iterations < max_iterations:
        iterations += 1
        L = _FixedSchedule(model, periodic_schedule(model, u))

        def matvec(w, L=L):
            return L(_apply(Ginv, w.reshape(n, m))).ravel()

        w = _gmres(matvec, r.ravel(), _apply(G, u).ravel(),
                   0.1 * tol * scale * np.sqrt(n * p), n * m)
        f = (_apply(Ginv, w.reshape(n, m)) - u).ravel()
        us, fs = (us + [u.ravel()])[-ANDERSON_DEPTH - 1:], (fs + [f])[-ANDERSON_DEPTH - 1:]
        step = f
        if len(fs) > 1:
            dF = np.diff(np.array(fs), axis=0).T
            dU = np.diff(np.array(us), axis=0).T
            gamma = np.linalg.lstsq(dF, f, rcond=None)[0]
            step = f - (dU + dF) @ gamma
        u = u + step.reshape(n, m)
        if not np.all(np.isfinite(u)):
            break
        err = error(u)
        if err < best_err:
            best, best_err = u, err
        elif err > 100 * best_err:
            break                         # the iteration diverges: keep the best
    u = best
    if np.all((u >= lo) & (u <= hi)):
        return _result(model, r, u, abar, iterations, best_err <= tol * scale, False)
    # the exact voltages leave the limits: projected steps from the clipped ones
    u = np.clip(np.where(np.isfinite(u), u, 0.0), lo, hi)
    residual = r - periodic_response(model, u)
    best, best_err = u, float(np.sqrt(np.mean(residual ** 2)))
    for _ in range(max_iterations):
        u = np.clip(u + _apply(Ginv, residual), lo, hi)
        residual = r - periodic_response(model, u)
        err = float(np.sqrt(np.mean(residual ** 2)))
        if err < best_err:
            best, best_err = u, err
    return _result(model, r, best, abar, iterations + max_iterations, best_err <= tol * scale, True)


def _result(model, r, u, abar, iterations, converged, saturated):
    y = periodic_response(model, u)
    return ScheduledCompensation(voltage=u, schedule=periodic_schedule(model, u), output=y,
                                 rms_error=float(np.sqrt(np.mean((y - r) ** 2))),
                                 amplitude=abar, iterations=iterations, converged=converged,
                                 saturated=saturated)


def compensate_mimo_scheduled(model: Any, desired: ArrayLike, u_min: Any, u_max: Any,
                              slew_rate: Any) -> tuple[NDArray[np.float64],
                                                       NDArray[np.float64], list[Any]]:
    """:func:`compensate_mimo`'s answer for a ScheduledStateSpace: (voltage, voltage,
    [ScheduledCompensation]) (the dynamics' input is the voltage itself)."""
    if slew_rate is not None:
        raise InvalidArgumentError("slew_rate is not supported for a ScheduledStateSpace "
                                   "(compensate_scheduled: voltage limits only)")
    res = compensate_scheduled(model, desired, u_min=u_min, u_max=u_max)
    return res.voltage, res.voltage, [res]
