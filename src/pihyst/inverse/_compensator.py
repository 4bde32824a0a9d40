"""Feedforward compensation: the voltage that makes a model produce a desired displacement.

For a model with non-negative weights the output for the next voltage u, from the
current operator state f, is

    y(u) = offset + sum_k w_k max(R_k(u), min(F_k(u), f_k)),

continuous, piecewise linear and non-decreasing in u. Each sample is solved exactly in
the C core (no iteration, no tolerance) by walking the breakpoints of y(u) away from the
last voltage and solving the linear equation of the segment that holds the desired
value; where y(u) is flat the voltage nearest the last one is kept (docs/theory/inverse.md).
For a model with creep (docs/theory/creep.md) the output is affine in the hysteresis
output H at each sample, y = (1 - beta) H + (lag terms), 1 - beta > 0: each sample first
solves for the hysteresis target H* (the lag state is known), then the voltage for H*
exactly as above, then advances the lags by the H reached.
Voltage limits and a slew limit hold for every output, whatever the input:
a desired value out of reach saturates at the limit and is flagged, NaN holds the last
voltage and is flagged.

:func:`compensate` does a whole trajectory; :class:`Compensator` does it sample by sample
with explicit state, like the models' ``step``/``reset``/``state``.

A model with an input delay of d samples (``model.delay``) answers a voltage d samples
later: y[k] = P[v](k - d). A trajectory known in advance is compensated with preview,

    v[k] = P^-1[y_d](k + d)   for k < N - d,   v[k] = v[N - d - 1] (held) after,

so that the model's output meets y_d[k] on every sample k >= d (the first d samples show
the voltage held before the run, the initial voltage). :func:`compensate` does that shift; the
streaming :class:`Compensator` takes, at each tick, the target d samples ahead.
"""

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from pihyst import _core
from pihyst._arguments import real_array
from pihyst.exceptions import InvalidArgumentError
from pihyst.model import InvalidModelError, PIModel
from pihyst.model._creep import sample_intervals
from pihyst.model._models import _finite_vector

__all__ = ["CompensationResult", "Compensator", "PreviewRun", "compensate", "FLAG_SATURATED_LOW",
           "FLAG_SATURATED_HIGH", "FLAG_NAN", "FLAG_SLEW"]

#: Compensators of the models that are not PI models (family -> class), registered by
#: their modules (inverse/_boucwen.py); compensate() dispatches to them
OTHER_COMPENSATORS: dict[str | None, Any] = {}

#: Per-sample flag bits of :attr:`CompensationResult.flags` (0: desired value reached).
#: Out of reach means beyond what the model gives at the voltage limit, whatever the slew
#: limit: a sample cut short by the slew limit on its way to an out-of-reach value has
#: both bits, FLAG_SATURATED_* | FLAG_SLEW.
FLAG_SATURATED_LOW = _core.FLAG_SATURATED_LOW    # out of reach below: voltage at u_min
FLAG_SATURATED_HIGH = _core.FLAG_SATURATED_HIGH  # out of reach above: voltage at u_max
FLAG_NAN = _core.FLAG_NAN                        # desired value NaN: last voltage held
FLAG_SLEW = _core.FLAG_SLEW                      # slew limit reached before the desired value


