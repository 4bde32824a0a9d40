"""The Bouc-Wen hysteresis model as a value (docs/theory/bouc-wen.md).

On the normalized input x = (u - u_lo) / (u_hi - u_lo) in [0, 1], with s = sign(dx),

    y = offset + c_1 x + c_2 x^2 + a z,
    dz/dx = g_s(z) = 1 - |z|^n (s beta sign(z) + gamma)       (beta > |gamma|, n >= 1),

the rate-independent Bouc-Wen law dz = dx - beta |dx| |z|^(n-1) z - gamma dx |z|^n. Its
loops need not close, a unipolar cycle can leave a remanent displacement, and minor loops
drift: none of that is Preisach-like. The state |z| <= z_max = (beta + gamma)^(-1/n) is
invariant and g_s(z) lies in [0, D], D = 2 beta / (beta + gamma), on it, so

    dy/dx = c_1 + 2 c_2 x + a g_s(z) >= min(c_1, c_1 + 2 c_2) + min(a, 0) D

and the model is monotone (hence invertible) on every branch when that bound is >= 0.

Between two input samples the model integrates dz/dx = g_s(z) by the classical
Runge-Kutta method with m = ceil(|dx| / H) equal substeps, H = min(1/256, 1/(32 (beta +
|gamma|))); this *is* the model's definition (sample by sample, batch or inverse run the
same arithmetic); a substep across z = 0, where g_s has a kink, is split at the crossing.
Its distance to the exact ODE solution is below 1e-8 of z_max (tests/model/test_boucwen.py
checks it against the closed form for n = 1).

The model's state is (u, z): the last input and the Bouc-Wen variable.

With creep (docs/theory/creep.md) the output above is the settled displacement H, and
n first-order lags give the approach to it, exactly as for the PI models
(:class:`pihyst.model.Creep`, csrc/pihyst_creep.h (C1)-(C3)):

    z_i[t] = z_i[t-1] + alpha_i[t] (H[t] - z_i[t-1]),  alpha_i[t] = 1 - exp(-dt[t]/tau_i),
    y[t]   = H[t] - sum_i g_i (H[t] - z_i[t]).

Runs (``simulate``, ``predict``, the stepper) go through the C core
(csrc/pihyst_boucwen.c, the same arithmetic operation for operation); the functions of this
module are its Python twin, which the tests compare it against (:func:`twin_simulation`).
"""

import json
import math
import os
from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst import _boucwen_core
from pihyst._atomic import write_atomically
from pihyst.exceptions import InputRangeError, InvalidArgumentError, InvalidModelError
from pihyst.model._creep import Creep, creep_twin_run, sample_intervals
from pihyst.model._delay import (
    DelayLine,
    checked_delay,
    checked_sample_period,
    delay_at,
    delayed_input,
    pending_after,
)
from pihyst.model._models import (
    DELAY_KEYS,
    OTHER_FAMILIES,
    Immutable,
    Response,
    _finite_vector,
    checked_input,
    checked_metadata,
    checked_units,
    delay_dict,
    delay_from_dict,
    metadata_json,
    simulated,
)

FAMILY = "bouc-wen"
SCHEMA_VERSION = 1
DEFAULT_UNITS = MappingProxyType({"input": "V", "output": "um"})
MAX_SHAPE = 1000.0   # beta + |gamma| above this: the loop is a step, not a model
MAX_EXPONENT = 10.0
MIN_SPREAD = 1e-9    # beta + gamma below this: z_max = (beta + gamma)^(-1/n) is beyond use
                     # and |z|^n overflows (the C core refuses it as well)


def _number(value, name):
    if isinstance(value, (str, bytes, bool, np.bool_)):     # float() would take "1"
        raise InvalidModelError(f"{name} must be a number, got {value!r:.40}")
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError):
        raise InvalidModelError(f"{name} must be a number, got {value!r:.40}") from None
    if not math.isfinite(x):
        raise InvalidModelError(f"{name} is {x}, not a finite number")
    return x


def substep(beta, gamma):
    """H = min(1/256, 1/(32 (beta + |gamma|))): the largest Runge-Kutta substep in x."""
    return min(1.0 / 256.0, 1.0 / (32.0 * (beta + abs(gamma))))


def slope(z, s, beta, gamma, n):
    """g_s(z) = 1 - |z|^n (s beta sign(z) + gamma): dz/dx in direction s (floats or
    NumPy arrays, elementwise)."""
    p = abs(z) ** n
    # sign(z) matters only where |z|^n > 0, so copysign's sign of 0 is harmless
    sg = np.sign(z) if isinstance(z, np.ndarray) else math.copysign(1.0, z)
    return 1.0 - p * (s * beta * sg + gamma)


