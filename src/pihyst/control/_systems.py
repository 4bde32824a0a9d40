"""A model and its compensator as discrete-time python-control systems.

Both are :class:`control.NonlinearIOSystem` objects whose states are the operator
outputs f_k, so they interconnect with linear dynamics (``control.series``,
``control.interconnect``, ``*``) and simulate with ``control.input_output_response``.
One sample of each is one step of pihyst's C core, the code ``predict`` and
``compensate`` run:

model (input ``voltage``, output ``displacement``, states ``f[k]``)::

    f[t] = play(u[t], f[t-1])             (the state update)
    y[t] = offset + sum_k w_k f_k[t]      (the output: the same step, read before it)

so the system's state x[t] is f[t-1], the operator state before sample t, and the
output has direct feedthrough from the input, as the model has.

compensator (input ``desired``, output ``voltage``, states ``f[k]`` and ``u_last``):
the exact inverse of :class:`pihyst.Compensator` (limits, slew limit), with the last
voltage as a state because the slew limit and the choice of voltage on a flat stretch
depend on it.

python-control evaluates the output function more than once per step, and in an
interconnection first with provisional inputs; each system therefore caches its last
step, and the model's output for an input outside its range is that of the nearest
input in the range (a provisional value), while its state update raises
:class:`~pihyst.exceptions.InputRangeError` (the input really applied).
"""

import numpy as np
from numpy.typing import ArrayLike, NDArray

try:
    import control as ct
except ImportError:  # pragma: no cover - exercised only without the extra
    raise ImportError("pihyst.control needs python-control: "
                      "pip install 'pihyst[control]'") from None

from pihyst.exceptions import InputRangeError, InvalidArgumentError, InvalidModelError
from pihyst.inverse import Compensator
from pihyst.model import PIModel

__all__ = ["compensator_state", "compensator_system", "model_system"]


def _labels(prefix, n):
    return [f"{prefix}[{k}]" for k in range(n)]


def _scalar(u):
    u = np.asarray(u, dtype=np.float64).reshape(-1)
    return float(u[0])


class _ModelStep:
    """One step of a model from a given operator state, cached on (state, input)."""

    def __init__(self, model):
        self.model = model
        self.stepper = model.stepper()
        self.lo, self.hi = model.input_range
        self.key = None

    def __call__(self, x, u):
        x = np.asarray(x, dtype=np.float64)
        key = (x.tobytes(), u)
        if key != self.key:
            self.stepper.reset(x)
            y = self.stepper.step(u)
            self.key, self.value = key, (self.stepper.state, y)
        return self.value

    def output(self, t, x, u, params):
        # an input outside the range can be a provisional one of an interconnection:
        # answer for the nearest input in the range (finite, so python-control's
        # fixed-point iteration settles); the update of the same sample raises if the
        # input really applied is outside
        u = min(max(_scalar(u), self.lo), self.hi)
        return np.array([self(x, u)[1]])

    def update(self, t, x, u, params):
        u = _scalar(u)
        if not self.lo <= u <= self.hi:
            err = InputRangeError(0, u, self.model.input_range)
            err.index = None
            err.args = (f"time {t:g}: input {u:g} is outside the model's input range "
                        f"[{self.lo:g}, {self.hi:g}]",)
            raise err
        return self(x, u)[0]


class _CompensatorStep:
    """One step of a compensator from a given (operator state, last voltage).

    The C compensator carries, besides its state, the model output at the last voltage
    (from which it solves the next sample); a reset recomputes that output from the
    state, which may round differently from the value the running compensator has. So
    a step from the state the compensator has just reached continues without a reset,
    and a simulation gives the voltages of :func:`pihyst.compensate` bit for bit; the
    steps of the last few (state, input) pairs are kept for python-control's repeated
    calls."""

    _MEMO = 8

    def __init__(self, compensator):
        self.comp = compensator
        self.n = compensator.model.n_operators
        self.here = None    # the state the compensator is at, as bytes
        self.memo = {}

    def __call__(self, x, y_desired):
        x = np.asarray(x, dtype=np.float64)
        key = (x.tobytes(), y_desired)
        if key in self.memo:
            return self.memo[key]
        if key[0] != self.here:
            self.comp.reset(x[:self.n], x[self.n])
        u = self.comp.step(y_desired)
        new = np.r_[self.comp.state, u]
        self.here = new.tobytes()
        if len(self.memo) >= self._MEMO:
            self.memo.clear()
        self.memo[key] = (new, u)
        return new, u

    def output(self, t, x, u, params):
        return np.array([self(x, _scalar(u))[1]])

    def update(self, t, x, u, params):
        return self(x, _scalar(u))[0]


def _check(model):
    if not isinstance(model, PIModel):
        raise InvalidArgumentError(f"model must be a pihyst model (ClassicalPI, MultislopePI, "
                                   f"PiecewiseLinearPI), not {type(model).__name__}")
    if model.delay:
        # the system's state is the operator state: it has no room for pending inputs
        raise InvalidModelError(f"the model has an input delay of {model.delay} samples: "
                                f"make the system of model.replace(delay=0) and put the "
                                f"delay in series (a {model.delay}-sample delay block)")


