"""Compensation of a Bouc-Wen model: the voltage that makes it produce a desired output.

From the state (u_p, z_p) the output for the next voltage u is

    Y(u) = offset + c_1 x + c_2 x^2 + a Z(u),   Z(u) = z after the monotone step u_p -> u

(the model's own Runge-Kutta arithmetic, docs/theory/bouc-wen.md). A monotone model
(``model.is_monotone``) has Y non-decreasing on both sides of u_p, with Y(u_p) the current
output. The compensator solves Y(u) = y_d between u_p and the reachable end
[max(u_min, u_p - slew), min(u_max, u_p + slew)] by Newton steps from u_p, evaluating the
end only when a step would reach or pass it; once y_d is bracketed, Newton steps that stay
inside and halve the step before last, else bisection (:meth:`_solve`), until the
bracket is two adjacent floats or |Y(u) - y_d| <= 4 eps (|y_d| + |offset| + |c_1| +
|c_2| + |a| z_max): the inverse is exact to that tolerance. Where Y is flat at y_d (a
model at its monotone bound) the voltage is one of the flat stretch. Out of reach: the
voltage saturates at the bracket's end and is flagged (limit or slew); NaN holds the last
voltage. The flags are those of :mod:`pihyst.inverse._compensator`, and so is the result.

:class:`BoucWenCompensator` runs in the C core (csrc/pihyst_boucwen.c, the same algorithm
operation for operation); :class:`BoucWenCompensatorTwin` is its Python twin, the
reference the tests compare it against.

A model with creep (docs/theory/creep.md) is inverted as a PI model with creep is: its
output y = (1 - beta) H + sum_i g_i (1 - alpha_i) z_i is affine in the Bouc-Wen output H
at each sample, so each sample first finds the hysteresis target

    H* = (y_d - sum_i g_i (1 - alpha_i) z_i) / (1 - beta)                     (C5)

then the voltage for H* as above (limits, slew and flags unchanged), then advances the
lags by the H reached (csrc/pihyst_bw_creep.c; the twin: pihyst.model._creep's
``creep_twin_*``).
"""

import math

import numpy as np
from numpy.typing import ArrayLike

from pihyst import _boucwen_core
from pihyst.exceptions import InvalidArgumentError
from pihyst.inverse._compensator import (
    FLAG_NAN,
    FLAG_SATURATED_HIGH,
    FLAG_SATURATED_LOW,
    FLAG_SLEW,
    OTHER_COMPENSATORS,
    CompensationResult,
    _desired,
    _number,
    run_result,
    slew_per_sample,
)
from pihyst.model import InvalidModelError
from pihyst.model._boucwen import BoucWenModel, advance, slope
from pihyst.model._creep import creep_twin_step, creep_twin_target, sample_intervals
from pihyst.model._models import _finite_vector

_EPS = np.finfo(float).eps
MAX_ITERATIONS = 200
NEWTON_FIRST = 8      # Newton steps from u_p before the reachable end must be evaluated


