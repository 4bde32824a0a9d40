"""What the loop drives, tick by tick: a voltage signal (record), a desired trajectory
through pihyst's compensator (track), or that plus PID feedback (track --feedback).

A program has ``n_ticks``, ``reference_unit``, ``initial_voltage()`` (where the start
ramp goes), ``start()`` (called when the ramp has arrived), ``command(k, measured_um)``
-> ``(reference, volts)`` and ``describe()``.
"""

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from pihyst.exceptions import InvalidArgumentError
from pihyst.inverse import compensator_for


def _samples(values: ArrayLike, what: str) -> np.ndarray:
    """``values`` as a float array; InvalidArgumentError naming ``what`` if they are not
    numbers."""
    try:
        return np.asarray(values, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise InvalidArgumentError(f"{what} must be a sequence of numbers") from None


def creep_at_tick(model: Any, period_s: float) -> Any:
    """``model`` with its creep lags stepped every ``period_s`` (itself without creep, or
    when they already are)."""
    creep = getattr(model, "creep", None)
    if creep is None or creep.dt == period_s:
        return model
    from pihyst.model import Creep
    return model.replace(creep=Creep(creep.tau, creep.gain, dt=period_s))


class VoltageProgram:
    """Drive the voltages ``voltages``, one per tick (record a loop).

    Parameters
    ----------
    voltages : array_like
        One voltage (V) per tick; the controller clips them to the rig's limits.
    description : str
        What the signal is, for :meth:`describe`.

    Raises
    ------
    InvalidArgumentError
        An empty, multi-dimensional or not finite signal.

    Examples
    --------
    >>> from pihyst.rig import VoltageProgram
    >>> program = VoltageProgram([0.0, 10.0, 20.0], description="a ramp")
    >>> program.initial_voltage(), program.command(1, None), program.describe()
    (0.0, (10.0, 10.0), 'record: a ramp (3 ticks)')
    """

    reference_unit = "V"

    def __init__(self, voltages: ArrayLike, description: str = "voltage signal") -> None:
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

    def initial_voltage(self) -> float:
        """The voltage the start ramp goes to: the first of the signal.

        Returns
        -------
        float
            Volts.

        Examples
        --------
        >>> from pihyst.rig import VoltageProgram
        >>> program = VoltageProgram([2.0, 4.0, 6.0])
        >>> program.initial_voltage()
        2.0
        """
        return float(self.voltages[0])

    def start(self) -> None:
        """Called when the start ramp has arrived (nothing to do for a voltage signal).

        Examples
        --------
        >>> from pihyst.rig import VoltageProgram
        >>> VoltageProgram([1.0]).start()
        """

    def command(self, k: int, measured_um: float | None) -> tuple[float, float]:
        """The reference and the voltage of tick ``k``.

        Parameters
        ----------
        k : int
            The tick, 0 to ``n_ticks - 1``.
        measured_um : float or None
            The displacement measured at this tick (unused).

        Returns
        -------
        reference : float
            The signal's voltage (V).
        volts : float
            The same voltage, to send.

        Examples
        --------
        >>> from pihyst.rig import VoltageProgram
        >>> program = VoltageProgram([2.0, 4.0, 6.0])
        >>> program.command(2, measured_um=1.5)
        (6.0, 6.0)
        """
        v = float(self.voltages[k])
        return v, v

    def describe(self) -> str:
        """One line for the log: what is recorded, and how many ticks.

        Returns
        -------
        str
            The line.

        Examples
        --------
        >>> from pihyst.rig import VoltageProgram
        >>> program = VoltageProgram([2.0, 4.0, 6.0])
        >>> program.describe()
        'record: voltage signal (3 ticks)'
        """
        return f"record: {self.description} ({self.n_ticks} ticks)"


class FeedforwardProgram:
    """Track ``desired`` (um, one per tick) open loop: u = H^-1(y_desired), the exact
    inverse of ``model`` (:func:`pihyst.inverse.compensator_for`: the family's compensator)
    within the voltage limits and the slew limit per tick.

    A model with an input delay of d ticks is driven with preview: the voltage of tick k
    aims at ``desired[k + d]`` (the trajectory is known in advance), and the last d
    ticks hold the last voltage; the reference logged at tick k stays ``desired[k]``.

    Parameters
    ----------
    model : PIModel or BoucWenModel
        The actuator's model (with its creep and delay, if it has them).
    desired : array_like
        The desired displacement (µm), one per tick.
    u_min, u_max : float
        The voltage limits (V); the program keeps within these and the model's input
        range.
    max_step : float or None
        The largest voltage change per tick (V), or None.
    description : str
        What the trajectory is, for :meth:`describe`.

    Raises
    ------
    InvalidArgumentError
        An empty or multi-dimensional trajectory, or limits that do not overlap the
        model's input range.

    Examples
    --------
    >>> import pihyst
    >>> from pihyst.rig import FeedforwardProgram
    >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    >>> program = FeedforwardProgram(model, [0.0, 5.0, 10.0], u_min=0.0, u_max=150.0)
    >>> program.initial_voltage(); program.start()
    0.0
    >>> [round(program.command(k, None)[1], 3) for k in range(3)]
    [0.0, 30.41, 52.432]
    """

    reference_unit = "um"

    def __init__(self, model: Any, desired: ArrayLike, u_min: float, u_max: float,
                 max_step: float | None = None, description: str = "desired") -> None:
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
        self._start: tuple[Any, float] | None = None

    def bind_tick(self, period_s: float) -> None:
        """Run a creep model's lags at the rig's tick ``period_s`` (the controller calls
        this before the run).

        The compensator steps the lags by ``creep.dt`` per step, the interval of the
        record the model was fitted on (5 ms for a 200 Hz record, while a 20 Hz rig's
        ticks are 50 ms apart: holding 20 µm, 78.7 V instead of 71.4 V).

        Parameters
        ----------
        period_s : float
            The rig's tick (s).

        Examples
        --------
        >>> import pihyst
        >>> from pihyst.rig import FeedforwardProgram
        >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
        >>> program = FeedforwardProgram(model, [1.0, 2.0], u_min=0.0, u_max=150.0)
        >>> program.bind_tick(0.05)       # no creep: the model stays as it is
        >>> program.model is model
        True
        """
        model = creep_at_tick(self.model, period_s)
        if model is not self.model:
            self.model = model
            self.compensator = compensator_for(model, u_min=self.limits[0],
                                               u_max=self.limits[1], slew_rate=self.max_step,
                                               sample_period=1.0)

    def initial_voltage(self) -> float:
        """The voltage for the first desired value, reached by a monotone ramp from 0 V.

        Returns
        -------
        float
            Volts.

        Examples
        --------
        >>> import pihyst
        >>> from pihyst.rig import FeedforwardProgram
        >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
        >>> program = FeedforwardProgram(model, [3.0, 5.0], u_min=0.0, u_max=150.0)
        >>> round(program.initial_voltage(), 3)
        19.133
        """
        probe = compensator_for(self.model, u_min=self.limits[0], u_max=self.limits[1])
        u0 = probe.step(self.desired[0])
        self._start = (probe.state, u0)
        return u0

    def start(self) -> None:
        """Called when the start ramp has arrived: the compensator continues from the
        state the ramp left.

        Examples
        --------
        >>> import pihyst
        >>> from pihyst.rig import FeedforwardProgram
        >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
        >>> program = FeedforwardProgram(model, [3.0, 5.0], u_min=0.0, u_max=150.0)
        >>> u0 = program.initial_voltage(); program.start()
        >>> round(program.command(0, None)[1], 3) == round(u0, 3)
        True
        """
        if self._start is not None:
            self.compensator.reset(*self._start)

    def _feedforward(self, k: int) -> float:
        """The compensator's voltage for tick k: for desired[k + d], held past the end."""
        ahead = k + self.compensator.delay
        if ahead >= self.n_ticks:
            return self.compensator.voltage
        return self.compensator.step(float(self.desired[ahead]))

    def command(self, k: int, measured_um: float | None) -> tuple[float, float]:
        """The reference and the voltage of tick ``k``.

        Parameters
        ----------
        k : int
            The tick, 0 to ``n_ticks - 1``.
        measured_um : float or None
            The displacement measured at this tick (unused: open loop).

        Returns
        -------
        reference : float
            ``desired[k]`` (µm).
        volts : float
            The compensator's voltage.

        Examples
        --------
        >>> import pihyst
        >>> from pihyst.rig import FeedforwardProgram
        >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
        >>> program = FeedforwardProgram(model, [3.0, 5.0], u_min=0.0, u_max=150.0)
        >>> _ = program.initial_voltage(); program.start()
        >>> [round(v, 3) for v in program.command(1, None)]
        [5.0, 30.41]
        """
        return float(self.desired[k]), self._feedforward(k)

    def describe(self) -> str:
        """One line for the log: the trajectory, its ticks and the model's family.

        Returns
        -------
        str
            The line.

        Examples
        --------
        >>> import pihyst
        >>> from pihyst.rig import FeedforwardProgram
        >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
        >>> FeedforwardProgram(model, [1.0, 2.0], u_min=0.0, u_max=150.0).describe()
        'track open loop: desired (2 ticks) through the inverse of a multislope model'
        """
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
    valid reading leave the integral unchanged.

    Parameters
    ----------
    model : PIModel or BoucWenModel
        The actuator's model.
    desired : array_like
        The desired displacement (µm), one per tick.
    u_min, u_max : float
        The voltage limits (V).
    dt : float
        The tick (s), for the integral and the derivative.
    kp, ki, kd : float
        The PID's gains, >= 0 (V/µm, V/(µm s), V s/µm).
    max_step : float or None
        The largest voltage change per tick (V), or None.
    description : str
        What the trajectory is, for :meth:`describe`.

    Raises
    ------
    InvalidArgumentError
        As :class:`FeedforwardProgram`, or a gain or ``dt`` that is negative or not
        finite.

    Examples
    --------
    >>> import pihyst
    >>> from pihyst.rig import FeedbackProgram
    >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    >>> program = FeedbackProgram(model, [0.0, 5.0, 10.0], u_min=0.0, u_max=150.0,
    ...                           dt=0.05, kp=0.5, ki=10.0)
    >>> program.initial_voltage(); program.start()
    0.0
    >>> [round(program.command(k, y)[1], 3) for k, y in enumerate([0.0, 4.0, 9.5])]
    [0.0, 31.41, 53.432]
    """

    def __init__(self, model: Any, desired: ArrayLike, u_min: float, u_max: float, dt: float,
                 kp: float, ki: float, kd: float = 0.0, max_step: float | None = None,
                 description: str = "desired") -> None:
        super().__init__(model, desired, u_min, u_max, max_step, description)
        for name, v in (("KP", kp), ("KI", ki), ("KD", kd), ("dt", dt)):
            if not (math.isfinite(v) and v >= 0):
                raise InvalidArgumentError(f"{name} must be a finite number >= 0, got {v}")
        self.dt, self.kp, self.ki, self.kd = dt, kp, ki, kd
        self.integral = 0.0
        self._e_prev: float | None = None
        self._last: float | None = None

    def start(self) -> None:
        """Called when the start ramp has arrived: the compensator continues from the
        ramp's state, and the slew limit from its voltage.

        Examples
        --------
        >>> import pihyst
        >>> from pihyst.rig import FeedbackProgram
        >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
        >>> program = FeedbackProgram(model, [3.0, 5.0], u_min=0.0, u_max=150.0, dt=0.05,
        ...                           kp=0.5, ki=0.0, max_step=2.0)
        >>> u0 = program.initial_voltage(); program.start()
        >>> round(program.command(0, -10.0)[1] - u0, 3)   # 6.5 V, limited to 2 V per tick
        2.0
        """
        super().start()
        self._last = self.compensator.voltage

    def command(self, k: int, measured_um: float | None) -> tuple[float, float]:
        """The reference and the voltage of tick ``k``: feedforward plus the PID's
        correction, within the limits and the slew limit.

        Parameters
        ----------
        k : int
            The tick, 0 to ``n_ticks - 1``.
        measured_um : float or None
            The displacement measured at this tick (None or NaN: no valid reading).

        Returns
        -------
        reference : float
            ``desired[k]`` (µm).
        volts : float
            The voltage to send.

        Examples
        --------
        >>> import pihyst
        >>> from pihyst.rig import FeedbackProgram
        >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
        >>> program = FeedbackProgram(model, [3.0, 5.0], u_min=0.0, u_max=150.0, dt=0.05,
        ...                           kp=0.5, ki=0.0, max_step=2.0)
        >>> u0 = program.initial_voltage(); program.start()
        >>> y_d, u = program.command(0, 3.0)     # on target: no correction
        >>> y_d, round(u - u0, 3)
        (3.0, 0.0)
        """
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

    def describe(self) -> str:
        """One line for the log: as :meth:`FeedforwardProgram.describe`, with the gains.

        Returns
        -------
        str
            The line.

        Examples
        --------
        >>> import pihyst
        >>> from pihyst.rig import FeedbackProgram
        >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
        >>> print(FeedbackProgram(model, [1.0], 0.0, 150.0, dt=0.05, kp=0.5,
        ...                       ki=10.0).describe().split("; ")[1])
        PID Kp 0.5 V/µm, Ki 10 V/(µm s), Kd 0 V s/µm
        """
        return (super().describe().replace("open loop", "with feedback") +
                f"; PID Kp {self.kp:g} V/µm, Ki {self.ki:g} V/(µm s), Kd {self.kd:g} V s/µm")