def model_system(model: PIModel, dt: float | bool = True, *, name: str | None = None,
                 inputs: str = "voltage", outputs: str = "displacement") -> "ct.NonlinearIOSystem":
    """The model as a discrete-time :class:`control.NonlinearIOSystem`.

    Parameters
    ----------
    model : PIModel
        Any pihyst model.
    dt : float or True
        Sampling period (True: unspecified, as python-control allows).
    name, inputs, outputs : str, optional
        System and signal names (signals default to ``voltage`` and ``displacement``,
        so ``control.interconnect`` connects a compensator's ``voltage`` to it by name).

    Returns
    -------
    control.NonlinearIOSystem
        One input, one output, one state ``f[k]`` per operator: the operator state
        before each sample. Start it from ``model.initial_state`` (python-control's
        default initial state is zero).

    Examples
    --------
    >>> import numpy as np, control, pihyst
    >>> from pihyst.control import model_system
    >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    >>> u = np.r_[np.linspace(0, 150, 76), np.linspace(150, 0, 76)[1:]]
    >>> resp = control.input_output_response(model_system(model), np.arange(u.size), u,
    ...                                      model.initial_state)
    >>> bool(np.array_equal(resp.outputs, model.predict(u)))
    True
    """
    _check(model)
    step = _ModelStep(model)
    k = model.n_operators
    return ct.NonlinearIOSystem(step.update, step.output, inputs=inputs, outputs=outputs,
                                states=_labels("f", k), dt=dt, name=name)


def compensator_system(model: PIModel, dt: float | bool = True, *, u_min: float | None = None,
                       u_max: float | None = None, slew_rate: float | None = None,
                       name: str | None = None, inputs: str = "desired",
                       outputs: str = "voltage") -> "ct.NonlinearIOSystem":
    """The model's exact compensator as a discrete-time :class:`control.NonlinearIOSystem`.

    Parameters
    ----------
    model : PIModel
        A model with non-negative weights.
    dt : float or True
        Sampling period (True: unspecified).
    u_min, u_max, slew_rate
        As for :class:`pihyst.Compensator`: voltage limits inside the model's input
        range, and the largest rate of voltage change in V/s (converted at ``dt`` when it
        is a number, else at the model's sample period).
    name, inputs, outputs : str, optional
        System and signal names (``desired`` and ``voltage`` by default).

    Returns
    -------
    control.NonlinearIOSystem
        Input: the desired displacement; output: the voltage; states: the operator
        state ``f[k]`` and the last voltage ``u_last``. Start it from
        :func:`compensator_state` (python-control's default initial state is zero:
        the zero operator state at 0 V).

    Examples
    --------
    >>> import numpy as np, control, pihyst
    >>> from pihyst.control import compensator_state, compensator_system
    >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    >>> desired = 20 + 15 * np.sin(np.linspace(0, 4 * np.pi, 200))
    >>> resp = control.input_output_response(compensator_system(model),
    ...                                      np.arange(desired.size), desired,
    ...                                      compensator_state(model))
    >>> bool(np.array_equal(resp.outputs, pihyst.compensate(model, desired).voltage))
    True
    """
    _check(model)
    period = None if dt is True or dt is None else dt
    comp = Compensator(model, u_min=u_min, u_max=u_max, slew_rate=slew_rate,
                       sample_period=period if slew_rate is not None else None)
    step = _CompensatorStep(comp)
    k = model.n_operators
    return ct.NonlinearIOSystem(step.update, step.output, inputs=inputs, outputs=outputs,
                                states=_labels("f", k) + ["u_last"], dt=dt, name=name)


def compensator_state(model: PIModel, *, u_min: float | None = None,
                      u_max: float | None = None, initial_voltage: float | None = None,
                      initial_state: ArrayLike | None = None) -> NDArray[np.float64]:
    """The initial state of :func:`compensator_system`: the operator state (default the
    model's own) with the initial voltage applied (default 0 V, or the nearer limit),
    then that voltage; as :class:`pihyst.Compensator` starts.

    Parameters
    ----------
    model : PIModel
        The model the compensator inverts (non-negative weights).
    u_min, u_max, initial_voltage, initial_state
        As for :class:`pihyst.Compensator`.

    Returns
    -------
    numpy.ndarray
        The K operator states, then the voltage.

    Raises
    ------
    InvalidModelError
        If the model cannot be inverted.
    InvalidArgumentError
        If the model is not a PI model or an argument is not valid.

    Examples
    --------
    >>> import pihyst
    >>> from pihyst.control import compensator_state
    >>> compensator_state(pihyst.ClassicalPI([0, 10], [1.0, 0.5]), u_min=20.0).tolist()
    [20.0, 10.0, 20.0]
    """
    _check(model)
    comp = Compensator(model, u_min=u_min, u_max=u_max, initial_voltage=initial_voltage,
                       initial_state=initial_state)
    return np.r_[comp.state, comp.voltage]
