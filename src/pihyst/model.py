"""PI-type hysteresis models: value objects over the C core.

A model is y[t] = offset + sum_k w_k f_k[t], with f_k the generalized play operators
f_k[t] = max(R_k(u[t]), min(F_k(u[t]), f_k[t-1])) of one family (DESIGN.md section 2):

- :class:`ClassicalPI`: R(u) = u - r, F(u) = u + r (paper eq. 1);
- :class:`MultislopePI`: the paper's multislope play (eq. 6) with shape (U, a, b, h);
- :class:`PiecewiseLinearPI`: user-given polyline envelopes (covers both, and
  Krasnosel'skii-Pokrovskii kernels).

The parameters are fixed at construction and validated there: an invalid model cannot
exist. ``predict``/``simulate`` never touch the model; ``step`` advances a running
state that starts at ``initial_state`` and is reset by ``reset``.
"""

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from pihyst import _core

PAPER_SHAPE = {"U": 150.0, "a": 0.8, "b": 1.2, "h": 0.5}
DEFAULT_INPUT_RANGE = (0.0, 150.0)
DEFAULT_UNITS = {"input": "V", "output": "um"}


class InvalidModelError(ValueError):
    """The parameters do not describe a valid model; the message says which and why."""


class InputRangeError(ValueError):
    """An input sample lies outside the model's input range."""

    def __init__(self, index, value, input_range):
        self.index = index
        self.value = value
        super().__init__(f"sample {index}: input {value:g} is outside the model's input range "
                         f"[{input_range[0]:g}, {input_range[1]:g}]")


@dataclass(frozen=True)
class Response:
    """Result of :meth:`PIModel.simulate`."""

    input: np.ndarray
    output: np.ndarray
    final_state: np.ndarray