class BoucWenCompensatorTwin:
    """Streaming exact inverse of a :class:`pihyst.model.BoucWenModel`, with voltage
    limits and a slew limit; the same interface as :class:`pihyst.Compensator`. In
    Python: the twin of the C core's :class:`BoucWenCompensator`. Given an
    ``initial_state`` (u, z) without an ``initial_voltage``, it starts at that state's u
    (within the limits).

    Examples
    --------
    >>> from pihyst.model import BoucWenModel
    >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
    >>> comp = BoucWenCompensatorTwin(m, slew_rate=1e5, sample_period=1e-4)
    >>> u = comp.step(20.0)            # 10 V per sample is all 100 kV/s allows
    >>> u, comp.last_flags == comp.FLAG_SLEW
    (10.0, True)
    >>> u = comp.step(5.0)             # within reach: exact
    >>> round(u, 6), abs(comp.displacement - 5.0) < 1e-12
    (18.667945, True)
    """

    FLAG_SATURATED_LOW = FLAG_SATURATED_LOW
    FLAG_SATURATED_HIGH = FLAG_SATURATED_HIGH
    FLAG_NAN = FLAG_NAN
    FLAG_SLEW = FLAG_SLEW

    def __init__(self, model: BoucWenModel, *, u_min: float | None = None,
                 u_max: float | None = None, slew_rate: float | None = None,
                 initial_voltage: float | None = None,
                 initial_state: tuple[float, float] | None = None,
                 creep_state: ArrayLike | None = None,
                 sample_period: float | None = None) -> None:
        if not isinstance(model, BoucWenModel):
            raise InvalidArgumentError(f"model must be a BoucWenModel, not {type(model).__name__}")
        if not model.is_monotone:
            raise InvalidModelError(f"compensation needs a monotone model: the slope bound "
                                    f"min(c_1, c_1 + 2 c_2) + min(a, 0) D is "
                                    f"{model.min_slope:g} < 0")
        self.model = model
        lo, hi = model.input_range
        u_min = lo if u_min is None else _number(u_min, "u_min")
        u_max = hi if u_max is None else _number(u_max, "u_max")
        if not lo <= u_min < u_max <= hi:
            raise InvalidArgumentError(f"voltage limits [{u_min:g}, {u_max:g}] must satisfy u_min "
                                       f"< u_max inside the model's input range [{lo:g}, {hi:g}]")
        self.limits = (u_min, u_max)
        self.slew_rate, self.sample_period, self.max_step = slew_per_sample(
            slew_rate, model, sample_period)
        u0, z0 = model._state(initial_state)
        if initial_voltage is None:
            # a state given is at rest at its own voltage: 0 V applied would move it
            initial_voltage = min(max(0.0 if initial_state is None else u0, u_min), u_max)
        initial_voltage = _number(initial_voltage, "initial_voltage")
        if not u_min <= initial_voltage <= u_max:
            raise InvalidArgumentError(f"initial_voltage {initial_voltage:g} is outside the "
                                       f"voltage limits [{u_min:g}, {u_max:g}]")
        # the initial voltage is applied to the initial state
        z0 = advance(z0, model._x(initial_voltage) - model._x(u0), model.beta, model.gamma,
                     model.n)
        self._start = (initial_voltage, z0)
        scale = (abs(model.offset) + abs(model.linear) + abs(model.quadratic)
                 + abs(model.hysteretic) * model.z_max)
        self._scale = scale
        self._start_creep = creep_state
        self.reset()

    @property
    def delay(self):
        """The model's input delay in samples: ``step`` takes the target that many
        samples ahead (as :class:`pihyst.Compensator`)."""
        return self.model.delay

    @property
    def state(self):
        """(u, z) after the last voltage."""
        return np.array([self._u, self._z])

    @property
    def voltage(self):
        return self._u

    @property
    def displacement(self):
        """The model's output at the last voltage (with creep: at the last sample)."""
        return self._h() if self.model.creep is None else self._output

    def _h(self):
        """The Bouc-Wen output (without creep) at the last voltage."""
        return self.model.output(self._u, self._z)

    @property
    def creep_state(self):
        """The creep lag states (a copy; None for a model without creep)."""
        return None if self.model.creep is None else np.array(self._lags)

    @property
    def last_flags(self):
        return self._flags

    def _start_lags(self, creep_state):
        """With creep: the lag state from ``creep_state``, or settled at the output now."""
        if self.model.creep is None:
            if creep_state is not None:
                raise InvalidArgumentError("the bouc-wen model has no creep: creep_state "
                                           "does not apply")
            return
        n = self.model.creep.n_lags
        self._output = self._h()
        z = (np.full(n, self._output) if creep_state is None else
             _finite_vector(creep_state, "creep_state", n))
        self._set_lags(z)

    def _set_lags(self, z):
        self._lags = [float(v) for v in z]

    def _dt(self, dt):
        """The checked interval of one sample (None: the creep's fixed one)."""
        if dt is None:
            return None
        dt = _number(dt, "dt")
        if dt < 0:
            raise InvalidArgumentError(f"dt must be >= 0 s, got {dt:g}")
        return dt

    def _intervals(self, n, t, t_previous):
        """Per-sample intervals of a block of n samples at times ``t`` (None: the fixed
        one), the first ``creep.dt`` after the last sample or ``t[0] - t_previous``."""
        if t is None:
            return None
        first = self.model.creep.dt
        if t_previous is not None and n:
            first = float(np.asarray(t, dtype=np.float64)[0]) - float(t_previous)
        try:
            return sample_intervals(t, n, first)
        except ValueError as err:
            raise InvalidArgumentError(str(err)) from None

    def reset(self, state: tuple[float, float] | None = None, voltage: float | None = None,
              creep_state: ArrayLike | None = None) -> None:
        """Back to the initial state and voltage, or to ``state`` = (u, z) and ``voltage``
        (with creep: the lags to ``creep_state``, default settled at the output).

        Parameters
        ----------
        state : (float, float), optional
            The state (u, z) to go to (default: the initial state).
        voltage : float, optional
            A voltage to apply to it, within the limits.
        creep_state : array_like, optional
            With creep: the lag states.

        Raises
        ------
        InvalidArgumentError
            If the voltage is outside the limits.

        Examples
        --------
        >>> from pihyst.model import BoucWenModel
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> comp = BoucWenCompensatorTwin(m)
        >>> _ = comp.step(5.0); comp.reset(); comp.voltage
        0.0
        """
        if state is None and voltage is None and creep_state is None:
            creep_state = self._start_creep
        self._reset_hysteresis(state, voltage)
        self._start_lags(creep_state)

    def _reset_hysteresis(self, state, voltage):
        if state is None:
            self._u, self._z = self._start
        else:
            self._u, self._z = self.model._state(state)
        if voltage is not None:
            voltage = _number(voltage, "voltage")
            lo, hi = self.limits
            if not lo <= voltage <= hi:
                raise InvalidArgumentError(f"voltage {voltage:g} is outside the limits [{lo:g}, "
                                           f"{hi:g}]")
            m = self.model
            self._z = advance(self._z, m._x(voltage) - m._x(self._u), m.beta, m.gamma, m.n)
            self._u = voltage
        self._flags = 0

    def _beyond_limit(self, end, y_end, z_end, limit, yd, s):
        """Whether yd is out of reach at the voltage limit, beyond the slew window's end
        (Y(end) = y_end with z_end, yd past it in direction s): decided by the bounds of
        Y(limit) (z moves from z_end towards s z_max, and Y by at least min_slope per
        unit of x) where yd is clearly on one side (by 1e-3 of the output scale), else by
        evaluating Y(limit), as beyond_limit of csrc/pihyst_boucwen.c."""
        m = self.model
        margin = 1e-3 * self._scale
        x_limit = m._x(limit)
        p = m.offset + m.linear * x_limit + m.quadratic * x_limit * x_limit
        y_from, y_to = p + m.hysteretic * z_end, p + m.hysteretic * (s * m.z_max)
        reach = y_end + s * m.min_slope * abs(x_limit - m._x(end))
        nearest, farthest = (y_from, y_to) if (y_from - y_to) * s < 0 else (y_to, y_from)
        if (reach - nearest) * s > 0:
            nearest = reach
        if (yd - nearest) * s < -margin:
            return False
        if (yd - farthest) * s > margin:
            return True
        return (self._y(limit)[0] - yd) * s < 0

    def _y(self, u):
        m = self.model
        z = advance(self._z, m._x(u) - m._x(self._u), m.beta, m.gamma, m.n)
        return m.output(u, z), z

    def step(self, y_desired: float, dt: float | None = None) -> float:
        """The voltage for one desired output (applied to the state).

        Parameters
        ----------
        y_desired : float
            The desired output (µm; any value: out of reach saturates, NaN holds).
        dt : float, optional
            With creep: the time (s) since the previous sample (default
            ``model.creep.dt``).

        Returns
        -------
        float
            The voltage, within the limits and the slew limit.

        Examples
        --------
        >>> from pihyst.model import BoucWenModel
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> u = BoucWenCompensator(m).step(5.0)
        >>> round(u, 6)
        18.667945
        """
        yd = float(y_desired)
        creep = self.model.creep
        if creep is None:
            return self._step(yd)
        dt = self._dt(dt)
        u = self._step(creep_twin_target(creep, self._lags, yd, dt))      # (C5)
        self._output = creep_twin_step(creep, self._lags, self._h(), dt)
        return u

    def _step(self, yd):
        """The voltage for the Bouc-Wen output ``yd`` (applied to the state)."""
        m = self.model
        if math.isnan(yd):
            self._flags = FLAG_NAN
            return self._u
        up = self._u
        yp = m.output(up, self._z)
        lo, hi = self.limits
        slew = math.inf if self.max_step is None else self.max_step
        if yd == yp:
            self._flags = 0
            return up
        s = 1.0 if yd > yp else -1.0
        end = min(hi, up + slew) if s > 0 else max(lo, up - slew)
        while abs(end - up) > slew:        # rounding of u_p +- slew: stay within the limit
            end = math.nextafter(end, up)
        self._u, self._z, self._flags = self._solve(up, end, yd, s)
        return self._u

    def _solve(self, a, end, yd, s):
        # a = u_p (Y(a) before yd); Newton steps from there. The reachable end is
        # evaluated only when a step would reach or pass it (or after NEWTON_FIRST steps
        # without a bracket): out of reach there, the voltage stops at the end; else
        # [a, b] brackets yd (Y(a) before, Y(b) past it) while Newton or bisection steps
        # shrink it: Newton where its step stays in the bracket and is at most half the
        # step before last, else bisection (so the bracket at least halves every two
        # steps, and Newton converging from one side is not interrupted). A tracking step
        # thus costs a few short model steps, not a long one.
        m = self.model
        span = m.input_range[1] - m.input_range[0]
        tol = 4 * _EPS * (abs(yd) + self._scale)

        def newton(u, z, err):
            x = m._x(u)
            dy = (m.linear + 2 * m.quadratic * x
                  + m.hysteretic * slope(z, s, m.beta, m.gamma, m.n)) / span
            return u - err / dy if dy > 0 else math.nan

        u = newton(a, self._z, m.output(a, self._z) - yd)
        dx = dx_old = abs(end - a)
        b = z_b = None
        for i in range(MAX_ITERATIONS):
            if b is None and (not min(a, end) < u < max(a, end) or i >= NEWTON_FIRST):
                y_end, z_end = self._y(end)
                if (y_end - yd) * s <= 0:      # out of reach (or just reached) at the end
                    limit = self.limits[1] if s > 0 else self.limits[0]
                    saturated = FLAG_SATURATED_HIGH if s > 0 else FLAG_SATURATED_LOW
                    if y_end == yd:
                        flags = 0
                    elif end == limit:
                        flags = saturated
                    else:
                        # cut short by the slew limit; out of reach too if the voltage
                        # limit itself misses yd (out of reach does not depend on the slew)
                        flags = FLAG_SLEW | (saturated if self._beyond_limit(
                            end, y_end, z_end, limit, yd, s) else 0)
                    return end, z_end, flags
                b, z_b = end, z_end
            if b is not None and not min(a, b) < u < max(a, b):
                u = 0.5 * (a + b)
            y, z = self._y(u)
            err = y - yd
            if abs(err) <= tol:
                return u, z, 0
            if err * s < 0:
                a = u
            else:
                b, z_b = u, z
            if b is None:
                u = newton(u, z, err)
                continue
            if abs(b - a) <= 2 * _EPS * max(abs(a), abs(b), 1e-300):
                break
            step = newton(u, z, err)
            dx_old = dx
            if min(a, b) < step < max(a, b) and abs(step - u) <= 0.5 * dx_old:
                dx = abs(step - u)
                u = step
            else:
                u = 0.5 * (a + b)
                dx = 0.5 * abs(b - a)
        return b, z_b, 0

    def run(self, y_desired: ArrayLike, t: ArrayLike | None = None,
            t_previous: float | None = None) -> CompensationResult:
        """Compensate a block of desired outputs, continuing from the current state.

        Parameters
        ----------
        y_desired : array_like
            Desired outputs (µm), one per sample (any values).
        t, t_previous : array_like, float, optional
            With creep: as for :meth:`pihyst.Compensator.run` (ignored without).

        Returns
        -------
        pihyst.inverse.CompensationResult
            Voltages, outputs, flags, and the states before and after.

        Raises
        ------
        InvalidArgumentError
            If ``y_desired`` is not a vector of numbers.

        Examples
        --------
        >>> from pihyst.model import BoucWenModel
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> r = BoucWenCompensatorTwin(m).run([5.0, 100.0])
        >>> r.flags.tolist()
        [0, 2]
        """
        yd = _desired(y_desired)
        initial_state, initial_voltage = self.state, self.voltage
        initial_creep = self.creep_state
        dt = None if self.model.creep is None else self._intervals(yd.size, t, t_previous)
        u, y, flags = self._run(yd, dt)
        return run_result(self, yd, u, y, flags, initial_state, initial_voltage,
                          initial_creep_state=initial_creep,
                          final_creep_state=self.creep_state)

    def _run(self, yd, dt):
        u = np.empty(yd.size)
        y = np.empty(yd.size)
        flags = np.zeros(yd.size, dtype=np.uint8)
        for i, v in enumerate(yd.tolist()):
            u[i] = self.step(v, None if dt is None else dt[i])
            y[i] = self.displacement
            flags[i] = self._flags
        return u, y, flags

    def __repr__(self):
        slew = "" if self.slew_rate is None else \
            f", slew_rate={self.slew_rate:g} V/s at {self.sample_period:g} s"
        return (f"{type(self).__name__}(limits=[{self.limits[0]:g}, {self.limits[1]:g}]"
                f"{slew}, voltage={self.voltage:g})")