# 8-point Gauss-Legendre nodes and weights on [-1, 1]: numpy.polynomial.legendre.leggauss(8)
# to 17 digits, written out so that the C core (csrc/pihyst_boucwen.c) holds the same
_GL_NODES = [-0.9602898564975362, -0.7966664774136267, -0.525532409916329,
             -0.18343464249564978, 0.18343464249564978, 0.525532409916329,
             0.7966664774136267, 0.9602898564975362]
_GL_WEIGHTS = [0.10122853629037706, 0.22238103445337443, 0.3137066458778869,
               0.36268378337836166, 0.36268378337836166, 0.3137066458778869,
               0.22238103445337443, 0.10122853629037706]


def _rk4(z, k, s, beta, gamma, n):
    # z + k (g1 + 2 g2 + 2 g3 + g4) / 6
    g1 = slope(z, s, beta, gamma, n)
    g2 = slope(z + 0.5 * k * g1, s, beta, gamma, n)
    g3 = slope(z + 0.5 * k * g2, s, beta, gamma, n)
    g4 = slope(z + k * g3, s, beta, gamma, n)
    return z + k * (g1 + 2.0 * g2 + 2.0 * g3 + g4) / 6.0


def _to_zero(z, s, beta, gamma, n):
    """The input change that brings z to 0: dx_c = integral from z to 0 of dzeta / g_s,
    by 8-point Gauss-Legendre (g_s is smooth on one side of 0)."""
    half = -0.5 * z
    return half * sum(w / slope(z + half * (1.0 + t), s, beta, gamma, n)
                      for t, w in zip(_GL_NODES, _GL_WEIGHTS))


def advance(z, dx, beta, gamma, n, h=None):
    """z after an input change dx (one monotone step), by m = ceil(|dx| / H) classical
    Runge-Kutta substeps of dx / m.

    For a float z a substep that takes z across 0 (where g_s has a kink) is split there:
    the input change to reach 0 is integrated in z (:func:`_to_zero`), the rest continues
    from z = 0, so the kink costs no accuracy. ``z`` and the shape may also be NumPy arrays
    (one entry per model, all with the same substeps ``h``, kinks not split: for searches).
    """
    if dx == 0.0:
        return z
    if h is None:
        h = substep(beta, gamma)
    m = max(1, math.ceil(abs(dx) / h - 1e-9))
    s = 1.0 if dx > 0 else -1.0
    k = dx / m
    if isinstance(z, np.ndarray):
        for _ in range(m):
            z = _rk4(z, k, s, beta, gamma, n)
        return z
    for _ in range(m):
        z_new = _rk4(z, k, s, beta, gamma, n)
        if z * s < 0 < z_new * s:
            dx_c = _to_zero(z, s, beta, gamma, n)
            if abs(dx_c) < abs(k):
                z_new = _rk4(0.0, k - dx_c, s, beta, gamma, n)
        z = z_new
    return z


def _normalized_core(beta, gamma, n, x0=0.0, z0=0.0):
    """The C core's model of z alone on the normalized input (a = 1, range [0, 1]): the
    same arithmetic as :func:`advance` with the model's substeps, at C speed."""
    return _boucwen_core.BoucWen(beta, gamma, n, 1.0, 0.0, 0.0, 0.0, (0.0, 1.0), (x0, z0))


def trajectory(x, x0, z0, beta, gamma, n, h=None):
    """z at every normalized input x[t] in [0, 1], starting from (x0, z0); the shape may
    be arrays (then the result is len(x) x len(shape)). One shape with the model's own
    substeps runs in the C core."""
    if h is None and np.ndim(z0) == 0 and np.ndim(beta) == 0:
        return _normalized_core(beta, gamma, n, x0, z0).trajectory(
            np.asarray(x, dtype=np.float64))[1]
    out = np.empty((x.size,) + np.shape(z0))
    xp, z = float(x0), z0
    for t, xt in enumerate(x.tolist()):
        z = advance(z, xt - xp, beta, gamma, n, h)
        out[t] = z
        xp = xt
    return out


def cycled_z(beta, gamma, n, h=None):
    """z at rest at x = 0 after a full 0 -> 1 -> 0 cycle from the virgin state z = 0."""
    if h is None and np.ndim(beta) == 0:
        return _normalized_core(beta, gamma, n).rest_z
    z0 = np.zeros(np.shape(beta)) if np.ndim(beta) else 0.0
    return advance(advance(z0, 1.0, beta, gamma, n, h), -1.0, beta, gamma, n, h)


