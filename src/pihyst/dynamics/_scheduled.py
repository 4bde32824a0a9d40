"""Amplitude-scheduled state-space model: linear MIMO dynamics whose modes move with the
amplitude of the input (a describing-function model of hysteresis inside the actuator's
mechanical loop, docs/theory/hammerstein.md).

A piezo's compliance grows with its excursion (Rayleigh's law: about linearly with the
field amplitude), so the stage's static gain rises and its resonances soften as the
drive grows. On a drive whose amplitude changes slowly, the system is, at each instant,
close to the linear system of that amplitude. The schedule is a causal running
amplitude of the inputs over about ``window`` samples (W):

    mu_i[t] = mu_i[t-1] + (u_i[t] - mu_i[t-1]) / W,
    s[t]    = s[t-1] + (mean_i (u_i[t] - mu_i[t])^2 - s[t-1]) / W,
    a[t]    = sqrt(s[t]),                       from rest: mu = 0, s = 0.

The dynamics at amplitude a, in modal form (one term per conjugate pole pair, Im > 0,
and per real pole):

    x_q[t+1] = lambda_q(a[t]) x_q[t] + b_q(a[t])^T u[t],
    y[t]     = sum_pairs 2 Re(c_q(a[t]) x_q[t]) + sum_reals c_q(a[t]) x_q[t] + D(a[t]) u[t],

each parameter piecewise linear in g(a) between the anchors a_1 < ... < a_K (the levels
it was fitted at) and held at the nearest anchor's value outside them, with

    g(a) = a^p   (p != 0),      g(a) = log a   (p = 0),

``exponent`` p (1 by default: linear in the amplitude; at a_k < a < a_k+1 the weight of
a_k+1 is (g(a) - g(a_k)) / (g(a_k+1) - g(a_k)), the same for a^p and c a^p, so p = 0,
the log, is the one shape that does not depend on which power of the amplitude is
called the amplitude). A pair's pole is interpolated in radius and angle, so it stays
inside the unit circle. At a constant amplitude a the model is the linear system
:meth:`ScheduledStateSpace.at` (a) returns.
"""

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst.dynamics._refine import real_modal_state_space
from pihyst.dynamics._statespace import StateSpace
from pihyst.exceptions import InvalidArgumentError


def running_amplitude(u: ArrayLike, window: float) -> NDArray[np.float64]:
    """The schedule a[t] of the inputs ``u`` (module notes), from rest.

    Parameters
    ----------
    u : array_like
        (N, m) inputs, or (N,) for one.
    window : float
        W, the averaging length in samples (>= 1).

    Returns
    -------
    ndarray
        (N,) the running amplitude.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import running_amplitude
    >>> u = np.sqrt(2) * np.sin(2 * np.pi * np.arange(20000) / 50)
    >>> round(float(running_amplitude(u, 500)[-1]), 2)
    1.0
    """
    from scipy.signal import lfilter

    x = np.atleast_2d(np.asarray(u, dtype=float).T).T
    if not window >= 1:
        raise InvalidArgumentError(f"window must be at least 1 sample, not {window!r}")
    g = 1.0 / float(window)
    # y[t] = y[t-1] + g (x[t] - y[t-1]):  y = g / (1 - (1 - g) q^-1) x
    mu = lfilter([g], [1.0, g - 1.0], x, axis=0)
    s = lfilter([g], [1.0, g - 1.0], np.mean((x - mu) ** 2, axis=1))
    return np.sqrt(np.maximum(s, 0.0))


def schedule_shape(a, exponent):
    """g(a) of the module notes: a^p, or log a for p = 0 (a > 0 there)."""
    a = np.asarray(a, dtype=float)
    return np.log(a) if exponent == 0 else a ** exponent


def _weights(amplitudes, a, exponent=1.0):
    """Index k and fraction f with value = (1 - f) v[k] + f v[k + 1]; clamped outside;
    f linear in g(a) = a^p (log a for p = 0)."""
    K = amplitudes.size
    if K == 1:
        return np.zeros(a.shape, int), np.zeros(a.shape)
    a = np.clip(a, amplitudes[0], amplitudes[-1])
    k = np.clip(np.searchsorted(amplitudes, a, side="right") - 1, 0, K - 2)
    g, ga = schedule_shape(a, exponent), schedule_shape(amplitudes, exponent)
    f = np.clip((g - ga[k]) / (ga[k + 1] - ga[k]), 0.0, 1.0)
    return k, f


def _blend(values, k, f):
    """(1 - f) values[k] + f values[k + 1] along the leading axis (k, f of shape (T,))."""
    if values.shape[0] == 1:
        return np.broadcast_to(values[0], k.shape + values.shape[1:])
    shape = (-1,) + (1,) * (values.ndim - 1)
    return (1 - f).reshape(shape) * values[k] + f.reshape(shape) * values[k + 1]