@dataclass(frozen=True)
class CompensationResult:
    """Result of :func:`compensate` and :meth:`Compensator.run`.

    Parameters
    ----------
    desired : ndarray
        The desired displacements, as given.
    voltage : ndarray
        The voltages, within the limits and the slew limit.
    displacement : ndarray
        The model's prediction for those voltages (equal to ``desired`` wherever the
        desired value was reached, to rounding).
    flags : ndarray of uint8
        Per-sample bits ``FLAG_SATURATED_LOW | FLAG_SATURATED_HIGH | FLAG_NAN |
        FLAG_SLEW``; 0 where the desired value was reached.
    saturated, saturated_low, saturated_high, slew_limited, nan_held : ndarray of bool
        The flags per sample; ``saturated`` is low or high: the desired value is out of
        reach within the voltage limits (the voltage at the limit, or on its way there
        when ``slew_limited`` too).
    initial_state, initial_voltage : ndarray, float
        Where the run started (the state has the initial voltage applied).
    final_state, final_voltage : ndarray, float
        Where it ended: a following run from there continues exactly.
    limits : (float, float)
        The voltage limits.
    slew_rate : float or None
        The slew limit, V/s.
    max_step : float or None
        The slew limit as the largest voltage step per sample, V.
    initial_creep_state, final_creep_state : ndarray or None
        With creep: the lag states before the first and after the last sample.

    Examples
    --------
    >>> import pihyst
    >>> r = pihyst.compensate(pihyst.ClassicalPI([0], [1.0]), [1.0, 200.0])
    >>> r.voltage.tolist(), r.saturated_high.tolist(), r.final_voltage
    ([1.0, 150.0], [False, True], 150.0)
    """

    desired: np.ndarray
    voltage: np.ndarray
    displacement: np.ndarray
    flags: np.ndarray
    saturated: np.ndarray
    saturated_low: np.ndarray
    saturated_high: np.ndarray
    slew_limited: np.ndarray
    nan_held: np.ndarray
    initial_state: np.ndarray
    initial_voltage: float
    final_state: np.ndarray
    final_voltage: float
    limits: tuple
    slew_rate: float | None = None
    max_step: float | None = None
    initial_creep_state: np.ndarray | None = None
    final_creep_state: np.ndarray | None = None

    @property
    def n_saturated(self):
        """Samples out of reach within the voltage limits (whatever the slew limit)."""
        return int(np.count_nonzero(self.saturated))

    @property
    def n_slew_limited(self):
        """Samples not reached because of the slew limit."""
        return int(np.count_nonzero(self.slew_limited))

    @property
    def n_nan(self):
        """Samples whose desired value was NaN (voltage held)."""
        return int(np.count_nonzero(self.nan_held))

    @property
    def reached(self):
        """True where the desired value was reached (no flag)."""
        return self.flags == 0