def _finite_vector(values, name, length=None):
    try:
        a = np.array(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidModelError(f"{name} must be a list of numbers") from None
    if a.ndim != 1:
        raise InvalidModelError(f"{name} must be a flat list of numbers")
    if length is not None and a.size != length:
        raise InvalidModelError(f"{name} must have {length} values (one per operator), "
                                f"got {a.size}")
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise InvalidModelError(f"{name}[{bad[0]}] is {a[bad[0]]}, not a finite number")
    a.setflags(write=False)
    return a


class PIModel(ABC):
    """Base of every family: weights, offset, input range, initial state, units.

    Subclasses describe their operators through ``_bank_args``.
    """

    family = None

    def __init__(self, weights, *, offset=0.0, input_range=None, initial_state=None,
                 units=None):
        self.weights = _finite_vector(weights, "weights")
        if self.weights.size == 0:
            raise InvalidModelError("a model needs at least one operator (weights is empty)")
        self.offset = float(offset)
        if not np.isfinite(self.offset):
            raise InvalidModelError(f"offset is {self.offset}, not a finite number")
        lo, hi = DEFAULT_INPUT_RANGE if input_range is None else input_range
        self.input_range = (float(lo), float(hi))
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise InvalidModelError(f"input_range must be [min, max] with min < max, got "
                                    f"{list(self.input_range)}")
        self.initial_state = (np.zeros(self.weights.size) if initial_state is None else
                              _finite_vector(initial_state, "initial_state", self.weights.size))
        self.initial_state.setflags(write=False)
        self.units = dict(DEFAULT_UNITS if units is None else units)
        self.metadata = {}
        self._bank = self._new_bank(self.initial_state)

    @property
    def n_operators(self):
        return self.weights.size

    @abstractmethod
    def _bank_args(self):
        """Family-specific keyword arguments of :class:`pihyst._core.Bank`."""

    def _new_bank(self, initial_state):
        try:
            return _core.Bank(self.family, weights=self.weights, offset=self.offset,
                              u_min=self.input_range[0], u_max=self.input_range[1],
                              initial_state=initial_state, **self._bank_args())
        except _core.CoreError as err:
            raise InvalidModelError(f"invalid {self.family} model: {err}") from None

    # ---------------------------------------------------------------- batch
    def _checked_input(self, u):
        u = np.ascontiguousarray(u, dtype=np.float64)
        if u.ndim != 1:
            raise ValueError(f"input must be one-dimensional, got shape {u.shape}")
        lo, hi = self.input_range
        # min/max first: two fast passes; NaN makes the comparison fail too
        if u.size and not (u.min() >= lo and u.max() <= hi):
            bad = np.flatnonzero(~((u >= lo) & (u <= hi)))
            raise InputRangeError(int(bad[0]), float(u[bad[0]]), self.input_range)
        return u

    def _state_or_initial(self, initial_state):
        if initial_state is None:
            return self.initial_state
        return _finite_vector(initial_state, "initial_state", self.n_operators)

    def simulate(self, u, *, initial_state=None):
        """Run the model over the input ``u`` from ``initial_state`` (default: the
        model's own). Returns a :class:`Response` with the final operator state,
        from which a following chunk continues exactly."""
        u = self._checked_input(u)
        bank = self._new_bank(self._state_or_initial(initial_state))
        y = bank.run(u)
        return Response(input=u, output=y, final_state=bank.state)

    def predict(self, u, *, initial_state=None):
        """Displacements for the voltages ``u`` (a NumPy array of the same length)."""
        return self.simulate(u, initial_state=initial_state).output

    def operators(self, u, *, initial_state=None):
        """The N x K operator matrix Phi[t, k] = f_k[t] (paper eq. 8)."""
        u = self._checked_input(u)
        return self._new_bank(self._state_or_initial(initial_state)).operators(u)

    def envelopes(self, u):
        """(R_k(u), F_k(u)) of every operator at one input value."""
        return self._bank.envelopes(float(u))

    # ---------------------------------------------------------------- streaming
    @property
    def state(self):
        """The running operator state used by :meth:`step` (a copy)."""
        return self._bank.state

    def reset(self, state=None):
        """Set the running state to ``state`` (default: the initial state)."""
        self._bank.state = self._state_or_initial(state)

    def step(self, u):
        """One sample: advance the running state by the input ``u``, return y."""
        u = float(u)
        lo, hi = self.input_range
        if not lo <= u <= hi:
            raise InputRangeError(0, u, self.input_range)
        return self._bank.step(u)

    # ---------------------------------------------------------------- derived models
    def replace(self, **changes):
        """A copy with some constructor arguments changed (e.g. weights, offset)."""
        params = self._params()
        params.update(changes)
        return type(self)(**params)

    def _params(self):
        return {"weights": self.weights, "offset": self.offset,
                "input_range": self.input_range, "initial_state": self.initial_state,
                "units": self.units}

    # ---------------------------------------------------------------- persistence
    def to_dict(self):
        """The model as a JSON-ready dict (see :func:`pihyst.io.load_model`)."""
        from pihyst.io import model_to_dict
        return model_to_dict(self)

    def save(self, path):
        """Write the model as JSON to ``path``."""
        from pihyst.io import save_model
        save_model(self, path)

    def __repr__(self):
        return f"{type(self).__name__}({self._describe()}, weights={self.weights.tolist()})"

    def _describe(self):
        return ""


class ClassicalPI(PIModel):
    """Classical Prandtl-Ishlinskii model (paper eq. 1-3).

    Examples
    --------
    >>> import numpy as np
    >>> m = ClassicalPI([0, 10, 30, 150], [0.008, 0.252, 0.019, 0.582])
    >>> u = np.r_[np.arange(0, 151), np.arange(149, -1, -1)]
    >>> y = m.predict(u)
    >>> print(f"{y[150]:.2f} {y[-1]:.2f}")
    38.76 3.09
    """

    family = "classical"

    def __init__(self, thresholds, weights, **kwargs):
        self.thresholds = _finite_vector(thresholds, "thresholds")
        super().__init__(weights, **kwargs)
        if self.thresholds.size != self.weights.size:
            raise InvalidModelError(f"{self.thresholds.size} thresholds but "
                                    f"{self.weights.size} weights")

    def _bank_args(self):
        _check_thresholds(self.thresholds, self.weights.size)
        return {"thresholds": self.thresholds}

    def _params(self):
        return {"thresholds": self.thresholds, **super()._params()}

    def _describe(self):
        return f"thresholds={self.thresholds.tolist()}"

    def inverse(self):
        """The analytic inverse, a :class:`ClassicalPI` from displacement to voltage
        (DESIGN.md section 4; see :func:`pihyst.inverse.classical_inverse`)."""
        from pihyst.inverse import classical_inverse
        return classical_inverse(self)


class MultislopePI(PIModel):
    """Multislope PI model of Xu et al. (2020), eq. 6, with shape (U, a, b, h).

    R(u) = max(a(u - r), b u - r - (b - 1)U),  F(u) = min(b u, a u + (1 - a)U - (1 - a h) r).
    Thresholds must not exceed (1 - a)U / (1 - a h) (50 V for the paper's shape).

    Examples
    --------
    >>> import numpy as np
    >>> m = MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    >>> u = np.r_[np.arange(0, 151), np.arange(149, -1, -1)]
    >>> y = m.predict(u)
    >>> print(f"{y[150]:.2f} {abs(y[-1]):.1f}")
    41.38 0.0
    """

    family = "multislope"

    def __init__(self, thresholds, weights, *, U=PAPER_SHAPE["U"], a=PAPER_SHAPE["a"],
                 b=PAPER_SHAPE["b"], h=PAPER_SHAPE["h"], input_range=None, **kwargs):
        self.thresholds = _finite_vector(thresholds, "thresholds")
        self.U, self.a, self.b, self.h = (float(v) for v in (U, a, b, h))
        shape = np.array([self.U, self.a, self.b, self.h])
        if not np.all(np.isfinite(shape)):
            raise InvalidModelError(f"multislope shape U={U}, a={a}, b={b}, h={h} is not finite")
        if not (self.U > 0 and 0 < self.a < self.b and 0 <= self.h <= 1):
            raise InvalidModelError(f"multislope shape needs U > 0, 0 < a < b and 0 <= h <= 1; "
                                    f"got U={U:g}, a={a:g}, b={b:g}, h={h:g}")
        if input_range is None:
            input_range = (0.0, self.U)
        super().__init__(weights, input_range=input_range, **kwargs)
        if self.thresholds.size != self.weights.size:
            raise InvalidModelError(f"{self.thresholds.size} thresholds but "
                                    f"{self.weights.size} weights")

    @property
    def max_threshold(self):
        """Largest valid threshold, (1 - a)U / (1 - a h): F's kink stays at u >= 0."""
        return (1 - self.a) * self.U / (1 - self.a * self.h)

    def _bank_args(self):
        _check_thresholds(self.thresholds, self.weights.size)
        r_max = self.thresholds.max(initial=0.0)
        if r_max > self.max_threshold * (1 + 1e-12):
            raise InvalidModelError(
                f"multislope threshold {r_max:g} is above (1 - a)U/(1 - a h) = "
                f"{self.max_threshold:g} for U={self.U:g}, a={self.a:g}, h={self.h:g}: "
                f"its falling envelope would not return to the origin")
        return {"thresholds": self.thresholds, "shape": (self.U, self.a, self.b, self.h)}

    def _params(self):
        return {"thresholds": self.thresholds, "U": self.U, "a": self.a, "b": self.b,
                "h": self.h, **super()._params()}

    def _describe(self):
        return (f"thresholds={self.thresholds.tolist()}, U={self.U:g}, a={self.a:g}, "
                f"b={self.b:g}, h={self.h:g}")


class PiecewiseLinearPI(PIModel):
    """PI model whose operators have user-given polyline envelopes.

    ``rising[k]`` and ``falling[k]`` are (x, y) breakpoint pairs of operator k, x strictly
    increasing and y non-decreasing; beyond its ends a polyline continues with the slope
    of its end segment. R_k <= F_k must hold on the input range.
    """

    family = "pwl"

    def __init__(self, rising, falling, weights, **kwargs):
        self.rising = [_polyline(p, f"rising[{k}]") for k, p in enumerate(rising)]
        self.falling = [_polyline(p, f"falling[{k}]") for k, p in enumerate(falling)]
        super().__init__(weights, **kwargs)

    def _bank_args(self):
        k = self.weights.size
        if len(self.rising) != k or len(self.falling) != k:
            raise InvalidModelError(f"pwl model needs one rising and one falling polyline per "
                                    f"weight: {len(self.rising)} rising, {len(self.falling)} "
                                    f"falling, {k} weights")
        return {"thresholds": None, "rising": self.rising, "falling": self.falling}

    def _params(self):
        return {"rising": self.rising, "falling": self.falling, **super()._params()}

    def _describe(self):
        return f"{len(self.rising)} polyline operators"


def _check_thresholds(thresholds, n):
    if thresholds.size != n:
        raise InvalidModelError(f"{thresholds.size} thresholds but {n} weights")
    if thresholds.size and thresholds.min() < 0:
        raise InvalidModelError(f"thresholds must be >= 0, got {thresholds.min():g}")
    steps = np.flatnonzero(np.diff(thresholds) <= 0)
    if steps.size:
        i = steps[0]
        raise InvalidModelError(f"thresholds must be strictly increasing: thresholds[{i}] = "
                                f"{thresholds[i]:g} is followed by {thresholds[i + 1]:g}")


def _polyline(points, name):
    x, y = points
    x = _finite_vector(x, f"{name} x")
    y = _finite_vector(y, f"{name} y", x.size)
    if x.size == 0:
        raise InvalidModelError(f"{name} has no breakpoints")
    if np.any(np.diff(x) <= 0):
        raise InvalidModelError(f"{name}: breakpoints must be strictly increasing")
    if np.any(np.diff(y) < 0):
        raise InvalidModelError(f"{name}: envelope values must be non-decreasing")
    return (x, y)
