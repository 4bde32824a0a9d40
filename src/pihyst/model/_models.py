"""PI-type hysteresis models: value objects over the C core.

A model is y[t] = offset + sum_k w_k f_k[t], with f_k the generalized play operators
f_k[t] = max(R_k(u[t]), min(F_k(u[t]), f_k[t-1])) of one family (docs/theory/operators.md):

- :class:`ClassicalPI`: R(u) = u - r, F(u) = u + r (paper eq. 1);
- :class:`MultislopePI`: the paper's multislope play (eq. 6) with shape (U, a, b, h);
- :class:`PiecewiseLinearPI`: user-given polyline envelopes (covers both, and
  Krasnosel'skii-Pokrovskii kernels).

A model is a value: its parameters are fixed and validated at construction (an invalid
model cannot exist), two models with the same parameters are equal, and
:meth:`PIModel.replace` makes a changed copy. ``predict``/``simulate`` never touch the
model; sample-by-sample work goes through a :class:`Stepper` (``model.stepper()``), which
owns the running operator state.
"""

import json
import numbers
import os
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, ClassVar, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst import _core, paper
from pihyst._arguments import real_array
from pihyst._atomic import write_atomically
from pihyst._frozen import frozen, frozen_array
from pihyst.exceptions import InputRangeError, InvalidArgumentError, InvalidModelError
from pihyst.model._classical_inverse import classical_inverse
from pihyst.model._creep import Creep, first_interval, sample_intervals
from pihyst.model._delay import (
    DelayLine,
    checked_delay,
    checked_sample_period,
    delay_at,
    delayed_input,
    pending_after,
)

PAPER_SHAPE = paper.SHAPE
DEFAULT_INPUT_RANGE = (0.0, 150.0)
DEFAULT_UNITS = MappingProxyType({"input": "V", "output": "um"})
SCHEMA_VERSION = 1
_SHORT_VECTOR = 6   # repr shows at most this many values of a vector
#: Model classes that are not PI models (family -> class with from_dict), registered by
#: their modules; PIModel.from_dict dispatches to them
OTHER_FAMILIES: dict[str, Any] = {}
#: the JSON keys of the delay (docs/interfaces.md), omitted at their defaults
DELAY_KEYS = ("delay_samples", "sample_period_s")
#: a model class, for methods that return a model of their own class
_Model = TypeVar("_Model", bound="PIModel")


@dataclass(frozen=True)
class Response:
    """Result of :meth:`PIModel.simulate`.

    Parameters
    ----------
    input : numpy.ndarray
        The input run, as checked (V).
    output : numpy.ndarray
        The output at each sample (µm).
    final_state : numpy.ndarray
        The operator state after the last sample: a following chunk's ``initial_state``.
    final_creep_state : numpy.ndarray or None
        With creep: the lag states z_i after the last sample (None without creep).
    pending_input : numpy.ndarray or None
        With a delay of d samples: the last d inputs, not yet seen at the output (the
        ``pending_input`` of a following chunk); None without a delay.

    Examples
    --------
    >>> r = ClassicalPI([0, 10], [1.0, 0.5]).simulate([0.0, 20.0, 15.0])
    >>> r.output.tolist(), r.final_state.tolist()
    ([0.0, 25.0, 20.0], [15.0, 10.0])
    """

    input: np.ndarray
    output: np.ndarray
    final_state: np.ndarray
    #: with creep: the lag states z_i after the last sample (None without creep)
    final_creep_state: NDArray[np.float64] | None = None
    #: with a delay of d samples: the last d inputs, not yet seen at the output (the
    #: ``pending_input`` of a following chunk); None without a delay
    pending_input: NDArray[np.float64] | None = None