class Compensator:
    """Streaming exact inverse of a model, with voltage limits and a slew limit.

    Parameters
    ----------
    model : PIModel
        Any model with non-negative weights (classical, multislope, piecewise-linear).
    u_min, u_max : float, optional
        Voltage limits, inside the model's input range (default: that range).
    slew_rate : float, optional
        Largest rate of voltage change, V/s (default none): the voltage changes by at most
        ``slew_rate * sample_period`` per sample (:attr:`max_step`).
    sample_period : float, optional
        The period (s) the slew limit is converted at; default the model's
        ``sample_period``, else its creep lags' ``dt`` (a slew limit with neither is
        refused).
    initial_voltage : float, optional
        The voltage before the first sample (default 0 V, or the nearer limit if 0 V
        is outside the limits; with ``initial_state`` given, the voltage within the limits
        nearest that at which the state is at rest, e.g. the top of the range for a state
        at rest there, if there is one).
    initial_state : array_like, optional
        Operator state before the first sample (default: the model's initial state).
        The initial voltage is applied to it (a no-op for a state at rest at that
        voltage).
    creep_state : array_like, optional
        For a model with creep: the lag states before the first sample (default:
        settled at the model's output at the initial voltage).

    Raises
    ------
    InvalidModelError
        If a weight is negative (the model is not monotone, so not invertible).
    InvalidArgumentError
        If the model is not a PI model, or a limit or the initial voltage is not valid.

    Notes
    -----
    A model with a delay of d samples (:attr:`delay`) makes the voltage of tick k act
    at tick k + d: ``step`` and ``run`` take the target d samples ahead (y_d[k + d] at
    tick k; :func:`compensate` shifts a whole trajectory so), and their displacement is
    the model's output d samples later.

    Examples
    --------
    >>> import pihyst
    >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    >>> comp = pihyst.Compensator(model, slew_rate=5e4, sample_period=1e-4)
    >>> u = comp.step(1.0)           # 50 kV/s allows 5 V per 100 us sample from 0 V
    >>> u, comp.last_flags == pihyst.Compensator.FLAG_SLEW
    (5.0, True)
    >>> u = comp.step(1.0)
    >>> round(u, 6), round(comp.displacement, 9)
    (6.377551, 1.0)
    """

    FLAG_SATURATED_LOW = FLAG_SATURATED_LOW
    FLAG_SATURATED_HIGH = FLAG_SATURATED_HIGH
    FLAG_NAN = FLAG_NAN
    FLAG_SLEW = FLAG_SLEW

    def __init__(self, model: PIModel, *, u_min: float | None = None,
                 u_max: float | None = None, slew_rate: float | None = None,
                 initial_voltage: float | None = None, initial_state: ArrayLike | None = None,
                 creep_state: ArrayLike | None = None,
                 sample_period: float | None = None) -> None:
        if not isinstance(model, PIModel):
            raise InvalidArgumentError(f"model must be a pihyst model (ClassicalPI, MultislopePI, "
                            f"PiecewiseLinearPI), not {type(model).__name__}")
        negative = np.flatnonzero(model.weights < 0)
        if negative.size:
            k = negative[0]
            hint = " (for a classical model, model.inverse() is its exact inverse)" \
                if model.family == "classical" else ""
            raise InvalidModelError(f"compensation needs non-negative weights (a monotone "
                                    f"model); weights[{k}] = {model.weights[k]:g}{hint}")
        self.model = model
        lo, hi = model.input_range
        u_min = lo if u_min is None else _number(u_min, "u_min")
        u_max = hi if u_max is None else _number(u_max, "u_max")
        if not lo <= u_min < u_max <= hi:
            raise InvalidArgumentError(
                f"voltage limits [{u_min:g}, {u_max:g}] must satisfy u_min < u_max inside the "
                f"model's input range [{lo:g}, {hi:g}]")
        self.limits = (u_min, u_max)
        self.slew_rate, self.sample_period, self.max_step = slew_per_sample(
            slew_rate, model, sample_period)
        state = (model.initial_state if initial_state is None else
                 _finite_vector(initial_state, "initial_state", model.n_operators))
        if initial_voltage is None:
            initial_voltage = min(max(0.0, u_min), u_max)
            if initial_state is not None:
                # 0 V applied to a state at rest elsewhere (at the top of the range) would
                # wipe it out, and the slew limit would start from the wrong voltage
                initial_voltage = rest_voltage(model, state, initial_voltage, u_min, u_max)
        initial_voltage = _number(initial_voltage, "initial_voltage")
        if not u_min <= initial_voltage <= u_max:
            raise InvalidArgumentError(f"initial_voltage {initial_voltage:g} is outside the "
                                       f"voltage limits [{u_min:g}, {u_max:g}]")
        self._start = (np.array(state), initial_voltage, creep_state)
        self._core = _core.Compensator(model._new_bank(state), u_min, u_max,
                                       np.inf if self.max_step is None else self.max_step,
                                       initial_voltage)
        self._lags = None
        self._start_lags(creep_state)

    @property
    def delay(self):
        """The model's input delay in samples: how far ahead the targets are taken."""
        return self.model.delay

    def _start_lags(self, creep_state):
        """With creep: the lags from ``creep_state``, or settled at the output now."""
        if self.model.creep is None:
            return
        n = self.model.creep.n_lags
        z = (np.full(n, self._core.output) if creep_state is None else
             _finite_vector(creep_state, "creep_state", n))
        self._lags = self.model.creep.lags(z)
        self._output = self._core.output

    # ---------------------------------------------------------------- state
    @property
    def state(self):
        """Operator state after the last voltage (a copy)."""
        return self._core.state

    @property
    def voltage(self):
        """The last voltage."""
        return self._core.voltage

    @property
    def displacement(self):
        """The model's displacement at the last voltage (with creep: at the last
        sample)."""
        return self._core.output if self._lags is None else self._output

    @property
    def creep_state(self):
        """The creep lag states (a copy; None for a model without creep)."""
        return None if self._lags is None else self._lags.state

    @property
    def last_flags(self):
        """Flags of the last :meth:`step` (0: desired value reached)."""
        return self._core.last_flags

    def reset(self, state: ArrayLike | None = None, voltage: float | None = None,
              creep_state: ArrayLike | None = None) -> None:
        """Go back to the initial state and voltage, or to ``state`` and ``voltage``
        (with creep: the lags to ``creep_state``, default settled at the output).

        ``voltage`` is applied to ``state`` (a no-op for a state at rest there). With
        ``state`` alone the voltage is the one within the limits at which ``state`` is at
        rest, so that the compensator continues as the one that reached ``state``; where
        the state is at rest at a whole interval of voltages (the voltage moved back
        inside the play of every operator, or a model without a zero threshold) it does
        not say which voltage was last, and the slew limit and a NaN target depend on
        it: an :class:`InvalidArgumentError` asks for ``voltage``, as it does for a state
        at rest nowhere within the limits (no run within them reaches it).

        Parameters
        ----------
        state : array_like, optional
            The operator state to go to (default: the initial state).
        voltage : float, optional
            The voltage to apply to it, within the limits (default: see above).
        creep_state : array_like, optional
            With creep: the lag states (default: settled at the output).

        Raises
        ------
        InvalidArgumentError
            If the voltage is outside the limits, or is needed and not given.

        Examples
        --------
        >>> import pihyst
        >>> m = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
        >>> comp = pihyst.Compensator(m)
        >>> _ = comp.step(10.0); comp.reset(); comp.voltage
        0.0
        """
        start_state, start_voltage, start_creep = self._start
        if state is None and voltage is None and creep_state is None:
            creep_state = start_creep
        state = start_state if state is None else _finite_vector(state, "state",
                                                                 self.model.n_operators)
        lo, hi = self.limits
        if voltage is None:
            voltage = start_voltage if state is start_state else \
                self._voltage_of(state, lo, hi)
        voltage = _number(voltage, "voltage")
        if not lo <= voltage <= hi:
            raise InvalidArgumentError(f"voltage {voltage:g} is outside the limits "
                                       f"[{lo:g}, {hi:g}]")
        self._core.reset(state, voltage)
        self._start_lags(creep_state)

    def _voltage_of(self, state, lo, hi):
        """The one voltage in [lo, hi] at which ``state`` is at rest (InvalidArgumentError
        if there is none, or a whole interval)."""
        at_rest = rest_interval(self.model, state, lo, hi)
        if at_rest is None:
            raise InvalidArgumentError(
                f"state is at rest at no voltage within the limits [{lo:g}, {hi:g}] V, so "
                f"no run within them reaches it: give the voltage to apply to it, "
                f"reset(state, voltage)")
        a, b = at_rest
        # narrower than the rounding of voltages of the limits' size: one voltage
        if b - a > 8 * np.spacing(max(abs(lo), abs(hi))):
            raise InvalidArgumentError(
                f"state is at rest at every voltage in [{a:.6g}, {b:.6g}] V, so it does not "
                f"say which voltage was last (the slew limit and a NaN target start from "
                f"it): give it, reset(state, voltage)")
        return a

    # ---------------------------------------------------------------- compensation
    def step(self, y_desired: float, dt: float | None = None) -> float:
        """The voltage for one desired displacement (applied to the state).

        Parameters
        ----------
        y_desired : float
            The desired displacement (µm; any value: out of reach saturates, NaN holds
            the last voltage; :attr:`last_flags` says which). With a delay of d samples,
            the target d samples ahead.
        dt : float, optional
            With creep: the time (s) since the previous sample (default
            ``model.creep.dt``).

        Returns
        -------
        float
            The voltage, within the limits and the slew limit.

        Raises
        ------
        InvalidArgumentError
            If ``y_desired`` or ``dt`` is not a number (``dt`` >= 0).

        Examples
        --------
        >>> import pihyst
        >>> pihyst.Compensator(pihyst.ClassicalPI([0], [2.0])).step(10.0)
        5.0
        """
        y_desired = _number(y_desired, "y_desired", allow_inf=True, allow_nan=True)
        if self._lags is None:
            return self._core.step(y_desired)
        if dt is not None:
            dt = _number(dt, "dt")
            if dt < 0:
                raise InvalidArgumentError(f"dt must be >= 0 s, got {dt:g}")
        u, y, _ = self._lags.compensate(self._core, np.array([y_desired]),
                                        None if dt is None else np.array([dt]))
        self._output = float(y[0])
        return float(u[0])

    def run(self, y_desired: ArrayLike, t: ArrayLike | None = None,
            t_previous: float | None = None) -> CompensationResult:
        """Compensate a block of desired displacements, continuing from the current state.
        With creep, ``t`` are the sample times (s; default: every ``model.creep.dt``,
        the first one ``creep.dt`` after the previous sample, or at ``t[0] - t_previous``
        when the previous sample's time is given).

        Parameters
        ----------
        y_desired : array_like
            Desired displacements (µm), one per sample (any values, as for :meth:`step`).
        t : array_like, optional
            With creep: the sample times (s).
        t_previous : float, optional
            With creep: the time (s) of the sample before the block.

        Returns
        -------
        CompensationResult
            Voltages, displacements, flags, and the states before and after.

        Raises
        ------
        InvalidArgumentError
            If ``y_desired`` is not a vector of numbers (or ``t`` does not fit it).

        Examples
        --------
        >>> import pihyst
        >>> comp = pihyst.Compensator(pihyst.ClassicalPI([0], [2.0]))
        >>> comp.run([10.0, 20.0]).voltage.tolist()
        [5.0, 10.0]
        """
        y_desired = _desired(y_desired)
        initial_state, initial_voltage = self.state, self.voltage
        initial_creep = self.creep_state
        if self._lags is None:
            u, y, flags = self._core.run(y_desired)
        else:
            first = self.model.creep.dt
            if t is not None and t_previous is not None and y_desired.size:
                first = float(np.asarray(t, dtype=np.float64)[0]) - float(t_previous)
            dt = None if t is None else sample_intervals(t, y_desired.size, first)
            u, y, flags = self._lags.compensate(self._core, y_desired, dt)
            if y.size:
                self._output = float(y[-1])
        return run_result(self, y_desired, u, y, flags, initial_state, initial_voltage,
                          initial_creep_state=initial_creep,
                          final_creep_state=self.creep_state)

    def __repr__(self):
        slew = "" if self.slew_rate is None else \
            f", slew_rate={self.slew_rate:g} V/s at {self.sample_period:g} s"
        return (f"Compensator({type(self.model).__name__}, limits=[{self.limits[0]:g}, "
                f"{self.limits[1]:g}]{slew}, voltage={self.voltage:g})")