class BoucWenModel(Immutable):
    """Bouc-Wen hysteresis y(u) (module notes); immutable, compared by parameters.

    Parameters
    ----------
    beta, gamma : float
        Shape on the normalized input (beta > |gamma|).
    n : float
        Exponent, 1 <= n <= 10.
    hysteretic : float
        a, weight of the Bouc-Wen variable z (output units).
    linear, quadratic : float
        c_1, c_2 of the reversible part (output units at the top of the range).
    offset : float
        Output at u_lo with z = 0.
    input_range : (float, float)
        (u_lo, u_hi), default (0, 150).
    initial_state : (float, float), optional
        The state (u, z); default: at rest at u_lo after a full u_lo -> u_hi -> u_lo
        cycle.
    units : dict, optional
        Names of the units (default: {"input": "V", "output": "um"}).
    metadata : dict, optional
        Free-form notes carried with the model and its file (JSON types).
    delay : int
        Input dead time in samples (as for the PI models: y[k] = P[u](k - d)).
    sample_period : float, optional
        The sample period (s) the delay holds at.
    creep : Creep or dict, optional
        Creep lags driven by the Bouc-Wen output, which is then the settled
        displacement (module notes, docs/theory/creep.md); None: rate-independent.

    Raises
    ------
    InvalidModelError
        If a parameter is not valid (the message names it).

    Examples
    --------
    >>> import numpy as np
    >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
    >>> y = m.predict(np.r_[np.linspace(0, 150, 151), np.linspace(149, 0, 150)])
    >>> print(f"{y[0]:.3f} {y[150]:.3f} {y[-1]:.3f}")   # remanent: y(0) after the cycle
    1.326 38.674 1.326
    """

    family = FAMILY
    # set once, in __init__
    beta: float
    gamma: float
    n: float
    hysteretic: float
    linear: float
    quadratic: float
    offset: float
    input_range: tuple[float, float]
    initial_state: tuple[float, float]
    units: Mapping[str, str]
    metadata: Mapping[str, Any]
    delay: int
    sample_period: float | None
    creep: Creep | None
    _KEYS = ("beta", "gamma", "n", "hysteretic", "linear", "quadratic", "offset",
             "input_range", "initial_state", "units", "metadata", "creep")

    def __init__(self, *, beta: float, gamma: float, hysteretic: float, linear: float,
                 n: float = 1.0, quadratic: float = 0.0, offset: float = 0.0,
                 input_range: tuple[float, float] | None = None,
                 initial_state: tuple[float, float] | None = None,
                 units: Mapping[str, str] | None = None,
                 metadata: Mapping[str, Any] | None = None, delay: int = 0,
                 sample_period: float | None = None,
                 creep: "Creep | Mapping[str, Any] | None" = None) -> None:
        set_ = object.__setattr__
        for name, value in (("beta", beta), ("gamma", gamma), ("n", n),
                            ("hysteretic", hysteretic), ("linear", linear),
                            ("quadratic", quadratic), ("offset", offset)):
            set_(self, name, _number(value, name))
        if not self.beta > abs(self.gamma):
            raise InvalidModelError(f"Bouc-Wen needs beta > |gamma| (bounded loops); got "
                                    f"beta={self.beta:g}, gamma={self.gamma:g}")
        if not self.beta + abs(self.gamma) <= MAX_SHAPE:
            raise InvalidModelError(f"Bouc-Wen needs beta + |gamma| <= {MAX_SHAPE:g}")
        if not self.beta + self.gamma >= MIN_SPREAD:
            raise InvalidModelError(f"Bouc-Wen needs beta + gamma >= {MIN_SPREAD:g} (a finite "
                                    f"bound of z); got {self.beta + self.gamma:g}")
        if not 1.0 <= self.n <= MAX_EXPONENT:
            raise InvalidModelError(f"Bouc-Wen exponent n must be in [1, {MAX_EXPONENT:g}], "
                                    f"got {self.n:g}")
        try:
            lo, hi = (0.0, 150.0) if input_range is None else input_range
        except (TypeError, ValueError):
            raise InvalidModelError(f"input_range must be [min, max], got "
                                    f"{input_range!r:.60}") from None
        lo, hi = _number(lo, "input_range[0]"), _number(hi, "input_range[1]")
        if not lo < hi:
            raise InvalidModelError(f"input_range must be [min, max] with min < max, got "
                                    f"{[lo, hi]}")
        set_(self, "input_range", (lo, hi))
        if initial_state is None:
            state = (lo, cycled_z(self.beta, self.gamma, self.n))
        else:
            try:
                u0, z0 = initial_state
            except (TypeError, ValueError):
                raise InvalidModelError("initial_state must be [u, z]") from None
            state = (_number(u0, "initial_state[0]"), _number(z0, "initial_state[1]"))
            if not lo <= state[0] <= hi:
                raise InvalidModelError(f"initial_state u = {state[0]:g} is outside the input "
                                        f"range [{lo:g}, {hi:g}]")
            if abs(state[1]) > self.z_max * (1 + 1e-9):
                raise InvalidModelError(f"initial_state z = {state[1]:g} is beyond z_max = "
                                        f"{self.z_max:g}")
        set_(self, "initial_state", state)
        set_(self, "units", checked_units(units))
        set_(self, "metadata", checked_metadata(metadata))
        set_(self, "delay", checked_delay(delay))
        set_(self, "sample_period", checked_sample_period(sample_period))
        # creep lags (docs/theory/creep.md): None for a rate-independent model
        set_(self, "creep", None if creep is None else Creep.from_dict(creep))

    # ---------------------------------------------------------------- properties
    @property
    def z_max(self):
        """(beta + gamma)^(-1/n): the bound of |z| on the reachable states."""
        return (self.beta + self.gamma) ** (-1.0 / self.n)

    @property
    def n_operators(self):
        """1: one hysteresis state, z (what a comparison with the PI models' operator
        counts uses)."""
        return 1

    @property
    def min_slope(self):
        """Lower bound of dy/dx over every reachable state (module notes): the model is
        monotone, hence invertible, when it is >= 0."""
        d = 2.0 * self.beta / (self.beta + self.gamma)
        return (min(self.linear, self.linear + 2.0 * self.quadratic)
                + min(self.hysteretic, 0.0) * d)

    @property
    def is_monotone(self):
        return self.min_slope >= 0.0

    def _x(self, u):
        lo, hi = self.input_range
        return (u - lo) / (hi - lo)

    def output(self, u: Any, z: Any) -> Any:
        """y = offset + c_1 x + c_2 x^2 + a z at input u (floats or arrays).

        Parameters
        ----------
        u : float or numpy.ndarray
            Input (V).
        z : float or numpy.ndarray
            The Bouc-Wen variable.

        Returns
        -------
        float or numpy.ndarray
            The output y (µm), before creep.

        Examples
        --------
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> float(m.output(150.0, 0.0))
        40.0
        """
        x = self._x(u)
        return self.offset + self.linear * x + self.quadratic * x * x + self.hysteretic * z

    def hysteresis_output(self, state: tuple[float, float]) -> float:
        """The output at the state (u, z) without creep: the settled displacement H.

        Parameters
        ----------
        state : (float, float)
            The state (u, z).

        Returns
        -------
        float
            The output (µm) at that state, before creep.

        Examples
        --------
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> m.hysteresis_output((75.0, 0.0))
        20.0
        """
        u, z = state
        return self.output(float(u), float(z))

    # ---------------------------------------------------------------- runs
    def _checked_input(self, u):
        return checked_input(u, self.input_range)

    def _core(self, state):
        """The model in the C core (:mod:`pihyst._boucwen_core`) at ``state`` = (u, z)."""
        return _boucwen_core.BoucWen(self.beta, self.gamma, self.n, self.hysteretic,
                                     self.linear, self.quadratic, self.offset,
                                     self.input_range, state)

    def _state(self, state):
        if state is None:
            return self.initial_state
        return self.replace(initial_state=state).initial_state

    def simulate(self, u: ArrayLike, *, initial_state: tuple[float, float] | None = None,
                 t: ArrayLike | None = None, creep_state: ArrayLike | None = None,
                 pending_input: ArrayLike | None = None,
                 t_previous: float | None = None) -> Response:
        """Run over the input ``u`` from ``initial_state`` (default: the model's own);
        returns a :class:`pihyst.model.Response` whose ``final_state`` is (u, z). With a
        :attr:`delay` the input is delayed as for the PI models
        (:meth:`pihyst.model.PIModel.simulate`). With :attr:`creep`, ``t`` are the sample
        times (s; default every ``creep.dt``; ``t_previous``: the time of the sample
        before, for a following chunk), ``creep_state`` the lag state (default:
        settled at the initial output) and the response carries ``final_creep_state``, as
        for the PI models; without creep ``t`` only checks the sample period.

        Parameters
        ----------
        u : array_like
            Input samples (V), each inside :attr:`input_range`.
        initial_state : (float, float), optional
            The state (u, z) before ``u`` (default: the model's own).
        t : array_like, optional
            Sample times (s), for creep and to check the period of a delayed model.
        creep_state : array_like, optional
            Creep lag states before ``u`` (default: settled at the initial output).
        pending_input : array_like, optional
            With a delay of d samples: the d inputs before ``u`` (default: u[0] held).
        t_previous : float, optional
            Time (s) of the sample before ``u``, for the first creep interval.

        Returns
        -------
        pihyst.model.Response
            Input, output, final state (u, z), and final creep state, pending input.

        Raises
        ------
        InputRangeError
            If an input sample is outside :attr:`input_range` (or not finite).
        InvalidArgumentError
            If an argument is malformed (not numbers, wrong length or period).

        Examples
        --------
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> r = m.simulate([0.0, 150.0])
        >>> float(r.final_state[0])
        150.0
        """
        def hysteresis(state, run):
            core = self._core(state)
            return core.run(run), np.array(core.state)

        return simulated(self, u, self._state(initial_state), hysteresis, t=t,
                         creep_state=creep_state, pending_input=pending_input,
                         t_previous=t_previous)

    def twin_simulation(self, u: ArrayLike, *, initial_state: tuple[float, float] | None = None,
                        t: ArrayLike | None = None, creep_state: ArrayLike | None = None,
                        pending_input: ArrayLike | None = None) -> Response:
        """:meth:`simulate` by the Python twin of the C core (this module's functions and,
        with creep, :func:`creep_twin_run`): the reference the tests compare the C core
        against; slow.

        Parameters
        ----------
        u : array_like
            Input samples (V), each inside :attr:`input_range`.
        initial_state : (float, float), optional
            The state (u, z) before ``u`` (default: the model's own).
        t : array_like, optional
            Sample times (s), for creep and to check the period of a delayed model.
        creep_state : array_like, optional
            Creep lag states before ``u`` (default: settled at the initial output).
        pending_input : array_like, optional
            With a delay of d samples: the d inputs before ``u`` (default: u[0] held).

        Returns
        -------
        pihyst.model.Response
            As :meth:`simulate` returns it, to rounding.

        Raises
        ------
        InputRangeError
            If an input sample is outside :attr:`input_range` (or not finite).
        InvalidArgumentError
            If an argument is malformed (not numbers, wrong length or period).

        Examples
        --------
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> u = [0.0, 75.0, 150.0, 75.0]
        >>> bool(abs(m.twin_simulation(u).output - m.predict(u)).max() < 1e-9)
        True
        """
        x = self._checked_input(u)
        d = self.delay_at(t=t)
        if d and pending_input is not None:
            pending_input = self._checked_input(pending_input)
        run = delayed_input(x, d, pending_input)
        u0, z0 = self._state(initial_state)
        # the substep given explicitly: trajectory() would hand one shape to the C core
        z = trajectory(self._x(run), self._x(u0), z0, self.beta, self.gamma, self.n,
                       h=substep(self.beta, self.gamma))
        final = (float(run[-1]), float(z[-1])) if x.size else (u0, z0)
        h = self.output(run, z)
        pending = pending_after(x, d, pending_input) if d else None
        if self.creep is None:
            return Response(input=x, output=h, final_state=np.array(final),
                            pending_input=pending)
        lags = self._lag_state((u0, z0), creep_state)
        dt = None if t is None else sample_intervals(t, x.size, self.creep.dt)
        y = creep_twin_run(self.creep, lags, h, dt)
        return Response(input=x, output=y, final_state=np.array(final),
                        final_creep_state=lags, pending_input=pending)

    def predict(self, u: ArrayLike, *, initial_state: tuple[float, float] | None = None,
                t: ArrayLike | None = None, creep_state: ArrayLike | None = None,
                pending_input: ArrayLike | None = None,
                t_previous: float | None = None) -> NDArray[np.float64]:
        """Displacements for the inputs ``u``: the output of :meth:`simulate`.

        Parameters
        ----------
        u : array_like
            Input samples (V), each inside :attr:`input_range`.
        initial_state : (float, float), optional
            The state (u, z) before ``u`` (default: the model's own).
        t : array_like, optional
            Sample times (s), for creep and to check the period of a delayed model.
        creep_state : array_like, optional
            Creep lag states before ``u`` (default: settled at the initial output).
        pending_input : array_like, optional
            With a delay of d samples: the d inputs before ``u`` (default: u[0] held).
        t_previous : float, optional
            Time (s) of the sample before ``u``, for the first creep interval.

        Returns
        -------
        numpy.ndarray
            The displacement at each sample (µm), as long as ``u``.

        Raises
        ------
        InputRangeError
            If an input sample is outside :attr:`input_range` (or not finite).
        InvalidArgumentError
            If an argument is malformed (not numbers, wrong length or period).

        Examples
        --------
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> m.predict([0.0, 150.0]).round(3).tolist()
        [1.326, 38.674]
        """
        return self.simulate(u, initial_state=initial_state, t=t, creep_state=creep_state,
                             pending_input=pending_input, t_previous=t_previous).output

    def _lag_state(self, state, creep_state):
        """The lag state z_i: ``creep_state`` checked, or settled at the output of the
        state (u, z)."""
        if creep_state is None:
            return np.full(self.creep.n_lags, self.hysteresis_output(state))
        return np.array(_finite_vector(creep_state, "creep_state", self.creep.n_lags))

    def _lags(self, state, creep_state):
        """The C creep lags (:meth:`pihyst.model.Creep.lags`) from ``creep_state``
        (None: settled at the output of the state (u, z))."""
        return self.creep.lags(self._lag_state(state, creep_state))

    def delay_at(self, sample_period: float | None = None, *,
                 t: ArrayLike | None = None) -> int:
        """The delay in samples at another sample period (see
        :meth:`pihyst.model.PIModel.delay_at`).

        Parameters
        ----------
        sample_period : float, optional
            The sample period (s) to convert the delay to.
        t : array_like, optional
            Uniform sample times (s), whose period is used instead.

        Returns
        -------
        int
            The delay in samples at that period.

        Raises
        ------
        InvalidArgumentError
            If the delay is not a whole number of samples at that period.

        Examples
        --------
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0, delay=1,
        ...                  sample_period=0.01)
        >>> m.delay_at(0.005)
        2
        """
        return delay_at(self.delay, self.sample_period, sample_period, t)

    def stepper(self, initial_state: tuple[float, float] | None = None, *,
                creep_state: ArrayLike | None = None, pending_input: ArrayLike | None = None,
                sample_period: float | None = None) -> "BoucWenStepper":
        """A :class:`BoucWenStepper`: the model sample by sample (with a delay, through
        a FIFO of d inputs; with creep, from the lag state ``creep_state``).

        Parameters
        ----------
        initial_state : (float, float), optional
            The state (u, z) before the first step (default: the model's own).
        creep_state : array_like, optional
            Creep lag states before the first step (default: settled).
        pending_input : array_like, optional
            With a delay of d samples: the d inputs before the first step.
        sample_period : float, optional
            The period (s) the stepper is stepped at, to convert the delay.

        Returns
        -------
        BoucWenStepper
            A stepper owning its own running state.

        Examples
        --------
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> s = m.stepper()
        >>> round(s.step(150.0), 3)
        38.674
        """
        return BoucWenStepper(self, initial_state, creep_state, pending_input=pending_input,
                              sample_period=sample_period)

    # ---------------------------------------------------------------- values
    def _params(self):
        return {"beta": self.beta, "gamma": self.gamma, "n": self.n,
                "hysteretic": self.hysteretic, "linear": self.linear,
                "quadratic": self.quadratic, "offset": self.offset,
                "input_range": self.input_range, "initial_state": self.initial_state,
                "units": dict(self.units), "metadata": dict(self.metadata),
                "delay": self.delay, "sample_period": self.sample_period,
                "creep": self.creep}

    def replace(self, **changes: Any) -> "BoucWenModel":
        """A copy with some constructor arguments changed.

        Parameters
        ----------
        **changes
            Constructor arguments by name, and their new values.

        Returns
        -------
        BoucWenModel
            The changed copy (its rest state follows a changed shape).

        Raises
        ------
        InvalidModelError
            If a name is not a constructor argument or a value is not valid.

        Examples
        --------
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> m.replace(offset=1.0).offset
        1.0
        """
        params = self._params()
        unknown = sorted(set(changes) - set(params))
        if unknown:
            raise InvalidModelError(f"BoucWenModel has no parameter {unknown[0]!r}")
        shape = {"beta", "gamma", "n", "input_range"}
        if shape & set(changes) and "initial_state" not in changes and \
                self.initial_state == (self.input_range[0],
                                       cycled_z(self.beta, self.gamma, self.n)):
            params["initial_state"] = None     # the rest state follows the new shape
        params.update(changes)
        return type(self)(**params)

    def _key(self):
        p = self._params()
        p.pop("metadata")
        p["units"] = tuple(sorted(p["units"].items()))
        return (self.family,) + tuple(p.items())

    def __eq__(self, other):
        if not isinstance(other, BoucWenModel):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def __repr__(self):
        parts = [f"{k}={self._params()[k]:.6g}" for k in
                 ("beta", "gamma", "n", "hysteretic", "linear", "quadratic", "offset")]
        if self.input_range != (0.0, 150.0):
            parts.append(f"input_range={self.input_range!r}")
        if self.delay:
            parts.append(f"delay={self.delay}")
        if self.sample_period is not None:
            parts.append(f"sample_period={self.sample_period:.6g}")
        if self.creep is not None:
            parts.append(f"creep={self.creep!r}")
        return f"BoucWenModel({', '.join(parts)})"

    def to_dict(self) -> dict[str, Any]:
        """The model as a JSON-ready dict (docs/interfaces.md, family "bouc-wen").

        Returns
        -------
        dict
            Plain JSON types only; :meth:`from_dict` reads it back.

        Examples
        --------
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> BoucWenModel.from_dict(m.to_dict()) == m
        True
        """
        d = {"schema_version": SCHEMA_VERSION, "family": FAMILY,
             **{k: getattr(self, k) for k in ("beta", "gamma", "n", "hysteretic", "linear",
                                                "quadratic", "offset")},
             "input_range": list(self.input_range),
             "initial_state": list(self.initial_state), "units": dict(self.units)}
        if self.creep is not None:
            d["creep"] = self.creep.to_dict()
        d.update(delay_dict(self))
        if self.metadata:
            d["metadata"] = metadata_json(self.metadata)
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], source: str = "model") -> "BoucWenModel":
        """A model from its JSON dict; errors name ``source`` and the key.

        Parameters
        ----------
        d : dict
            The model in the JSON schema (docs/interfaces.md, family "bouc-wen").
        source : str, default "model"
            Where ``d`` comes from, for the error messages (e.g. a file name).

        Returns
        -------
        BoucWenModel
            The model ``d`` describes.

        Raises
        ------
        InvalidModelError
            If ``d`` does not describe a valid model (the message names the key).

        Examples
        --------
        >>> d = {"family": "bouc-wen", "beta": 5, "gamma": 1, "hysteretic": -8,
        ...      "linear": 40}
        >>> BoucWenModel.from_dict(d).linear
        40.0
        """
        if not isinstance(d, dict):
            raise InvalidModelError(f"{source}: a model must be a JSON object")
        if d.get("family") != FAMILY:
            raise InvalidModelError(f"{source}: family {d.get('family')!r:.40} is not "
                                    f"{FAMILY!r}")
        version = d.get("schema_version", SCHEMA_VERSION)
        if version != SCHEMA_VERSION:
            raise InvalidModelError(f"{source}: schema_version {version!r:.20} is not "
                                    f"{SCHEMA_VERSION} (written by another pihyst version)")
        for key in ("beta", "gamma", "hysteretic", "linear"):
            if key not in d:
                raise InvalidModelError(f"{source}: missing required key {key!r}")
        allowed = {*cls._KEYS, *DELAY_KEYS}
        unknown = sorted(set(d) - allowed - {"family", "schema_version"})
        if unknown:
            raise InvalidModelError(f"{source}: unknown key {unknown[0]!r} for family "
                                    f"{FAMILY!r} (allowed: {', '.join(sorted(allowed))})")
        try:
            return cls(**{k: d[k] for k in cls._KEYS if k in d}, **delay_from_dict(d))
        except InvalidModelError as err:
            raise InvalidModelError(f"{source}: {err}") from None
        except (TypeError, ValueError, OverflowError) as err:
            raise InvalidModelError(f"{source}: {err}") from None

    def save(self, path: "str | os.PathLike[str]") -> None:
        """Write the model as JSON to ``path`` (the file appears only once complete).

        Parameters
        ----------
        path : str or os.PathLike
            The file to write.

        Raises
        ------
        OSError
            If the file cannot be written.

        Examples
        --------
        >>> import pathlib, tempfile
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> m.save(pathlib.Path(tempfile.mkdtemp()) / "bw.json")
        """
        write_atomically(path, json.dumps(self.to_dict(), indent=2) + "\n")


