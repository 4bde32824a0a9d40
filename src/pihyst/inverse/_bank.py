"""Many compensators run together: one vector of desired displacements per tick
(deformable mirrors, multi-axis stages). Each channel is a :class:`Compensator` of its
own (model, limits, slew limit, state); the bank runs them all in one call of the C core
(pihyst_bank_compensate), with bit for bit the voltages of the channels run one by
one, and every voltage inside its channel's limits and slew limit.

With ``fast=True`` the bank runs from a structure-of-arrays copy of the states
(pihyst_compbank, docs/c-core.md): classical channels (r_0 = 0, w_0 > 0) step their
model's exact inverse, itself a classical PI model, vectorized across channels, and fall
back to their compensator on every tick that would leave a limit or the slew limit; the
voltages and displacements then equal those of separate compensators to rounding (about
1e-13 of the range) instead of bit for bit, the flags are the same, and the limits hold
exactly as before."""

from collections.abc import Iterable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst import _core
from pihyst.exceptions import InvalidArgumentError
from pihyst.inverse._compensator import Compensator
from pihyst.model import PIModel
from pihyst.model._bank import refuse_delayed

#: one value for every channel, or one per channel (None entries: the default)
PerChannel = float | Sequence[float | None] | None


def _per_channel(value, n, name):
    if isinstance(value, (list, tuple, np.ndarray)):
        if len(value) != n:
            raise InvalidArgumentError(f"{name} must be one value or {n} values, got {len(value)}")
        return list(value)
    return [value] * n