def rest_voltage(model, state, preferred, lo, hi):
    """The voltage in [lo, hi] nearest ``preferred`` at which operator ``state`` is at rest
    (applying it leaves every operator as it is); ``preferred`` if there is none there.

    Applying u lowers some operator exactly when u is below the voltages the state rests
    at, and raises one exactly when u is above them: each side is found by bisection."""
    bank = model._new_bank(state)

    def moves(u, sign):
        bank.state = state
        bank.step(u)
        return bool(np.any(sign * (bank.state - state) > 0))

    falls, rises = moves(preferred, -1), moves(preferred, 1)
    if falls == rises:          # at rest there, or at rest nowhere
        return preferred
    sign, a, b = (-1, preferred, hi) if falls else (1, preferred, lo)
    if moves(b, sign):
        return preferred
    for _ in range(2100):       # a moves, b does not; halve until they are adjacent floats
        m = a + (b - a) / 2
        if m == a or m == b:
            break
        a, b = (m, b) if moves(m, sign) else (a, m)
    return b if not moves(b, -sign) else preferred


def rest_interval(model, state, lo, hi):
    """(a, b): the voltages in [lo, hi] at which operator ``state`` is at rest form the
    interval [a, b] (a == b: one voltage); None if it is at rest at none of them."""
    a = rest_voltage(model, state, lo, lo, hi)
    bank = model._new_bank(state)
    bank.step(a)
    if np.any(bank.state != state):
        return None
    return a, rest_voltage(model, state, hi, lo, hi)


