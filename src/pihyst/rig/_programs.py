"""What the loop drives, tick by tick: a voltage signal (record), a desired trajectory
through pihyst's compensator (track), or that plus PID feedback (track --feedback).

A program has ``n_ticks``, ``reference_unit``, ``initial_voltage()`` (where the start
ramp goes), ``start()`` (called when the ramp has arrived), ``command(k, measured_um)``
-> ``(reference, volts)`` and ``describe()``.
"""

import math

import numpy as np

from pihyst.exceptions import InvalidArgumentError
from pihyst.inverse import compensator_for


def _samples(values, what):
    """``values`` as a float array; InvalidArgumentError naming ``what`` if they are not
    numbers."""
    try:
        return np.asarray(values, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise InvalidArgumentError(f"{what} must be a sequence of numbers") from None


def creep_at_tick(model, period_s):
    """``model`` with its creep lags stepped every ``period_s`` (itself without creep, or
    when they already are)."""
    creep = getattr(model, "creep", None)
    if creep is None or creep.dt == period_s:
        return model
    from pihyst.model import Creep
    return model.replace(creep=Creep(creep.tau, creep.gain, dt=period_s))


class VoltageProgram:
    """Drive the voltages ``voltages``, one per tick (record a loop)."""

    reference_unit = "V"

    def __init__(self, voltages, description="voltage signal"):
        self.voltages = _samples(voltages, "the voltage signal")
        if self.voltages.ndim != 1 or self.voltages.size == 0:
            raise InvalidArgumentError(f"the voltage signal must be a non-empty sequence of "
                                       f"volts, got shape {self.voltages.shape}")
        if not np.all(np.isfinite(self.voltages)):
            k = int(np.flatnonzero(~np.isfinite(self.voltages))[0])
            raise InvalidArgumentError(f"the voltage signal is not a finite number at tick "
                                       f"{k}: {self.voltages[k]}")
        self.n_ticks = self.voltages.size
        self.description = description

    def initial_voltage(self):
        return float(self.voltages[0])

    def start(self):
        pass

    def command(self, k, measured_um):
        v = float(self.voltages[k])
        return v, v

    def describe(self):
        return f"record: {self.description} ({self.n_ticks} ticks)"


class FeedforwardProgram:
    """Track ``desired`` (um, one per tick) open loop: u = H^-1(y_desired), the exact
    inverse of ``model`` (:func:`pihyst.inverse.compensator_for`: the family's compensator)
    within the voltage limits and the slew limit per tick.

    A model with an input delay of d ticks is driven with preview: the voltage of tick k
    aims at ``desired[k + d]`` (the trajectory is known in advance), and the last d
    ticks hold the last voltage; the reference logged at tick k stays ``desired[k]``."""

    reference_unit = "um"

    def __init__(self, model, desired, u_min, u_max, max_step=None, description="desired"):
        self.model = model
        self.desired = _samples(desired, "the desired trajectory")
        if self.desired.ndim != 1 or self.desired.size == 0:
            raise InvalidArgumentError(f"the desired trajectory must be a non-empty sequence "
                                       f"of displacements, got shape {self.desired.shape}")
        lo, hi = model.input_range
        self.limits = (max(lo, u_min), min(hi, u_max))
        if not self.limits[0] < self.limits[1]:
            raise InvalidArgumentError(f"the model's input range [{lo:g}, {hi:g}] V and the "
                                       f"rig's limits [{u_min:g}, {u_max:g}] V do not overlap")
        self.max_step = max_step
        # max_step is volts per tick: a slew rate of max_step V/s at a 1 s "tick"
        self.compensator = compensator_for(model, u_min=self.limits[0], u_max=self.limits[1],
                                           slew_rate=max_step, sample_period=1.0)
        self.n_ticks = self.desired.size
        self.description = description
        self._start = None

    def bind_tick(self, period_s):
        """Run a creep model's lags at the rig's tick ``period_s`` (the controller calls
        this before the run): the compensator steps them by ``creep.dt`` per step, the
        interval of the record the model was fitted on (5 ms for a 200 Hz record, while a
        20 Hz rig's ticks are 50 ms apart: holding 20 um, 78.7 V instead of 71.4 V)."""
        model = creep_at_tick(self.model, period_s)
        if model is not self.model:
            self.model = model
            self.compensator = compensator_for(model, u_min=self.limits[0],
                                               u_max=self.limits[1], slew_rate=self.max_step,
                                               sample_period=1.0)

    def initial_voltage(self):
        # the voltage for the first desired value, reached by a monotone ramp from 0 V
        probe = compensator_for(self.model, u_min=self.limits[0], u_max=self.limits[1])
        u0 = probe.step(self.desired[0])
        self._start = (probe.state, u0)
        return u0

    def start(self):
        if self._start is not None:
            self.compensator.reset(*self._start)

    def _feedforward(self, k):
        """The compensator's voltage for tick k: for desired[k + d], held past the end."""
        ahead = k + self.compensator.delay
        if ahead >= self.n_ticks:
            return self.compensator.voltage
        return self.compensator.step(float(self.desired[ahead]))

    def command(self, k, measured_um):
        return float(self.desired[k]), self._feedforward(k)

    def describe(self):
        return (f"track open loop: {self.description} ({self.n_ticks} ticks) through the "
                f"inverse of a {self.model.family} model")


class FeedbackProgram(FeedforwardProgram):
    """Feedforward plus PID feedback on the measured error: the compensator cancels the
    hysteresis, the PID corrects what the model misses (creep, drift, model error) with a
    small voltage on top:

        e_k = y_d[k] - y_k,
        u_k = H^-1(y_d[k + d]) + Kp e_k + Ki sum_j e_j dt + Kd (e_k - e_{k-1}) / dt

    (gains in V/um, V/(um s) and V s/um), then clipped to the limits and the slew limit.
    With a model delay of d ticks the feedforward takes the target d ticks ahead (as
    :class:`FeedforwardProgram`) while the PID compares the measurement with the target
    of its own tick. The feedforward path runs on its own (the compensator's state
    follows H^-1(y_d), not the corrected voltage): the correction is a small voltage
    added in parallel. Feeding
    the correction through the inverse instead (a corrected desired value, or an
    operator state that follows every correction) makes small reversals at which the
    model is flat, and the voltage jumps across them.

    Anti-windup by conditional integration: the integral does not change on a tick whose
    voltage was clipped (limit or slew) in the direction of the error. Ticks without a
    valid reading leave the integral unchanged."""

    def __init__(self, model, desired, u_min, u_max, dt, kp, ki, kd=0.0, max_step=None,
                 description="desired"):
        super().__init__(model, desired, u_min, u_max, max_step, description)
        for name, v in (("KP", kp), ("KI", ki), ("KD", kd), ("dt", dt)):
            if not (math.isfinite(v) and v >= 0):
                raise InvalidArgumentError(f"{name} must be a finite number >= 0, got {v}")
        self.dt, self.kp, self.ki, self.kd = dt, kp, ki, kd
        self.integral = 0.0
        self._e_prev = None
        self._last = None

    def start(self):
        super().start()
        self._last = self.compensator.voltage

    def command(self, k, measured_um):
        y_d = float(self.desired[k])
        u_ff = self._feedforward(k)
        integral = self.integral
        correction = integral
        e = None
        if measured_um is not None and math.isfinite(measured_um):
            e = y_d - measured_um
            integral = self.integral + self.ki * e * self.dt
            derivative = 0.0 if self._e_prev is None else (e - self._e_prev) / self.dt
            self._e_prev = e
            correction = self.kp * e + integral + self.kd * derivative
        u = u_ff + correction
        lo, hi = self.limits
        if self.max_step is not None and self._last is not None:
            lo, hi = max(lo, self._last - self.max_step), min(hi, self._last + self.max_step)
        u_sent = min(max(u, lo), hi)
        pushing = e is not None and ((u_sent < u and e > 0) or (u_sent > u and e < 0))
        if not pushing:
            self.integral = integral
        self._last = u_sent
        return y_d, u_sent

    def describe(self):
        return (super().describe().replace("open loop", "with feedback") +
                f"; PID Kp {self.kp:g} V/µm, Ki {self.ki:g} V/(µm s), Kd {self.kd:g} V s/µm")