class BoucWenCompensator(BoucWenCompensatorTwin):
    """Streaming exact inverse of a :class:`pihyst.model.BoucWenModel`, with voltage
    limits and a slew limit; the same interface as :class:`pihyst.Compensator`. Runs in
    the C core; :class:`BoucWenCompensatorTwin` is the same algorithm in Python.

    Parameters
    ----------
    model : BoucWenModel
        A monotone Bouc-Wen model (``model.is_monotone``).
    u_min, u_max : float, optional
        Voltage limits, inside the model's input range (default: that range).
    slew_rate : float, optional
        Largest voltage change, V/s (default none), a step of ``slew_rate *
        sample_period`` per sample.
    initial_voltage : float, optional
        The voltage before the first sample (default 0 V within the limits; with
        ``initial_state`` given, that state's u within the limits).
    initial_state : (float, float), optional
        The state (u, z) before the first sample (default: the model's own).
    creep_state : array_like, optional
        For a model with creep: the lag states before the first sample.
    sample_period : float, optional
        Seconds per sample, for the slew limit (default: the model's sample period or
        its creep's dt; an error when a slew limit has none).

    Raises
    ------
    InvalidModelError
        If the model is not monotone.
    InvalidArgumentError
        If the model is not a Bouc-Wen model, or a limit is not valid.

    Examples
    --------
    >>> from pihyst.model import BoucWenModel
    >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
    >>> comp = BoucWenCompensator(m, slew_rate=1e5, sample_period=1e-4)
    >>> u = comp.step(20.0)            # 10 V per sample is all 100 kV/s allows
    >>> u, comp.last_flags == comp.FLAG_SLEW
    (10.0, True)
    >>> u = comp.step(5.0)             # within reach: exact
    >>> round(u, 6), abs(comp.displacement - 5.0) < 1e-12
    (18.667945, True)
    """

    @property
    def state(self):
        return np.array(self._core_model.state)

    @property
    def voltage(self):
        return self._core_model.state[0]

    def _h(self):
        u, z = self._core_model.state
        return self.model.output(u, z)

    @property
    def creep_state(self):
        return None if self.model.creep is None else self._lags.state

    @property
    def last_flags(self):
        return self._core.last_flags

    def _set_lags(self, z):
        c = self.model.creep
        self._lags = _boucwen_core.CreepCompensator(c.tau, c.gain, c.dt, z)

    def _reset_hysteresis(self, state, voltage):
        start = self._start if state is None else self.model._state(state)
        if voltage is not None:
            voltage = _number(voltage, "voltage")
            lo, hi = self.limits
            if not lo <= voltage <= hi:
                raise InvalidArgumentError(f"voltage {voltage:g} is outside the limits [{lo:g}, "
                                           f"{hi:g}]")
        if not hasattr(self, "_core"):
            slew = math.inf if self.max_step is None else self.max_step
            self._core_model = self.model._core(self._start)
            self._core = _boucwen_core.BoucWenCompensator(
                self._core_model, *self.limits, slew, self._start[0])
        # the state as given (its u may lie outside the voltage limits), then the voltage
        self._core_model.state = start
        if voltage is not None:
            self._core.reset(start, voltage)

    def step(self, y_desired: float, dt: float | None = None) -> float:
        """The voltage for one desired output (applied to the state).

        Parameters
        ----------
        y_desired : float
            The desired output (µm; any value: out of reach saturates, NaN holds).
        dt : float, optional
            With creep: the time (s) since the previous sample (default
            ``model.creep.dt``).

        Returns
        -------
        float
            The voltage, within the limits and the slew limit.

        Examples
        --------
        >>> from pihyst.model import BoucWenModel
        >>> m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
        >>> u = BoucWenCompensator(m).step(5.0)
        >>> round(u, 6)
        18.667945
        """
        yd = float(y_desired)
        if self.model.creep is None:
            return self._core.step(yd)
        dt = self._dt(dt)
        u, y, _ = self._lags.compensate(self._core, np.array([yd]),
                                        None if dt is None else np.array([dt]))
        self._output = float(y[0])
        return float(u[0])

    def _run(self, yd, dt):
        if self.model.creep is None:
            return self._core.run(yd)
        u, y, flags = self._lags.compensate(self._core, yd, dt)
        if y.size:
            self._output = float(y[-1])
        return u, y, flags


OTHER_COMPENSATORS[BoucWenModel.family] = BoucWenCompensator