def compensate(model: Any, y_desired: ArrayLike, *, u_min: float | None = None,
               u_max: float | None = None, slew_rate: float | None = None,
               initial_voltage: float | None = None, initial_state: ArrayLike | None = None,
               t: ArrayLike | None = None, creep_state: ArrayLike | None = None,
               sample_period: float | None = None) -> CompensationResult:
    """Voltages that make ``model`` follow the desired displacements ``y_desired``.

    Exact inverse sample by sample (see the module notes), within the voltage limits
    and the slew limit. Any values are accepted: out of reach saturates at a limit and
    is flagged, NaN holds the last voltage and is flagged.

    A model with a delay of d samples is compensated with preview (module notes):
    ``voltage[k]`` aims at ``desired[k + d]``, the last d voltages hold, and
    ``displacement[k]`` is the model's output at sample k, equal to ``desired`` on
    samples d.. wherever it was reached. The first d samples show the voltage held
    before the run and carry no flags (no voltage of this run reaches them):
    ``displacement`` is ``model.predict(voltage, initial_state=initial_state,
    pending_input=[initial_voltage] * d)`` (with creep: the same ``t``). With sample
    times ``t`` at another period than the model's, the delay is converted when exact
    (``model.delay_at``).

    Parameters
    ----------
    model : PIModel or BoucWenModel
        A model with non-negative weights, or a monotone Bouc-Wen model
        (:class:`pihyst.inverse.BoucWenCompensator`).
    y_desired : array_like
        Desired displacements, one per sample.
    u_min, u_max, slew_rate, initial_voltage, initial_state, creep_state
        As for :class:`Compensator` (``slew_rate`` in V/s).
    t : array_like, optional
        Sample times (s) for a model with creep (default: every ``model.creep.dt``);
        without creep only the slew limit's sample period comes from them.
    sample_period : float, optional
        The period (s) a slew limit is converted at; default the smallest interval of
        ``t``, else the model's (:class:`Compensator`).

    Returns
    -------
    CompensationResult
        ``voltage``, ``displacement`` (the model's prediction for those voltages),
        ``saturated`` per sample, the other flags and counts, and the final state.

    Raises
    ------
    InvalidModelError
        If the model cannot be inverted (a negative weight, a Bouc-Wen model that is
        not monotone).
    InvalidArgumentError
        If an argument is not valid (the message names it).

    Examples
    --------
    >>> import numpy as np, pihyst
    >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    >>> desired = 20 + 15 * np.sin(np.linspace(0, 6 * np.pi, 600)) * np.linspace(1, 0.2, 600)
    >>> result = pihyst.compensate(model, np.r_[0.0, desired, 50.0])
    >>> float(np.max(np.abs(result.displacement - result.desired)[:-1])) < 1e-9
    True
    >>> result.n_saturated, float(result.voltage[-1])   # 50 um is out of reach
    (1, 150.0)
    """
    cls = OTHER_COMPENSATORS.get(getattr(model, "family", None), Compensator)
    if slew_rate is not None and sample_period is None:
        sample_period = slew_per_sample(slew_rate, model, None, t, takes_times=True)[1]
    comp = cls(model, u_min=u_min, u_max=u_max, slew_rate=slew_rate,
               initial_voltage=initial_voltage, initial_state=initial_state,
               creep_state=creep_state, sample_period=sample_period)
    run = comp.run
    d = model.delay_at(t=t)
    if d == 0:
        return run(y_desired, t)
    y = _desired(y_desired)
    if t is not None:
        t = np.asarray(t, dtype=np.float64)
        if t.shape != y.shape:
            raise InvalidArgumentError(f"t must have one time per desired value "
                                       f"({y.size}), got shape {t.shape}")
    return PreviewRun(comp, d).feed(y, t, last=True)