def _finite_vector(values, name, length=None):
    """``values`` as a read-only float vector; InvalidModelError unless it is a flat
    sequence of finite real numbers (not strings, not booleans)."""
    if isinstance(values, (str, bytes, dict)) or values is None:
        raise InvalidModelError(f"{name} must be a list of numbers, got "
                                f"{type(values).__name__}")
    try:
        raw = np.asarray(values)
    except (TypeError, ValueError, OverflowError):
        raise InvalidModelError(f"{name} must be a flat list of numbers") from None
    if raw.ndim != 1:
        raise InvalidModelError(f"{name} must be a flat list of numbers")
    mixed = isinstance(values, (list, tuple)) and any(
        isinstance(v, (bool, np.bool_, str)) for v in values)
    if mixed or raw.dtype.kind not in "iuf":
        # mixed or exotic items: each must be a real number (a huge int is too large)
        for i, v in enumerate(values if mixed else raw.tolist()):
            _finite_number(v, f"{name}[{i}]")
    try:
        a = np.array(raw, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise InvalidModelError(f"{name} must be a list of numbers") from None
    if length is not None and a.size != length:
        raise InvalidModelError(f"{name} must have {length} values (one per operator), "
                                f"got {a.size}")
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise InvalidModelError(f"{name}[{bad[0]}] is {a[bad[0]]}, not a finite number")
    return frozen_array(a)       # read-only, and cannot be made writable again


def simulated(model, u, state, hysteresis, *, t, creep_state, pending_input, t_previous):
    """The :class:`Response` of ``model`` (a PI or Bouc-Wen model) to the input ``u`` from
    ``state``: the input delayed by the model's delay (``pending_input`` before it), the
    hysteresis output ``hysteresis(state, delayed input) -> (output, final state)``, then
    the creep lags, if any, at the sample times ``t`` (module notes of ``simulate``)."""
    u = model._checked_input(u)
    d = model.delay_at(t=t)
    if d and pending_input is not None:
        pending_input = model._checked_input(pending_input)
    h, final = hysteresis(state, delayed_input(u, d, pending_input))
    pending = pending_after(u, d, pending_input) if d else None
    if model.creep is None:
        return Response(input=u, output=h, final_state=final, pending_input=pending)
    lags = model._lags(state, creep_state)
    dt = None if t is None else sample_intervals(t, u.size,
                                                 first_interval(model.creep, t, t_previous))
    return Response(input=u, output=lags.run(h, dt), final_state=final,
                    final_creep_state=lags.state, pending_input=pending)


def checked_input(u, input_range):
    """``u`` as a contiguous float array, every sample finite and inside ``input_range``
    (InvalidArgumentError, InputRangeError naming the first sample that is not)."""
    real_array(u, "input")
    try:
        u = np.ascontiguousarray(u, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise InvalidArgumentError("input must be a sequence of numbers") from None
    if u.ndim != 1:
        raise InvalidArgumentError(f"input must be one-dimensional, got shape {u.shape}")
    lo, hi = input_range
    # min/max first: two fast passes; NaN makes the comparison fail too
    if u.size and not (u.min() >= lo and u.max() <= hi):
        bad = np.flatnonzero(~((u >= lo) & (u <= hi)))
        raise InputRangeError(int(bad[0]), float(u[bad[0]]), input_range)
    return u


class Immutable:
    """A value: attributes are set once, in ``__init__`` (through object.__setattr__),
    and never after; ``replace(...)`` makes a changed copy."""

    def __setattr__(self, name, value):
        raise AttributeError(f"{type(self).__name__} is immutable: use "
                             f"model.replace({name}=...) for a changed copy")

    def __delattr__(self, name):
        raise AttributeError(f"{type(self).__name__} is immutable")

    def __reduce__(self):
        # pickle (multiprocessing, Dask) and copy by the constructor's arguments: the
        # read-only units and metadata are remade, not copied attribute by attribute
        return (_rebuilt, (type(self), self._params()))


def _rebuilt(cls, params):
    return cls(**params)


def checked_units(units):
    """Read-only units of a model (default: V in, um out); InvalidModelError if not names
    mapped to strings."""
    units = DEFAULT_UNITS if units is None else units
    if not (isinstance(units, (dict, MappingProxyType))
            and all(isinstance(k, str) and isinstance(v, str) for k, v in units.items())):
        raise InvalidModelError(f"units must map names to strings, got {units!r:.60}")
    return MappingProxyType(dict(units))


def checked_metadata(metadata):
    """Deeply read-only metadata of a model (nested dicts and lists too: ``FrozenDict``,
    ``FrozenList``); InvalidModelError if not a dict."""
    if metadata is not None and not isinstance(metadata, (dict, MappingProxyType)):
        raise InvalidModelError(f"metadata must be a dict, got {type(metadata).__name__}")
    return frozen(metadata or {})


def metadata_json(value, where="metadata"):
    """``value`` (a model's metadata) in plain JSON types: NumPy scalars and arrays become
    numbers and lists, tuples lists, and a number that is not finite ``None`` (JSON has no
    NaN, and a model file with one could not be loaded); InvalidModelError for anything
    JSON cannot hold, naming where it is."""
    if isinstance(value, np.ndarray):
        value = value.tolist()
    elif isinstance(value, np.generic):
        value = value.item()
    if value is None or isinstance(value, (str, bool)):
        return value
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        value = float(value)
        return value if np.isfinite(value) else None
    if isinstance(value, (dict, MappingProxyType)):
        plain = {}
        for key, item in value.items():
            if isinstance(key, np.generic):
                key = key.item()
            if not (key is None or isinstance(key, (str, int, float, bool))):
                raise InvalidModelError(f"{where}: key {key!r:.40} is not a JSON key (a "
                                        f"string or a number)")
            plain[key] = metadata_json(item, f"{where}[{key!r}]")
        return plain
    if isinstance(value, (list, tuple)):
        return [metadata_json(item, f"{where}[{i}]") for i, item in enumerate(value)]
    raise InvalidModelError(f"{where}: a {type(value).__name__} cannot be written as JSON")


def _finite_number(value, name):
    """``value`` as a float; InvalidModelError unless it is a finite real number (a
    string or a boolean is not a number)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise InvalidModelError(f"{name} must be a number, got {value!r:.40}")
    try:
        x = float(value)
    except OverflowError:
        raise InvalidModelError(f"{name} is too large for a floating-point number") from None
    if not np.isfinite(x):
        raise InvalidModelError(f"{name} is {x}, not a finite number")
    return x


def _short(values):
    """A vector for a repr: every value when short, the ends and the count when long."""
    v = [float(x) for x in np.asarray(values).ravel()]
    if len(v) <= _SHORT_VECTOR:
        return repr(v)
    ends = ", ".join(f"{x:.6g}" for x in v[:3]) + ", ..., " + ", ".join(
        f"{x:.6g}" for x in v[-2:])
    return f"[{ends}] ({len(v)} values)"


class PIModel(Immutable, ABC):
    """Base of every family: weights, offset, input range, initial state, units, metadata.

    Subclasses describe their operators through ``_bank_args``, their own parameters
    through ``_own_params`` and their JSON keys through ``_own_dict``/``_own_from_dict``.
    Build a model through a family's class (:class:`ClassicalPI`, :class:`MultislopePI`,
    :class:`PiecewiseLinearPI`) or :meth:`from_dict`.

    Parameters
    ----------
    weights : array_like
        Weight w_k of each operator (µm per V of operator output).
    offset : float, default 0
        Output offset c (µm).
    input_range : (float, float), optional
        The inputs the model accepts, [min, max] (V); default (0, 150).
    initial_state : array_like, optional
        The operator outputs before the first sample (default: zeros).
    units : dict, optional
        Names of the units (default: {"input": "V", "output": "um"}).
    metadata : dict, optional
        Free-form notes carried with the model and its file (JSON types).
    creep : pihyst.model.Creep or dict, optional
        Creep lags after the hysteresis (docs/theory/creep.md); None: rate independent.
    delay : int, default 0
        Input dead time in samples.
    sample_period : float, optional
        The sample period (s) the delay was identified at.

    Raises
    ------
    InvalidModelError
        If a parameter is not valid (the message names it).

    Examples
    --------
    >>> PIModel.from_dict({"family": "classical", "thresholds": [0], "weights": [1]})
    ClassicalPI(thresholds=[0.0], weights=[1.0])
    """

    family: ClassVar[str | None] = None
    _registry: ClassVar[dict[str, type["PIModel"]]] = {}
    # set once, in __init__ (read-only arrays and mappings)
    weights: NDArray[np.float64]
    offset: float
    input_range: tuple[float, float]
    initial_state: NDArray[np.float64]
    units: Mapping[str, str]
    metadata: Mapping[str, Any]
    creep: Creep | None
    delay: int
    sample_period: float | None
    _bank: _core.Bank

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.family is not None:
            PIModel._registry[cls.family] = cls

    def __init__(self, weights: ArrayLike, *, offset: float = 0.0,
                 input_range: tuple[float, float] | None = None,
                 initial_state: ArrayLike | None = None, units: Mapping[str, str] | None = None,
                 metadata: Mapping[str, Any] | None = None,
                 creep: "Creep | Mapping[str, Any] | None" = None, delay: int = 0,
                 sample_period: float | None = None) -> None:
        set_ = object.__setattr__
        set_(self, "weights", _finite_vector(weights, "weights"))
        if self.weights.size == 0:
            raise InvalidModelError("a model needs at least one operator (weights is empty)")
        set_(self, "offset", _finite_number(offset, "offset"))
        try:
            if isinstance(input_range, (str, bytes, dict)):
                raise TypeError
            lo, hi = DEFAULT_INPUT_RANGE if input_range is None else input_range
        except (TypeError, ValueError):
            raise InvalidModelError(f"input_range must be [min, max], got "
                                    f"{input_range!r:.60}") from None
        lo, hi = _finite_number(lo, "input_range[0]"), _finite_number(hi, "input_range[1]")
        if not lo < hi:
            raise InvalidModelError(f"input_range must be [min, max] with min < max, got "
                                    f"{[lo, hi]}")
        if not np.isfinite(hi - lo):
            raise InvalidModelError(f"input_range {[lo, hi]} is too wide: its span overflows")
        set_(self, "input_range", (lo, hi))
        set_(self, "initial_state",
             frozen_array(np.zeros(self.weights.size)) if initial_state is None else
             _finite_vector(initial_state, "initial_state", self.weights.size))
        set_(self, "units", checked_units(units))
        set_(self, "metadata", checked_metadata(metadata))
        set_(self, "_bank", self._new_bank(self.initial_state))
        # creep lags (docs/theory/creep.md): None for a rate-independent model
        set_(self, "creep", None if creep is None else Creep.from_dict(creep))
        # input dead time in samples, at the sample period (s) it was identified at
        set_(self, "delay", checked_delay(delay))
        set_(self, "sample_period", checked_sample_period(sample_period))
        self._check_output_bound()

    def _check_output_bound(self):
        """InvalidModelError if an output could overflow: the envelopes are monotone, so
        every operator output lies between its envelopes' values at the ends of the input
        range (or its initial state), and |y| <= |offset| + sum_k |w_k| max|f_k|."""
        with np.errstate(over="ignore", invalid="ignore"):
            ends = [np.abs(np.asarray(e, dtype=float))
                    for u in self.input_range for e in self._bank.envelopes(u)]
            reach = np.max(np.vstack(ends + [np.abs(self.initial_state)]), axis=0)
            bound = abs(self.offset) + float(np.sum(np.abs(self.weights) * reach))
        if not np.isfinite(bound):
            raise InvalidModelError("the model's output would overflow on its input range "
                                    "(weights, thresholds, shape or input range too large "
                                    "for floating point)")

    @property
    def n_operators(self) -> int:
        """The number of operators K."""
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
        return checked_input(u, self.input_range)

    def _state_or_initial(self, initial_state):
        if initial_state is None:
            return self.initial_state
        return _finite_vector(initial_state, "initial_state", self.n_operators)

    def simulate(self, u: ArrayLike, *, initial_state: ArrayLike | None = None,
                 t: ArrayLike | None = None, creep_state: ArrayLike | None = None,
                 pending_input: ArrayLike | None = None,
                 t_previous: float | None = None) -> Response:
        """Run the model over the input ``u`` from ``initial_state`` (default: the
        model's own).

        Returns a :class:`Response` with the final operator state, from which a
        following chunk continues exactly.

        A model with :attr:`creep` also uses the sample times ``t`` (s; default: every
        ``creep.dt``; the first sample comes ``creep.dt`` after the initial state, or at
        ``t[0] - t_previous`` when the previous sample's time is given) and
        the lag state ``creep_state`` (default: settled at the initial output); the
        response then carries ``final_creep_state``. Without creep ``t`` is ignored,
        except to check the sample period of a delayed model.

        A model with a :attr:`delay` of d samples runs on the input delayed by d:
        y[k] = P[u](k - d), the first d outputs those of the initial state at
        ``pending_input`` (the d inputs before ``u``; default u[0] held). The response's
        ``pending_input`` continues a following chunk. Sample times ``t`` at another
        period than the model's ``sample_period`` convert the delay when exact, else
        InvalidArgumentError (:meth:`delay_at`).

        Parameters
        ----------
        u : array_like
            Input samples (V), each inside :attr:`input_range`.
        initial_state : array_like, optional
            Operator state before ``u`` (default: the model's ``initial_state``).
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
        Response
            Input, output, final state (and final creep state, pending input).

        Raises
        ------
        InputRangeError
            If an input sample is outside :attr:`input_range` (or not finite).
        InvalidArgumentError
            If an argument is malformed (not numbers, wrong length or period).

        Examples
        --------
        >>> m = ClassicalPI([0, 10], [1.0, 0.5])
        >>> first = m.simulate([0.0, 20.0])
        >>> m.simulate([15.0], initial_state=first.final_state).output.tolist()
        [20.0]
        """
        def hysteresis(state, run):
            bank = self._new_bank(state)
            return bank.run(run), bank.state

        return simulated(self, u, self._state_or_initial(initial_state), hysteresis, t=t,
                         creep_state=creep_state, pending_input=pending_input,
                         t_previous=t_previous)

    def predict(self, u: ArrayLike, *, initial_state: ArrayLike | None = None,
                t: ArrayLike | None = None, creep_state: ArrayLike | None = None,
                pending_input: ArrayLike | None = None,
                t_previous: float | None = None) -> NDArray[np.float64]:
        """Displacements for the voltages ``u``: the output of :meth:`simulate`.

        Parameters
        ----------
        u : array_like
            Input samples (V), each inside :attr:`input_range`.
        initial_state : array_like, optional
            Operator state before ``u`` (default: the model's ``initial_state``).
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
            If an argument is malformed.

        Examples
        --------
        >>> ClassicalPI([0, 10], [1.0, 0.5]).predict([0.0, 20.0, 15.0]).tolist()
        [0.0, 25.0, 20.0]
        """
        return self.simulate(u, initial_state=initial_state, t=t, creep_state=creep_state,
                             pending_input=pending_input, t_previous=t_previous).output

    def delay_at(self, sample_period: float | None = None, *,
                 t: ArrayLike | None = None) -> int:
        """The delay in samples at ``sample_period`` (s) or at the uniform sample times
        ``t``: :attr:`delay` when either period is unknown, d T / period when that is a
        whole number (docs/theory/identification.md).

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
        >>> m = ClassicalPI([0], [1.0], delay=2, sample_period=0.01)
        >>> m.delay_at(0.005), m.delay_at()
        (4, 2)
        """
        return delay_at(self.delay, self.sample_period, sample_period, t)

    def hysteresis_output(self, state: ArrayLike) -> float:
        """offset + sum_k w_k f_k for an operator state: the settled displacement.

        Parameters
        ----------
        state : array_like
            Operator outputs f_k, one per operator.

        Returns
        -------
        float
            The model's output at that state, before creep (µm).

        Examples
        --------
        >>> ClassicalPI([0, 10], [1.0, 0.5], offset=1.0).hysteresis_output([2.0, 4.0])
        5.0
        """
        return self.offset + float(self.weights @ np.asarray(state, dtype=np.float64))

    def _lags(self, state, creep_state):
        """The C creep lags from ``creep_state`` (None: settled at the output of the
        operator state ``state``)."""
        if creep_state is None:
            creep_state = np.full(self.creep.n_lags, self.hysteresis_output(state))
        else:
            creep_state = _finite_vector(creep_state, "creep_state", self.creep.n_lags)
        return self.creep.lags(creep_state)

    def operators(self, u: ArrayLike, *,
                  initial_state: ArrayLike | None = None) -> NDArray[np.float64]:
        """The N x K operator matrix Phi[t, k] = f_k[t] (paper eq. 8), of the input as
        given (a delay is not applied: Phi pairs with the output d samples later).

        Parameters
        ----------
        u : array_like
            Input samples (V), each inside :attr:`input_range`.
        initial_state : array_like, optional
            Operator state before ``u`` (default: the model's ``initial_state``).

        Returns
        -------
        numpy.ndarray
            The N x K operator outputs.

        Raises
        ------
        InputRangeError
            If an input sample is outside :attr:`input_range` (or not finite).

        Examples
        --------
        >>> ClassicalPI([0, 10], [1.0, 0.5]).operators([0.0, 20.0]).tolist()
        [[0.0, 0.0], [20.0, 10.0]]
        """
        u = self._checked_input(u)
        return self._new_bank(self._state_or_initial(initial_state)).operators(u)

    def envelopes(self, u: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(R_k(u), F_k(u)) of every operator at one input value.

        Parameters
        ----------
        u : float
            One input value (V).

        Returns
        -------
        rising, falling : numpy.ndarray
            The rising and falling envelope of each operator at ``u``.

        Raises
        ------
        InvalidArgumentError
            If ``u`` is not a number.

        Examples
        --------
        >>> r, f = ClassicalPI([0, 10], [1.0, 0.5]).envelopes(20.0)
        >>> r.tolist(), f.tolist()
        ([20.0, 10.0], [20.0, 30.0])
        """
        try:
            if isinstance(u, (str, bytes, bool, np.bool_)):      # float() would take "3"
                raise TypeError
            value = float(u)
        except (TypeError, ValueError):
            raise InvalidArgumentError(f"u must be one input value (a number), got "
                                       f"{u!r:.40}") from None
        return self._bank.envelopes(value)

    def stepper(self, initial_state: ArrayLike | None = None, *,
                creep_state: ArrayLike | None = None, pending_input: ArrayLike | None = None,
                sample_period: float | None = None) -> "Stepper":
        """A :class:`Stepper`: this model run sample by sample from ``initial_state``
        (default: the model's own); a delayed model's stepper holds a FIFO of its d
        ``pending_input`` (default: the first input, d times), d converted to
        ``sample_period`` (s) if given.

        Parameters
        ----------
        initial_state : array_like, optional
            Operator state before the first step (default: the model's own).
        creep_state : array_like, optional
            Creep lag states before the first step (default: settled).
        pending_input : array_like, optional
            With a delay of d samples: the d inputs before the first step.
        sample_period : float, optional
            The period (s) the stepper is stepped at, to convert the delay.

        Returns
        -------
        Stepper
            A stepper owning its own running state.

        Examples
        --------
        >>> s = ClassicalPI([0, 10], [1.0, 0.5]).stepper()
        >>> s.step(20.0)
        25.0
        """
        return Stepper(self, initial_state, creep_state, pending_input=pending_input,
                       sample_period=sample_period)

    # ---------------------------------------------------------------- values
    def _params(self):
        """Every constructor argument, by name."""
        return {**self._own_params(), "weights": self.weights, "offset": self.offset,
                "input_range": self.input_range, "initial_state": self.initial_state,
                "units": dict(self.units), "metadata": dict(self.metadata),
                "creep": self.creep, "delay": self.delay,
                "sample_period": self.sample_period}

    def _own_params(self):
        return {}

    def replace(self: "_Model", **changes: Any) -> "_Model":
        """A copy with some constructor arguments changed (e.g. weights, offset).

        Parameters
        ----------
        **changes
            Constructor arguments by name, and their new values.

        Returns
        -------
        PIModel
            A model of the same class with those arguments changed.

        Raises
        ------
        InvalidModelError
            If a name is not a constructor argument or a value is not valid.

        Examples
        --------
        >>> m = ClassicalPI([0, 10], [1.0, 0.5])
        >>> m.replace(offset=2.0)
        ClassicalPI(thresholds=[0.0, 10.0], weights=[1.0, 0.5], offset=2)
        """
        params = self._params()
        unknown = sorted(set(changes) - set(params))
        if unknown:
            raise InvalidModelError(f"{type(self).__name__} has no parameter {unknown[0]!r}")
        params.update(changes)
        return type(self)(**params)

    def _key(self):
        """What identifies the model's behaviour (metadata is not part of it)."""
        out = [self.family]
        for name, value in self._params().items():
            if name == "metadata":
                continue
            if isinstance(value, (list, _Polylines)):  # polylines
                value = tuple((tuple(x), tuple(y)) for x, y in value)
            elif isinstance(value, np.ndarray):
                value = tuple(value.tolist())
            elif isinstance(value, dict):
                value = tuple(sorted(value.items()))
            elif isinstance(value, Creep):
                value = value._key()
            out.append((name, value))
        return tuple(out)

    def __eq__(self, other):
        """Equal models have the same family and parameters (metadata aside)."""
        if not isinstance(other, PIModel):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self):
        return hash(self._key())

    def __repr__(self):
        defaults = type(self)._defaults(self)
        parts = []
        for name, value in self._params().items():
            if name == "metadata":
                continue
            if name in defaults and _same(value, defaults[name]):
                continue
            if isinstance(value, (list, _Polylines)):
                parts.append(f"{name}=<{len(value)} polylines>")
            elif isinstance(value, np.ndarray):
                parts.append(f"{name}={_short(value)}")
            elif isinstance(value, float):
                parts.append(f"{name}={value:.6g}")
            else:
                parts.append(f"{name}={value!r}")
        return f"{type(self).__name__}({', '.join(parts)})"

    @staticmethod
    def _defaults(model):
        return {"offset": 0.0, "input_range": DEFAULT_INPUT_RANGE,
                "initial_state": np.zeros(model.n_operators), "units": dict(DEFAULT_UNITS),
                "creep": None, "delay": 0, "sample_period": None}

    # ---------------------------------------------------------------- persistence
    def to_dict(self) -> dict[str, Any]:
        """The model as a JSON-ready dict (the schema of docs/interfaces.md).

        Returns
        -------
        dict
            Plain JSON types only; :meth:`from_dict` reads it back.

        Examples
        --------
        >>> ClassicalPI([0], [1.0]).to_dict()["family"]
        'classical'
        """
        d = {"schema_version": SCHEMA_VERSION, "family": self.family, **self._own_dict(),
             "weights": self.weights.tolist(), "offset": self.offset,
             "input_range": list(self.input_range),
             "initial_state": self.initial_state.tolist(), "units": dict(self.units)}
        if self.creep is not None:
            d["creep"] = self.creep.to_dict()
        d.update(delay_dict(self))
        if self.metadata:
            d["metadata"] = metadata_json(self.metadata)
        return d

    def _own_dict(self):
        return {}

    _COMMON_KEYS = frozenset({"family", "weights", "offset", "input_range", "initial_state",
                              "units", "metadata", "schema_version", "creep",
                              *DELAY_KEYS})
    _OWN_KEYS: ClassVar[frozenset[str]] = frozenset()
    _REQUIRED_KEYS: ClassVar[tuple[str, ...]] = ("weights",)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], source: str = "model") -> Any:
        """A model from a dict of the JSON schema; errors name ``source`` and the key.

        Called on :class:`PIModel` it picks the class by ``d["family"]``; called on a
        family's class it accepts that family only.

        Parameters
        ----------
        d : dict
            The model in the JSON schema (docs/interfaces.md).
        source : str, default "model"
            Where ``d`` comes from, for the error messages (e.g. a file name).

        Returns
        -------
        PIModel or BoucWenModel
            The model ``d`` describes.

        Raises
        ------
        InvalidModelError
            If ``d`` does not describe a valid model (the message names the key).

        Examples
        --------
        >>> ClassicalPI.from_dict({"family": "classical", "thresholds": [0, 5],
        ...                        "weights": [1, 0.5]})
        ClassicalPI(thresholds=[0.0, 5.0], weights=[1.0, 0.5])
        """
        if not isinstance(d, dict):
            raise InvalidModelError(f"{source}: a model must be a JSON object, got "
                                    f"{type(d).__name__}")
        family = d.get("family")
        if cls is PIModel and isinstance(family, str) and family in OTHER_FAMILIES:
            # not PI models: their own schema
            return OTHER_FAMILIES[family].from_dict(d, source)
        if not isinstance(family, str) or family not in PIModel._registry:
            known = sorted([*PIModel._registry, *OTHER_FAMILIES])
            raise InvalidModelError(f"{source}: key 'family' must be one of "
                                    f"{', '.join(known)}; got {family!r:.40}")
        target = PIModel._registry[family]
        if cls is not PIModel and target is not cls:
            raise InvalidModelError(f"{source}: family {family!r} is not {cls.family!r}")
        allowed = cls._COMMON_KEYS | target._OWN_KEYS
        for key in target._REQUIRED_KEYS:
            if key not in d:
                raise InvalidModelError(f"{source}: missing required key {key!r}")
        unknown = sorted(set(d) - allowed)
        if unknown:
            raise InvalidModelError(f"{source}: unknown key {unknown[0]!r} for family "
                                    f"{family!r} (allowed: {', '.join(sorted(allowed))})")
        version = d.get("schema_version", SCHEMA_VERSION)
        if isinstance(version, bool) or version != SCHEMA_VERSION:
            raise InvalidModelError(f"{source}: schema_version {version!r:.20} is not "
                                    f"{SCHEMA_VERSION} (written by another pihyst version)")
        common = {k: d[k] for k in ("weights", "offset", "input_range", "initial_state",
                                    "units", "metadata", "creep") if k in d}
        try:
            common.update(delay_from_dict(d))
            return target(**target._own_from_dict(d), **common)
        except InvalidModelError as err:
            raise InvalidModelError(f"{source}: {err}") from None
        except (TypeError, ValueError, OverflowError, ZeroDivisionError) as err:
            raise InvalidModelError(f"{source}: {err}") from None

    @classmethod
    def _own_from_dict(cls, d):
        return {}

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
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "model.json"
        >>> ClassicalPI([0], [1.0]).save(path)
        >>> PIModel.from_dict(__import__("json").loads(path.read_text())).weights.tolist()
        [1.0]
        """
        write_atomically(path, json.dumps(self.to_dict(), indent=2) + "\n")


def delay_dict(model):
    """The delay's JSON keys of ``model``: none for no delay and no known period."""
    d = {}
    if model.delay:
        d["delay_samples"] = model.delay
    if model.sample_period is not None:
        d["sample_period_s"] = model.sample_period
    return d


def delay_from_dict(d):
    """Constructor arguments from the delay's JSON keys."""
    out = {}
    if "delay_samples" in d:
        out["delay"] = checked_delay(d["delay_samples"], "delay_samples")
    if "sample_period_s" in d:
        out["sample_period"] = checked_sample_period(d["sample_period_s"], "sample_period_s")
    return out


def _same(a, b):
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a, dtype=float), np.asarray(b, dtype=float))
    return a == b


class Stepper:
    """A model run sample by sample: owns the running operator state, so the model itself
    never changes. ``step(u)`` advances by one input sample and returns y; ``state`` is a
    copy of the operator state; ``reset(state=None)`` goes back to a state (default: the
    initial state it was made with).

    Parameters
    ----------
    model : PIModel
        The model to run.
    initial_state : array_like, optional
        Operator state before the first step (default: the model's own).
    creep_state : array_like, optional
        With creep: the lag states before the first step (default: settled).
    pending_input : array_like, optional
        With a delay of d samples: the d inputs before the first step (default: the
        first input, d times).
    sample_period : float, optional
        The period (s) it is stepped at, to convert the model's delay.

    Examples
    --------
    >>> m = ClassicalPI([0, 10], [1.0, 0.5])
    >>> s = m.stepper()
    >>> [round(s.step(u), 3) for u in (0.0, 20.0, 15.0)]
    [0.0, 25.0, 20.0]
    """

    def __init__(self, model: PIModel, initial_state: ArrayLike | None = None,
                 creep_state: ArrayLike | None = None, *,
                 pending_input: ArrayLike | None = None,
                 sample_period: float | None = None) -> None:
        self.model = model
        self._initial = model._state_or_initial(initial_state)
        self._bank = model._new_bank(self._initial)
        # with creep: the lags, settled at the initial output unless given
        self._lags = None if model.creep is None else model._lags(self._initial, creep_state)
        #: the input dead time in samples (a FIFO of that many inputs)
        self.delay = model.delay_at(sample_period)
        if self.delay and pending_input is not None:
            pending_input = model._checked_input(pending_input)
        self._line = DelayLine(self.delay, pending_input)

    @property
    def state(self):
        """The running operator state (a copy)."""
        return self._bank.state

    @property
    def creep_state(self):
        """The creep lag states z_i (a copy; None for a model without creep)."""
        return None if self._lags is None else self._lags.state

    @property
    def pending_input(self):
        """The inputs in the delay FIFO, oldest first (None before the first step of a
        delayed model without given ``pending_input``; empty without a delay)."""
        return self._line.contents if self.delay else np.empty(0)

    def reset(self, state: ArrayLike | None = None,
              creep_state: ArrayLike | None = None) -> None:
        """Set the running state to ``state`` (default: the initial state); with
        creep, the lags to ``creep_state`` (default: settled at that state's output);
        the delay FIFO back to its start.

        Parameters
        ----------
        state : array_like, optional
            The operator state to go back to (default: the initial state).
        creep_state : array_like, optional
            The creep lag states (default: settled at that state's output).

        Raises
        ------
        InvalidModelError
            If ``state`` is not one finite number per operator.

        Examples
        --------
        >>> s = ClassicalPI([0], [1.0]).stepper()
        >>> s.step(5.0)
        5.0
        >>> s.reset(); s.state.tolist()
        [0.0]
        """
        self._bank.state = self._initial if state is None else \
            self.model._state_or_initial(state)
        if self._lags is not None:
            self._lags = self.model._lags(self._bank.state, creep_state)
        self._line.reset()

    def step(self, u: float, dt: float | None = None) -> float:
        """One sample: advance the running state by the input ``u`` (with a delay of d
        samples, by the input of d steps ago), return y.

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
        >>> s = ClassicalPI([0, 10], [1.0, 0.5]).stepper()
        >>> s.step(20.0), s.step(15.0)
        (25.0, 20.0)
        """
        try:
            u = float(u)
        except (TypeError, ValueError, OverflowError):
            raise InvalidArgumentError(f"input must be a number, got {u!r:.40}") from None
        lo, hi = self.model.input_range
        if not lo <= u <= hi:
            raise InputRangeError(0, u, self.model.input_range)
        h = self._bank.step(self._line.push(u))
        if self._lags is None:
            return h
        if dt is not None:
            try:
                dt = float(dt)
            except (TypeError, ValueError):
                raise InvalidArgumentError(f"dt must be a number of seconds, got "
                                           f"{dt!r:.40}") from None
            if not (np.isfinite(dt) and dt >= 0):
                raise InvalidArgumentError(f"dt must be a finite interval >= 0 s, got {dt}")
        return self._lags.step(h, dt)


class ClassicalPI(PIModel):
    """Classical Prandtl-Ishlinskii model (paper eq. 1-3).

    Parameters
    ----------
    thresholds : array_like
        Threshold r_k of each operator (V from the bottom of the input range), >= 0
        and strictly increasing.
    weights : array_like
        Weight w_k of each operator (µm/V).
    offset : float, default 0
        Output offset c (µm).
    input_range : (float, float), optional
        The inputs the model accepts, [min, max] (V); default (0, 150).
    initial_state : array_like, optional
        The operator outputs before the first sample (default: zeros).
    units : dict, optional
        Names of the units (default: {"input": "V", "output": "um"}).
    metadata : dict, optional
        Free-form notes carried with the model and its file (JSON types).
    creep : pihyst.model.Creep or dict, optional
        Creep lags after the hysteresis (docs/theory/creep.md); None: rate independent.
    delay : int, default 0
        Input dead time in samples.
    sample_period : float, optional
        The sample period (s) the delay was identified at.

    Raises
    ------
    InvalidModelError
        If a parameter is not valid (the message names it).

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

    _OWN_KEYS = frozenset({"thresholds"})
    _REQUIRED_KEYS = ("thresholds", "weights")
    thresholds: NDArray[np.float64]

    def __init__(self, thresholds: ArrayLike, weights: ArrayLike, *, offset: float = 0.0,
                 input_range: tuple[float, float] | None = None,
                 initial_state: ArrayLike | None = None, units: Mapping[str, str] | None = None,
                 metadata: Mapping[str, Any] | None = None,
                 creep: "Creep | Mapping[str, Any] | None" = None, delay: int = 0,
                 sample_period: float | None = None) -> None:
        object.__setattr__(self, "thresholds", _finite_vector(thresholds, "thresholds"))
        super().__init__(weights, offset=offset, input_range=input_range,
                         initial_state=initial_state, units=units, metadata=metadata,
                         creep=creep, delay=delay, sample_period=sample_period)

    def _bank_args(self):
        _check_thresholds(self.thresholds, self.weights.size)
        return {"thresholds": self.thresholds}

    def _own_params(self):
        return {"thresholds": self.thresholds}

    def _own_dict(self):
        return {"thresholds": self.thresholds.tolist()}

    @classmethod
    def _own_from_dict(cls, d):
        return {"thresholds": d["thresholds"]}

    def inverse(self) -> "ClassicalPI":
        """The analytic inverse, a :class:`ClassicalPI` from displacement to voltage
        (docs/theory/inverse.md; see :func:`pihyst.inverse.classical_inverse`).

        Returns
        -------
        ClassicalPI
            The inverse model, whose input is the displacement (µm).

        Raises
        ------
        InvalidModelError
            If the model cannot be inverted analytically (see ``classical_inverse``).

        Examples
        --------
        >>> m = ClassicalPI([0, 10], [1.0, 0.5])
        >>> round(float(m.inverse().predict([0.0, 25.0])[-1]), 6)
        20.0
        """
        return classical_inverse(self)


class MultislopePI(PIModel):
    """Multislope PI model of Xu et al. (2020), eq. 6, with shape (U, a, b, h).

    R(u) = max(a(u - r), b u - r - (b - 1)U),  F(u) = min(b u, a u + (1 - a)U - (1 - a h) r).
    Thresholds must not exceed (1 - a)U / (1 - a h) (50 V for the paper's shape).

    Parameters
    ----------
    thresholds : array_like
        Threshold r_k of each operator (V), >= 0, strictly increasing, at most
        :attr:`max_threshold`.
    weights : array_like
        Weight w_k of each operator.
    U, a, b, h : float
        The shape: top of the drive (V), slopes 0 < a < b, hold ratio 0 <= h <= 1 with
        a h < 1 (default: the paper's, 150, 0.8, 1.2, 0.5).
    offset : float, default 0
        Output offset c (µm).
    input_range : (float, float), optional
        The inputs the model accepts, [min, max] (V); default (0, U).
    initial_state : array_like, optional
        The operator outputs before the first sample (default: zeros).
    units : dict, optional
        Names of the units (default: {"input": "V", "output": "um"}).
    metadata : dict, optional
        Free-form notes carried with the model and its file (JSON types).
    creep : pihyst.model.Creep or dict, optional
        Creep lags after the hysteresis (docs/theory/creep.md); None: rate independent.
    delay : int, default 0
        Input dead time in samples.
    sample_period : float, optional
        The sample period (s) the delay was identified at.

    Raises
    ------
    InvalidModelError
        If a parameter is not valid (the message names it).

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

    _OWN_KEYS = frozenset({"thresholds", "U", "a", "b", "h"})
    _REQUIRED_KEYS = ("thresholds", "weights")
    thresholds: NDArray[np.float64]
    U: float
    a: float
    b: float
    h: float

    def __init__(self, thresholds: ArrayLike, weights: ArrayLike, *,
                 U: float = PAPER_SHAPE["U"], a: float = PAPER_SHAPE["a"],
                 b: float = PAPER_SHAPE["b"], h: float = PAPER_SHAPE["h"],
                 input_range: tuple[float, float] | None = None, offset: float = 0.0,
                 initial_state: ArrayLike | None = None, units: Mapping[str, str] | None = None,
                 metadata: Mapping[str, Any] | None = None,
                 creep: "Creep | Mapping[str, Any] | None" = None, delay: int = 0,
                 sample_period: float | None = None) -> None:
        set_ = object.__setattr__
        set_(self, "thresholds", _finite_vector(thresholds, "thresholds"))
        for name, value in (("U", U), ("a", a), ("b", b), ("h", h)):
            set_(self, name, _finite_number(value, f"multislope shape {name}"))
        # a h < 1 keeps the maximum threshold (1 - a)U/(1 - a h) finite
        if not (self.U > 0 and 0 < self.a < self.b and 0 <= self.h <= 1
                and self.a * self.h < 1):
            raise InvalidModelError(f"multislope shape needs U > 0, 0 < a < b, 0 <= h <= 1 "
                                    f"and a h < 1; got U={U:g}, a={a:g}, b={b:g}, h={h:g}")
        if not np.isfinite(self.b * self.U):
            raise InvalidModelError(f"multislope shape U={self.U:g}, b={self.b:g}: b U "
                                    f"overflows floating point")
        if input_range is None:
            input_range = (0.0, self.U)
        super().__init__(weights, offset=offset, input_range=input_range,
                         initial_state=initial_state, units=units, metadata=metadata,
                         creep=creep, delay=delay, sample_period=sample_period)

    @property
    def max_threshold(self) -> float:
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

    def _own_params(self):
        return {"thresholds": self.thresholds, "U": self.U, "a": self.a, "b": self.b,
                "h": self.h}

    @staticmethod
    def _defaults(model):
        return {**PIModel._defaults(model), **PAPER_SHAPE, "input_range": (0.0, model.U)}

    def _own_dict(self):
        return {"thresholds": self.thresholds.tolist(), "U": self.U, "a": self.a,
                "b": self.b, "h": self.h}

    @classmethod
    def _own_from_dict(cls, d):
        return {"thresholds": d["thresholds"],
                **{k: d[k] for k in ("U", "a", "b", "h") if k in d}}


class PiecewiseLinearPI(PIModel):
    """PI model whose operators have user-given polyline envelopes.

    ``rising[k]`` and ``falling[k]`` are (x, y) breakpoint pairs of operator k, x strictly
    increasing and y non-decreasing; beyond its ends a polyline continues with the slope
    of its end segment. R_k <= F_k must hold on the input range.

    Parameters
    ----------
    rising : sequence of (array_like, array_like)
        The rising envelope R_k of each operator: (x, y) breakpoints.
    falling : sequence of (array_like, array_like)
        The falling envelope F_k of each operator: (x, y) breakpoints.
    weights : array_like
        Weight w_k of each operator.
    offset : float, default 0
        Output offset c (µm).
    input_range : (float, float), optional
        The inputs the model accepts, [min, max] (V); default (0, 150).
    initial_state : array_like, optional
        The operator outputs before the first sample (default: zeros).
    units : dict, optional
        Names of the units (default: {"input": "V", "output": "um"}).
    metadata : dict, optional
        Free-form notes carried with the model and its file (JSON types).
    creep : pihyst.model.Creep or dict, optional
        Creep lags after the hysteresis (docs/theory/creep.md); None: rate independent.
    delay : int, default 0
        Input dead time in samples.
    sample_period : float, optional
        The sample period (s) the delay was identified at.

    Raises
    ------
    InvalidModelError
        If a parameter is not valid (the message names it).

    Examples
    --------
    >>> m = PiecewiseLinearPI(rising=[([0, 1], [-10, -9])], falling=[([0, 1], [10, 11])],
    ...                       weights=[1.0])
    >>> m.predict([0.0, 20.0, 15.0]).tolist()
    [0.0, 10.0, 10.0]
    """

    family = "pwl"

    _OWN_KEYS = frozenset({"rising", "falling"})
    _REQUIRED_KEYS = ("rising", "falling", "weights")
    rising: tuple[tuple[NDArray[np.float64], NDArray[np.float64]], ...]
    falling: tuple[tuple[NDArray[np.float64], NDArray[np.float64]], ...]

    def __init__(self, rising: Sequence[tuple[ArrayLike, ArrayLike]],
                 falling: Sequence[tuple[ArrayLike, ArrayLike]], weights: ArrayLike, *,
                 offset: float = 0.0,
                 input_range: tuple[float, float] | None = None,
                 initial_state: ArrayLike | None = None, units: Mapping[str, str] | None = None,
                 metadata: Mapping[str, Any] | None = None,
                 creep: "Creep | Mapping[str, Any] | None" = None, delay: int = 0,
                 sample_period: float | None = None) -> None:
        object.__setattr__(self, "rising", _polylines(rising, "rising"))
        object.__setattr__(self, "falling", _polylines(falling, "falling"))
        super().__init__(weights, offset=offset, input_range=input_range,
                         initial_state=initial_state, units=units, metadata=metadata,
                         creep=creep, delay=delay, sample_period=sample_period)

    def _bank_args(self):
        k = self.weights.size
        if len(self.rising) != k or len(self.falling) != k:
            raise InvalidModelError(f"pwl model needs one rising and one falling polyline per "
                                    f"weight: {len(self.rising)} rising, {len(self.falling)} "
                                    f"falling, {k} weights")
        return {"thresholds": None, "rising": self.rising, "falling": self.falling}

    def _own_params(self):
        return {"rising": self.rising, "falling": self.falling}

    def _own_dict(self):
        return {"rising": [{"x": x.tolist(), "y": y.tolist()} for x, y in self.rising],
                "falling": [{"x": x.tolist(), "y": y.tolist()} for x, y in self.falling]}

    @classmethod
    def _own_from_dict(cls, d):
        return {name: [_points(p, f"{name}[{i}]") for i, p in enumerate(_list(d[name], name))]
                for name in ("rising", "falling")}


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


def _list(value, name):
    if not isinstance(value, list):
        raise InvalidModelError(f"{name} must be a list of polylines, got "
                                f"{type(value).__name__}")
    return value


def _points(p, name):
    if not isinstance(p, dict) or "x" not in p or "y" not in p:
        raise InvalidModelError(f"{name} must be an object with lists 'x' and 'y'")
    return (p["x"], p["y"])


class _Polylines(tuple):
    """Polylines `_polylines` has checked: a tuple of read-only (x, y) arrays, passed on
    unchecked when a model is copied (`replace`), as the fit does for every candidate."""


def _polylines(polylines, name):
    if isinstance(polylines, _Polylines):
        return polylines
    try:
        items = list(polylines)
    except TypeError:
        raise InvalidModelError(f"{name} must be a list of (x, y) polylines") from None
    return _uniform(items) or _Polylines(_polyline(p, f"{name}[{k}]")
                                         for k, p in enumerate(items))


def _uniform(items):
    """The checks of :func:`_polyline` on all polylines at once when they are float
    arrays of one length (as the fit's kernel bases are): a KP basis of 135 kernels in
    0.2 ms instead of 10. None if they are not, or fail a check (then each is checked
    alone, for the error that names it)."""
    pairs = [p for p in items if isinstance(p, tuple) and len(p) == 2]
    arrays = [a for p in pairs for a in p
              if isinstance(a, np.ndarray) and a.dtype == np.float64 and a.ndim == 1]
    if not items or len(arrays) != 2 * len(items) or len({a.size for a in arrays}) != 1 \
            or arrays[0].size == 0:
        return None
    x, y = np.array(arrays[0::2]), np.array(arrays[1::2])
    if not (np.isfinite(x).all() and np.isfinite(y).all()
            and (np.diff(x, axis=1) > 0).all() and (np.diff(y, axis=1) >= 0).all()):
        return None
    x.flags.writeable = y.flags.writeable = False
    return _Polylines(zip(x, y))


def _polyline(points, name):
    try:
        x, y = points
    except (TypeError, ValueError):
        raise InvalidModelError(f"{name} must be a pair (x, y) of breakpoint lists") from None
    x = _finite_vector(x, f"{name} x")
    y = _finite_vector(y, f"{name} y", x.size)
    if x.size == 0:
        raise InvalidModelError(f"{name} has no breakpoints")
    if np.any(np.diff(x) <= 0):
        raise InvalidModelError(f"{name}: breakpoints must be strictly increasing")
    if np.any(np.diff(y) < 0):
        raise InvalidModelError(f"{name}: envelope values must be non-decreasing")
    return (x, y)
