"""Many compensators run together: one vector of desired displacements per tick
(deformable mirrors, multi-axis stages). Each channel is a :class:`Compensator` of its
own (model, limits, slew limit, state); the bank runs them all in one call of the C core
(pihyst_bank_compensate), with bit for bit the voltages of the channels run one by
one, and every voltage inside its channel's limits and slew limit."""

import numpy as np

from pihyst import _core
from pihyst.inverse._compensator import Compensator
from pihyst.model._bank import refuse_delayed


def _per_channel(value, n, name):
    if isinstance(value, (list, tuple, np.ndarray)):
        if len(value) != n:
            raise ValueError(f"{name} must be one value or {n} values, got {len(value)}")
        return list(value)
    return [value] * n


class CompensatorBank:
    """N exact compensators stepped together, one desired value per channel per tick.

    Parameters
    ----------
    models : sequence of PIModel
        One model (non-negative weights) per channel, without an input delay (a
        delayed model is refused: each channel would need its own preview).
    u_min, u_max, slew_rate, initial_voltage, initial_state
        As for :class:`Compensator`: one value for every channel, or a sequence of N
        (None entries: that channel's default).

    ``channels`` holds the N :class:`Compensator` objects; the bank steps their states,
    so ``channels[i].voltage`` and ``.state`` are current.

    Examples
    --------
    >>> import numpy as np, pihyst
    >>> from pihyst.inverse import CompensatorBank
    >>> m = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    >>> bank = CompensatorBank([m, m, m], slew_rate=[5.0, None, None])
    >>> u = bank.step([1.0, 1.0, 50.0])        # 50 um is out of reach
    >>> [round(float(v), 6) for v in u], [int(f) for f in bank.last_flags]
    ([5.0, 6.377551, 150.0], [8, 0, 2])
    """

    def __init__(self, models, *, u_min=None, u_max=None, slew_rate=None,
                 initial_voltage=None, initial_state=None):
        models = tuple(models)
        refuse_delayed(models)
        n = len(models)
        args = zip(models, _per_channel(u_min, n, "u_min"), _per_channel(u_max, n, "u_max"),
                   _per_channel(slew_rate, n, "slew_rate"),
                   _per_channel(initial_voltage, n, "initial_voltage"),
                   [None] * n if initial_state is None else
                   _per_channel(list(initial_state), n, "initial_state"), strict=True)
        self.channels = tuple(
            Compensator(m, u_min=lo, u_max=hi, slew_rate=s, initial_voltage=v, initial_state=f)
            for m, lo, hi, s, v, f in args)
        self._array = _core.CompensatorArray([c._core for c in self.channels])
        self._u = np.empty(n)
        self._y = np.empty(n)
        self._flags = np.zeros(n, dtype=np.uint8)

    def __len__(self):
        return len(self.channels)

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

    def reset(self):
        """Every channel back to its initial state and voltage."""
        for c in self.channels:
            c.reset()

    def step(self, y_desired):
        """One tick: the N voltages for N desired displacements (any values)."""
        y_desired = np.ascontiguousarray(y_desired, dtype=np.float64)
        if y_desired.shape != (len(self),):
            raise ValueError(f"y_desired must have {len(self)} values, got shape "
                             f"{y_desired.shape}")
        self._array.step_into(y_desired, self._u, self._y, self._flags)
        return self._u.copy()

    def run(self, y_desired):
        """T ticks: y_desired has shape (T, N). Returns (voltage, displacement, flags),
        each (T, N)."""
        y_desired = np.ascontiguousarray(y_desired, dtype=np.float64)
        if y_desired.ndim != 2 or y_desired.shape[1] != len(self):
            raise ValueError(f"y_desired must have shape (T, {len(self)}), got "
                             f"{y_desired.shape}")
        return self._array.run(y_desired)

    def __repr__(self):
        return f"CompensatorBank({len(self)} channels)"