class PreviewRun:
    """Compensation with preview for a model delayed by d samples, of a trajectory given
    whole or block by block (module notes): ``feed(block)`` returns the samples whose
    voltage is known so far, d behind the targets fed; ``feed(block, last=True)`` also
    the last d, whose voltage holds. Sample k gets ``voltage[k]`` aiming at
    ``desired[k + d]``, the displacement the model has at k (the compensator's at
    ``desired[k]``; before sample d the one at the initial voltage, which the actuator
    held before the run) and the flags of ``desired[k]`` (none before sample d).

    Parameters
    ----------
    compensator : Compensator or BoucWenCompensator
        The compensator of the delayed model, at the state the run starts from.
    delay : int
        The model's delay d in samples.

    Examples
    --------
    >>> import pihyst
    >>> from pihyst.inverse import PreviewRun
    >>> m = pihyst.ClassicalPI([0], [2.0], delay=1)
    >>> run = PreviewRun(pihyst.Compensator(m), m.delay)
    >>> run.feed([2.0, 4.0]).voltage.tolist()      # sample 0 aims at desired[1]
    [2.0]
    >>> run.feed([6.0], last=True).voltage.tolist()
    [3.0, 3.0]
    """

    def __init__(self, compensator: Any, delay: int) -> None:
        self.comp, self.d = compensator, int(delay)
        self._seen = 0                   # targets fed
        self._desired = np.empty(0)      # targets of the samples not yet returned
        self._voltage = np.empty(0)      # voltages of those samples, as far as known
        # the compensator's displacement and flags of desired[k - d], sample k on, after
        # the first ``_before`` samples (sample k < d: the displacement at the initial
        # voltage, no flags)
        self._before = self.d
        self._reached_y = np.empty(0)
        self._reached_flags = np.empty(0, dtype=np.uint8)
        self._start: Any = None
        self._t_last = None

    def _run(self, y, t, t_previous):
        return self.comp.run(y, t=t, t_previous=t_previous)

    def feed(self, y_desired: ArrayLike, t: ArrayLike | None = None, *,
             last: bool = False) -> CompensationResult:
        """The samples completed by the targets ``y_desired``.

        Parameters
        ----------
        y_desired : array_like
            The next desired displacements (µm).
        t : array_like, optional
            Their sample times (s), for a model with creep.
        last : bool, default False
            The trajectory ends here: return every remaining sample (the last d hold
            the last voltage).

        Returns
        -------
        CompensationResult
            The samples whose voltage is now known, in order, continuing the previous
            results.

        Raises
        ------
        InvalidArgumentError
            If ``y_desired`` is not a vector of numbers.

        Examples
        --------
        >>> import pihyst
        >>> m = pihyst.ClassicalPI([0], [2.0], delay=1)
        >>> PreviewRun(pihyst.Compensator(m), 1).feed([2.0, 4.0], last=True).voltage.tolist()
        [2.0, 2.0]
        """
        y = _desired(y_desired)
        if self._start is None:
            self._start = (self.comp.state, self.comp.voltage, self.comp.displacement,
                           getattr(self.comp, "creep_state", None))
        skip = max(0, min(self.d - self._seen, y.size))      # the first d: no voltage
        self._seen += y.size
        self._desired = np.concatenate([self._desired, y])
        t_previous = None
        if t is not None:
            # the first target fed comes one sample interval after the sample before it
            t = np.asarray(t, dtype=np.float64)
            t_previous = t[skip - 1] if skip > 0 else self._t_last
            self._t_last = t[-1] if t.size else self._t_last
        ahead = self._run(y[skip:], None if t is None else t[skip:], t_previous)
        #: the compensator's run on this block's targets (``block[skip:]``)
        self.ahead, self.skip = ahead, skip
        self._voltage = np.concatenate([self._voltage, ahead.voltage])
        self._reached_y = np.concatenate([self._reached_y, ahead.displacement])
        self._reached_flags = np.concatenate([self._reached_flags,
                                              np.asarray(ahead.flags, dtype=np.uint8)])
        n = self._desired.size if last else self._voltage.size
        held = n - self._voltage.size
        voltage = np.concatenate([self._voltage, np.full(held, self.comp.voltage)])
        first = min(n, self._before)     # samples before d: the initial displacement
        rest = n - first
        out = run_result(
            self.comp, self._desired[:n], voltage[:n],
            np.concatenate([np.full(first, self._start[2], dtype=np.float64),
                            self._reached_y[:rest]]),
            np.concatenate([np.zeros(first, dtype=np.uint8), self._reached_flags[:rest]]),
            self._start[0], self._start[1], initial_creep_state=self._start[3],
            final_creep_state=getattr(self.comp, "creep_state", None))
        self._desired, self._voltage = self._desired[n:], voltage[n:]
        self._before -= first
        self._reached_y, self._reached_flags = self._reached_y[rest:], self._reached_flags[rest:]
        return out