OTHER_FAMILIES[FAMILY] = BoucWenModel


class BoucWenStepper:
    """A :class:`BoucWenModel` run sample by sample; owns the running state (u, z).

    Parameters
    ----------
    model : BoucWenModel
        The model to run.
    initial_state : (float, float), optional
        The state (u, z) before the first step (default: the model's own).
    creep_state : array_like, optional
        With creep: the lag states before the first step (default: settled).
    pending_input : array_like, optional
        With a delay of d samples: the d inputs before the first step.
    sample_period : float, optional
        The period (s) it is stepped at, to convert the model's delay.

    Examples
    --------
    >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
    >>> s = m.stepper()
    >>> round(s.step(150.0), 3) == round(float(m.predict([150.0])[0]), 3)
    True
    """

    def __init__(self, model: BoucWenModel, initial_state: tuple[float, float] | None = None,
                 creep_state: ArrayLike | None = None, *, pending_input: ArrayLike | None = None,
                 sample_period: float | None = None) -> None:
        self.model = model
        self._initial = model._state(initial_state)
        self._core = model._core(self._initial)
        # with creep: the lags, settled at the initial output unless given
        self._initial_creep = creep_state
        self._lags = None if model.creep is None else model._lags(self._initial, creep_state)
        #: the input dead time in samples (a FIFO of that many inputs)
        self.delay = model.delay_at(sample_period)
        if self.delay and pending_input is not None:
            pending_input = model._checked_input(pending_input)
        self._line = DelayLine(self.delay, pending_input)

    @property
    def state(self):
        """(u, z) after the last sample applied (with a delay: d samples back)."""
        return np.array(self._core.state)

    @property
    def creep_state(self):
        """The creep lag states z_i (a copy; None for a model without creep)."""
        return None if self._lags is None else self._lags.state

    def reset(self, state: tuple[float, float] | None = None,
              creep_state: ArrayLike | None = None) -> None:
        """Back to ``state`` (default: the initial state); with creep, the lags to
        ``creep_state`` (default: settled at that state's output, or the stepper's own
        initial lags when neither is given); the delay FIFO to its start.

        Parameters
        ----------
        state : (float, float), optional
            The state (u, z) to go back to (default: the initial state).
        creep_state : array_like, optional
            The creep lag states (default: see above).

        Raises
        ------
        InvalidModelError
            If ``state`` is not a valid state (u, z).

        Examples
        --------
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> s = m.stepper(); _ = s.step(150.0); s.reset()
        >>> s.state.tolist() == list(m.initial_state)
        True
        """
        if state is None and creep_state is None:
            creep_state = self._initial_creep
        self._core.state = self._initial if state is None else self.model._state(state)
        if self._lags is not None:
            self._lags = self.model._lags(self._core.state, creep_state)
        self._line.reset()

    def output_at(self, u: float) -> float:
        """The output if the next sample applied were ``u`` (the state is not changed;
        with a delay, ``u`` is the input leaving the FIFO; with creep, the settled
        output H, the lags aside).

        Parameters
        ----------
        u : float
            The candidate input (V).

        Returns
        -------
        float
            The output (µm) that input would give.

        Examples
        --------
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> s = m.stepper()
        >>> s.output_at(150.0) == s.step(150.0)
        True
        """
        m = self.model
        u_p, z_p = self._core.state
        z = self._core.advance(z_p, m._x(u) - m._x(u_p))
        return m.output(u, z)

    def step(self, u: float, dt: float | None = None) -> float:
        """One sample: advance the state by the input ``u`` (with a delay of d samples,
        by the input of d steps ago), return y.

        Parameters
        ----------
        u : float
            The input sample (V), inside the model's input range.
        dt : float, optional
            With creep: the time (s) since the previous sample (default ``creep.dt``).

        Returns
        -------
        float
            The output y (µm).

        Raises
        ------
        InputRangeError
            If ``u`` is outside the model's input range.
        InvalidArgumentError
            If ``u`` or ``dt`` is not a number (``dt`` not finite and >= 0).

        Examples
        --------
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> round(m.stepper().step(150.0), 3)
        38.674
        """
        try:
            u = float(u)
        except (TypeError, ValueError, OverflowError):
            raise InvalidArgumentError(f"input must be a number, got {u!r:.40}") from None
        lo, hi = self.model.input_range
        if not lo <= u <= hi:
            raise InputRangeError(0, u, self.model.input_range)
        h = self._core.step(self._line.push(u))
        if self._lags is None:
            return h
        if dt is not None:
            dt = float(dt)
            if not (math.isfinite(dt) and dt >= 0):
                raise InvalidArgumentError(f"dt must be a finite interval >= 0 s, got {dt}")
        return self._lags.step(h, dt)