@dataclass(frozen=True, eq=False)
class ScheduledStateSpace:
    """Modal dynamics interpolated in the running input amplitude (module notes).

    Parameters
    ----------
    amplitudes : array_like
        (K,) the anchors a_k, strictly increasing.
    poles : array_like
        (K, P) complex: one pole of each conjugate pair (Im > 0) per anchor.
    c : array_like
        (K, P, p) complex output vectors of the pairs.
    b : array_like
        (K, P, m) complex input vectors of the pairs.
    real_poles : array_like
        (K, R) real poles.
    real_c : array_like
        (K, R, p) their output vectors.
    real_b : array_like
        (K, R, m) their input vectors.
    D : array_like
        (K, p, m) feedthrough.
    window : float
        W of the schedule, samples.
    exponent : float
        p of the interpolation's shape g(a) = a^p (0: log a; module notes); 1, linear
        in the amplitude, by default.

    Raises
    ------
    InvalidArgumentError
        Shapes that do not match, anchors not increasing, poles not inside the unit
        circle, NaN or infinite entries, an exponent that is not finite, an exponent of
        0 or below with an anchor at 0.

    Examples
    --------
    >>> import numpy as np
    >>> from pihyst.dynamics import ScheduledStateSpace
    >>> m = ScheduledStateSpace([1.0, 3.0], [[0.9j], [0.8j]], [[[1.0]], [[1.0]]],
    ...                         [[[1.0]], [[1.0]]], np.zeros((2, 0)), np.zeros((2, 0, 1)),
    ...                         np.zeros((2, 0, 1)), [[[0.0]], [[0.0]]], window=100)
    >>> round(float(np.abs(np.linalg.eigvals(m.at(2.0).A)).max()), 6)
    0.85
    """

    amplitudes: NDArray[np.float64]
    poles: NDArray[np.complex128]
    c: NDArray[np.complex128]
    b: NDArray[np.complex128]
    real_poles: NDArray[np.float64]
    real_c: NDArray[np.float64]
    real_b: NDArray[np.float64]
    D: NDArray[np.float64]
    window: float
    exponent: float = 1.0

    def __post_init__(self):
        conv = {"amplitudes": float, "poles": complex, "c": complex, "b": complex,
                "real_poles": float, "real_c": float, "real_b": float, "D": float}
        for name, kind in conv.items():
            value = np.array(getattr(self, name), dtype=kind)
            if not np.all(np.isfinite(value)):
                raise InvalidArgumentError(f"{name} holds NaN or infinite entries")
            object.__setattr__(self, name, value)
        a, D = self.amplitudes, self.D
        if a.ndim != 1 or a.size < 1 or np.any(np.diff(a) <= 0) or a[0] < 0:
            raise InvalidArgumentError(f"amplitudes must be non-negative and strictly "
                                       f"increasing, not {a.tolist()}")
        if D.ndim != 3 or D.shape[0] != a.size:
            raise InvalidArgumentError(f"D must be (K, p, m) with K = {a.size}, not {D.shape}")
        K, p, m = D.shape
        P = self.poles.shape[1] if self.poles.ndim == 2 else -1
        R = self.real_poles.shape[1] if self.real_poles.ndim == 2 else -1
        expected = {"poles": (K, P), "c": (K, P, p), "b": (K, P, m),
                    "real_poles": (K, R), "real_c": (K, R, p), "real_b": (K, R, m)}
        for name, shape in expected.items():
            if getattr(self, name).shape != shape or min(shape) < 0:
                raise InvalidArgumentError(f"{name} must have shape {shape}, not "
                                           f"{getattr(self, name).shape}")
        if np.any(np.abs(self.poles) >= 1) or np.any(np.abs(self.real_poles) >= 1):
            raise InvalidArgumentError("every pole must lie inside the unit circle")
        if np.any(self.poles.imag <= 0):
            raise InvalidArgumentError("a pair is given by its pole with Im > 0")
        if not self.window >= 1:
            raise InvalidArgumentError(f"window must be at least 1 sample, not "
                                       f"{self.window!r}")
        if not np.isfinite(self.exponent):
            raise InvalidArgumentError(f"exponent must be finite, not {self.exponent!r}")
        object.__setattr__(self, "exponent", float(self.exponent))
        if self.exponent <= 0 and a[0] <= 0 and a.size > 1:
            raise InvalidArgumentError(f"with exponent {self.exponent:g} every anchor must "
                                       f"be above 0, not {a[0]!r}")

    @property
    def n_inputs(self) -> int:
        """m."""
        return int(self.D.shape[2])

    @property
    def n_outputs(self) -> int:
        """p."""
        return int(self.D.shape[1])

    @property
    def order(self) -> int:
        """The state dimension, 2 P + R."""
        return int(2 * self.poles.shape[1] + self.real_poles.shape[1])

    def _parameters(self, a):
        """The modal parameters at the amplitudes ``a`` (T,): each with a leading T."""
        k, f = _weights(self.amplitudes, a, self.exponent)
        radius = _blend(np.abs(self.poles), k, f)
        angle = _blend(np.angle(self.poles), k, f)
        return (radius * np.exp(1j * angle), _blend(self.c, k, f), _blend(self.b, k, f),
                _blend(self.real_poles, k, f), _blend(self.real_c, k, f),
                _blend(self.real_b, k, f), _blend(self.D, k, f))

    def at(self, amplitude: float) -> StateSpace:
        """The linear system at a constant amplitude, in real modal form.

        Parameters
        ----------
        amplitude : float
            a (held at the nearest anchor outside them).

        Returns
        -------
        StateSpace
            x[t+1] = A x + B u, y = C x + D u with the parameters at ``a``.

        Examples
        --------
        >>> import numpy as np
        >>> from pihyst.dynamics import ScheduledStateSpace
        >>> m = ScheduledStateSpace([1.0, 3.0], [[0.5j], [0.7j]], [[[1.0]], [[1.0]]],
        ...                         [[[1.0]], [[1.0]]], np.zeros((2, 0)), np.zeros((2, 0, 1)),
        ...                         np.zeros((2, 0, 1)), [[[0.0]], [[0.0]]], window=100)
        >>> m.at(2.0).A.round(6).tolist()
        [[0.0, -0.6], [0.6, 0.0]]
        """
        params = self._parameters(np.array([float(amplitude)]))
        return real_modal_state_space(*(v[0] for v in params))

    def schedule(self, u: ArrayLike) -> NDArray[np.float64]:
        """The running amplitude a[t] of ``u`` (:func:`running_amplitude`).

        Parameters
        ----------
        u : array_like
            (N, m) inputs, or (N,) for one input.

        Returns
        -------
        ndarray
            (N,) the schedule.

        Examples
        --------
        >>> import numpy as np
        >>> from pihyst.dynamics import ScheduledStateSpace
        >>> m = ScheduledStateSpace([1.0, 3.0], [[0.5j], [0.7j]], [[[1.0]], [[1.0]]],
        ...                         [[[1.0]], [[1.0]]], np.zeros((2, 0)), np.zeros((2, 0, 1)),
        ...                         np.zeros((2, 0, 1)), [[[0.0]], [[0.0]]], window=100)
        >>> u = np.where(np.arange(5000) % 10 < 5, 2.0, -2.0)
        >>> round(float(m.schedule(u)[-1]), 2)     # the running mean ripples a little
        1.99
        """
        return running_amplitude(u, self.window)

    def predict(self, u: ArrayLike) -> NDArray[np.float64]:
        """The output for the input ``u``, from rest (x = 0, schedule at rest).

        Parameters
        ----------
        u : array_like
            (N, m) inputs, or (N,) for one input.

        Returns
        -------
        ndarray
            (N, p) outputs.

        Raises
        ------
        InvalidArgumentError
            ``u`` has not as many columns as the model has inputs.

        Examples
        --------
        >>> import numpy as np
        >>> from pihyst.dynamics import ScheduledStateSpace
        >>> m = ScheduledStateSpace([1.0, 3.0], [[0.5j], [0.7j]], [[[1.0]], [[1.0]]],
        ...                         [[[1.0]], [[1.0]]], np.zeros((2, 0)), np.zeros((2, 0, 1)),
        ...                         np.zeros((2, 0, 1)), [[[0.0]], [[0.0]]], window=100)
        >>> m.predict([1.0, 0.0, 0.0, 0.0]).ravel().round(6).tolist()
        [0.0, 2.0, 0.0, -0.5]
        """
        x_in = np.atleast_2d(np.asarray(u, dtype=float).T).T
        if x_in.ndim != 2 or x_in.shape[1] != self.n_inputs:
            raise InvalidArgumentError(f"the model has {self.n_inputs} inputs; u has "
                                       f"{x_in.shape[1] if x_in.ndim == 2 else '?'} columns")
        lam, c, b, lr, cr, br, D = self._parameters(self.schedule(x_in))
        # x_q[t+1] = lambda_q[t] x_q[t] + v_q[t],  v_q[t] = b_q[t]^T u[t]
        v = np.einsum("tqi,ti->tq", b, x_in)
        vr = np.einsum("tqi,ti->tq", br, x_in)
        N = x_in.shape[0]
        x = np.zeros((N, lam.shape[1]), complex)
        xr = np.zeros((N, lr.shape[1]))
        for t in range(N - 1):
            x[t + 1] = lam[t] * x[t] + v[t]
            xr[t + 1] = lr[t] * xr[t] + vr[t]
        return (2 * np.einsum("tqj,tq->tj", c, x).real + np.einsum("tqj,tq->tj", cr, xr)
                + np.einsum("tji,ti->tj", D, x_in))