def run_result(comp, desired, voltage, displacement, flags, initial_state, initial_voltage,
               **creep_states):
    """The :class:`CompensationResult` of a run of the compensator ``comp`` (now at its
    end), its per-sample booleans derived from ``flags``."""
    return _with_flag_arrays(CompensationResult(
        desired=desired, voltage=voltage, displacement=displacement, flags=flags,
        saturated=None, saturated_low=None, saturated_high=None, slew_limited=None,
        nan_held=None, initial_state=initial_state, initial_voltage=initial_voltage,
        final_state=comp.state, final_voltage=comp.voltage, limits=comp.limits,
        slew_rate=comp.slew_rate, max_step=comp.max_step, **creep_states))


def _with_flag_arrays(result):
    """``result`` with its per-sample booleans derived from its flags."""
    flags = result.flags
    low = (flags & FLAG_SATURATED_LOW) != 0
    high = (flags & FLAG_SATURATED_HIGH) != 0
    return replace(result, saturated=low | high, saturated_low=low, saturated_high=high,
                   slew_limited=(flags & FLAG_SLEW) != 0, nan_held=(flags & FLAG_NAN) != 0)


def slew_per_sample(slew_rate, model, sample_period=None, t=None, takes_times=False):
    """``(slew_rate, sample_period, max_step)`` of a compensator: the slew limit in V/s
    (None: none), the sample period it is converted at (s) and the largest voltage step
    per sample (V),

        max_step = slew_rate * sample_period.

    The period is ``sample_period`` when given, else the smallest interval of the sample
    times ``t``, else the model's (``model.sample_period``, else its creep lags' ``dt``);
    a slew limit with none of these is refused (the package's one unit convention: slew
    in V/s, time in s, docs/interfaces.md); ``takes_times``: the caller takes ``t`` (the
    message says so)."""
    if slew_rate is None:
        return None, _period_or_none(sample_period), None
    slew_rate = _number(slew_rate, "slew_rate", allow_inf=True)
    if not slew_rate > 0:
        raise InvalidArgumentError(f"slew_rate must be > 0 V/s, got {slew_rate:g}")
    period = _period_or_none(sample_period)
    if period is None and t is not None:
        steps = np.diff(np.asarray(t, dtype=np.float64))
        steps = steps[np.isfinite(steps) & (steps > 0)]
        period = float(steps.min()) if steps.size else None
    if period is None:
        period = getattr(model, "sample_period", None)
    if period is None and getattr(model, "creep", None) is not None:
        period = float(model.creep.dt)
    if period is None:
        raise InvalidArgumentError(
            f"slew_rate is in V/s and the model has no sample period to convert it to a step "
            f"per sample: give sample_period= (s){' or sample times t' if takes_times else ''}")
    return slew_rate, period, slew_rate * period


def _period_or_none(period):
    if period is None:
        return None
    period = _number(period, "sample_period")
    if not (np.isfinite(period) and period > 0):
        raise InvalidArgumentError(f"sample_period must be a positive number of seconds, got "
                                   f"{period:g}")
    return period


def _number(value, name, allow_inf=False, allow_nan=False):
    if isinstance(value, (str, bytes, bool, np.bool_)):     # float() would take "100"
        raise InvalidArgumentError(f"{name} must be a number, got {value!r:.40}")
    try:
        v = float(value)
    except (TypeError, ValueError, OverflowError):
        raise InvalidArgumentError(f"{name} must be a number, got {value!r:.40}") from None
    if (np.isnan(v) and not allow_nan) or (np.isinf(v) and not allow_inf):
        raise InvalidArgumentError(f"{name} must be a finite number, got {v}")
    return v


def _desired(y_desired):
    real_array(y_desired, "y_desired")
    try:
        y = np.array(y_desired, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise InvalidArgumentError("y_desired must be a sequence of numbers") from None
    if y.ndim != 1:
        raise InvalidArgumentError(f"y_desired must be one-dimensional, got shape {y.shape}")
    return y