class CompensatorBank:
    """N exact compensators stepped together, one desired value per channel per tick.

    Parameters
    ----------
    models : sequence of PIModel
        One model (non-negative weights) per channel, without an input delay (a
        delayed model is refused: each channel would need its own preview).
    u_min, u_max, slew_rate, initial_voltage, initial_state, sample_period
        As for :class:`Compensator` (``slew_rate`` in V/s, ``sample_period`` in s): one
        value for every channel, or a sequence of N (None entries: that channel's
        default).
    fast : bool
        Run classical channels by their analytic inverse (see above): 3-7 times as fast
        at 1000 channels of K = 16, equal to the exact compensator to rounding rather
        than bit for bit.

    Raises
    ------
    InvalidArgumentError
        If a model is delayed or an argument does not have one value per channel.
    InvalidModelError
        If a model cannot be inverted (a negative weight).

    Notes
    -----
    ``channels`` holds the N :class:`Compensator` objects; the bank steps their states,
    so ``channels[i].voltage`` and ``.state`` are current when read through
    ``bank.channels`` (a fast bank writes its state back to them when they are read).
    Reset them through :meth:`reset`: a fast bank does not see a channel reset on its own.

    Examples
    --------
    >>> import numpy as np, pihyst
    >>> from pihyst.inverse import CompensatorBank
    >>> m = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    >>> bank = CompensatorBank([m, m, m], slew_rate=[5e4, None, None], sample_period=1e-4)
    >>> u = bank.step([1.0, 1.0, 50.0])        # 50 um is out of reach
    >>> [round(float(v), 6) for v in u], [int(f) for f in bank.last_flags]
    ([5.0, 6.377551, 150.0], [8, 0, 2])

    A fast bank of classical channels gives the same voltages to rounding:

    >>> c = pihyst.ClassicalPI([0, 10, 30, 60], [0.2, 0.05, 0.04, 0.03])
    >>> fast = CompensatorBank([c] * 5, fast=True)
    >>> exact = CompensatorBank([c] * 5)
    >>> y_d = np.linspace(2.0, 20.0, 5)
    >>> bool(np.allclose(fast.step(y_d), exact.step(y_d), rtol=0, atol=1e-9))
    True
    """

    def __init__(self, models: Iterable[PIModel], *, u_min: PerChannel = None,
                 u_max: PerChannel = None, slew_rate: PerChannel = None,
                 initial_voltage: PerChannel = None,
                 initial_state: Sequence[ArrayLike | None] | None = None,
                 fast: bool = False, sample_period: float | None = None) -> None:
        models = tuple(models)
        refuse_delayed(models)
        n = len(models)
        args = zip(models, _per_channel(u_min, n, "u_min"), _per_channel(u_max, n, "u_max"),
                   _per_channel(slew_rate, n, "slew_rate"),
                   _per_channel(initial_voltage, n, "initial_voltage"),
                   [None] * n if initial_state is None else
                   _per_channel(list(initial_state), n, "initial_state"),
                   _per_channel(sample_period, n, "sample_period"), strict=True)
        self._channels = tuple(
            Compensator(m, u_min=lo, u_max=hi, slew_rate=s, initial_voltage=v, initial_state=f,
                        sample_period=T)
            for m, lo, hi, s, v, f, T in args)
        cores = [c._core for c in self._channels]
        self._array = _core.CompensatorSoA(cores) if fast else _core.CompensatorArray(cores)
        self._stale = False
        self._u = np.empty(n)
        self._y = np.empty(n)
        self._flags = np.zeros(n, dtype=np.uint8)

    def __len__(self):
        return len(self._channels)

    @property
    def fast(self):
        """True if the bank runs classical channels by their analytic inverse."""
        return isinstance(self._array, _core.CompensatorSoA)

    @property
    def n_fast(self):
        """The number of channels on the fast path now (0 for an exact bank)."""
        return self._array.n_fast if self.fast else 0

    @property
    def channels(self):
        """The N :class:`Compensator` objects, brought up to date."""
        if self._stale:
            self._array.sync()
            self._stale = False
        return self._channels

    @property
    def voltages(self):
        """The last voltage of every channel."""
        return np.array([c.voltage for c in self.channels])

    @property
    def displacements(self):
        """The model displacement of every channel at its last voltage."""
        return np.array([c.displacement for c in self.channels])

    @property
    def last_flags(self):
        """Flags of the last tick per channel (0: desired value reached)."""
        return np.array([c.last_flags for c in self.channels], dtype=np.uint8)

    def reset(self) -> None:
        """Every channel back to its initial state and voltage.

        Examples
        --------
        >>> import pihyst
        >>> bank = CompensatorBank([pihyst.ClassicalPI([0], [2.0])])
        >>> _ = bank.step([4.0]); bank.reset(); bank.voltages.tolist()
        [0.0]
        """
        for c in self._channels:
            c.reset()
        if isinstance(self._array, _core.CompensatorSoA):
            self._array.reload()
        self._stale = False

    def step(self, y_desired: ArrayLike) -> NDArray[np.float64]:
        """One tick: the N voltages for N desired displacements (any values).

        Parameters
        ----------
        y_desired : array_like
            One desired displacement per channel (µm), shape (N,).

        Returns
        -------
        numpy.ndarray
            The N voltages; :attr:`last_flags` says which were not reached.

        Raises
        ------
        InvalidArgumentError
            If ``y_desired`` does not have N values.

        Examples
        --------
        >>> import pihyst
        >>> bank = CompensatorBank([pihyst.ClassicalPI([0], [2.0])] * 2)
        >>> bank.step([2.0, 4.0]).tolist()
        [1.0, 2.0]
        """
        y_desired = np.ascontiguousarray(y_desired, dtype=np.float64)
        if y_desired.shape != (len(self),):
            raise InvalidArgumentError(f"y_desired must have {len(self)} values, got shape "
                                       f"{y_desired.shape}")
        self._array.step_into(y_desired, self._u, self._y, self._flags)
        self._stale = self.fast
        return self._u.copy()

    def run(self, y_desired: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                                NDArray[np.uint8]]:
        """T ticks, row t of ``y_desired`` one tick.

        Parameters
        ----------
        y_desired : array_like
            Desired displacements (µm), shape (T, N).

        Returns
        -------
        voltage, displacement, flags : numpy.ndarray
            Each of shape (T, N).

        Raises
        ------
        InvalidArgumentError
            If ``y_desired`` does not have shape (T, N).

        Examples
        --------
        >>> import pihyst
        >>> bank = CompensatorBank([pihyst.ClassicalPI([0], [2.0])])
        >>> u, y, flags = bank.run([[2.0], [400.0]])
        >>> u.tolist(), flags.tolist()
        ([[1.0], [150.0]], [[0], [2]])
        """
        y_desired = np.ascontiguousarray(y_desired, dtype=np.float64)
        if y_desired.ndim != 2 or y_desired.shape[1] != len(self):
            raise InvalidArgumentError(f"y_desired must have shape (T, {len(self)}), got "
                                       f"{y_desired.shape}")
        result = self._array.run(y_desired)
        self._stale = self.fast
        return result

    def __repr__(self):
        fast = f", {self.n_fast} on the fast path" if self.fast else ""
        return f"CompensatorBank({len(self)} channels{fast})"
