"""Many models stepped together: one input vector per tick (deformable mirrors,
multi-axis stages). Each channel is its own model with its own running state; the bank
steps them all in one call of the C core (pihyst_bank_step), with bit for bit the
outputs of the channels' own steppers. With ``fast=True`` it steps them from a
structure-of-arrays copy of their states (pihyst_modelbank, docs/c-core.md): classical
channels of up to 16 operators several at a time, with the same bits."""

from collections.abc import Iterable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst import _core
from pihyst.exceptions import InputRangeError, InvalidArgumentError, InvalidModelError
from pihyst.model._models import PIModel


class ModelBank:
    """N independent models (any families, sizes, input ranges) run sample vector by
    sample vector. Owns one running state per channel (a :class:`Stepper` each, in
    ``channels``), so the models themselves never change.

    Parameters
    ----------
    models : sequence of PIModel
        One model per channel; the same model may drive several channels.
    initial_states : sequence, optional
        One initial operator state per channel (None entries: that model's own).
    fast : bool
        Step classical channels (K <= 16) several at a time from a structure-of-arrays
        copy of the states: the same outputs, bit for bit, in less time per channel.
        ``channels`` (and ``states``) are brought up to date when read; reset them
        through :meth:`reset` (a fast bank does not see a channel reset on its own).

    Examples
    --------
    >>> import numpy as np, pihyst
    >>> from pihyst.model import ModelBank
    >>> a = pihyst.ClassicalPI([0, 10], [1.0, 0.5])
    >>> b = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    >>> bank = ModelBank([a, b, a])
    >>> y = bank.step([20.0, 100.0, 5.0])      # one tick: one voltage per channel
    >>> bool(np.array_equal(y, [a.predict([20.0])[0], b.predict([100.0])[0],
    ...                         a.predict([5.0])[0]]))
    True
    """

    def __init__(self, models: Iterable[PIModel],
                 initial_states: Sequence[ArrayLike | None] | None = None, *,
                 fast: bool = False) -> None:
        models = tuple(models)
        for i, m in enumerate(models):
            if not isinstance(m, PIModel):
                raise InvalidArgumentError(f"models[{i}] must be a pihyst model, not "
                                           f"{type(m).__name__}")
        refuse_delayed(models)
        if initial_states is None:
            initial_states = [None] * len(models)
        initial_states = list(initial_states)
        if len(initial_states) != len(models):
            raise InvalidArgumentError(f"initial_states must have {len(models)} entries, got "
                                       f"{len(initial_states)}")
        self.models = models
        self._channels = tuple(m.stepper(s) for m, s in zip(models, initial_states, strict=True))
        banks = [s._bank for s in self._channels]
        self._array = _core.BankSoA(banks) if fast else _core.BankArray(banks)
        self._stale = False
        self._lo = np.array([m.input_range[0] for m in models], dtype=np.float64)
        self._hi = np.array([m.input_range[1] for m in models], dtype=np.float64)

    def __len__(self):
        return len(self.models)

    @property
    def fast(self):
        """True if the bank steps from a structure-of-arrays copy of the states."""
        return isinstance(self._array, _core.BankSoA)

    @property
    def channels(self):
        """The N :class:`Stepper` objects, brought up to date."""
        if self._stale:
            self._array.sync()
            self._stale = False
        return self._channels

    @property
    def states(self):
        """The running operator state of every channel (a list of copies)."""
        return [s.state for s in self.channels]

    def reset(self, states: Sequence[ArrayLike | None] | None = None) -> None:
        """Every channel back to its initial state, or to ``states``.

        Parameters
        ----------
        states : sequence, optional
            One operator state per channel (None entries: the channel's initial state).

        Raises
        ------
        InvalidArgumentError
            If ``states`` does not have one entry per channel.

        Examples
        --------
        >>> from pihyst.model import ClassicalPI
        >>> bank = ModelBank([ClassicalPI([0], [1.0])])
        >>> _ = bank.step([5.0]); bank.reset(); bank.states[0].tolist()
        [0.0]
        """
        states = [None] * len(self) if states is None else list(states)
        if len(states) != len(self):
            raise InvalidArgumentError(f"states must have {len(self)} entries, got {len(states)}")
        for s, state in zip(self._channels, states, strict=True):
            s.reset(state)
        if isinstance(self._array, _core.BankSoA):
            self._array.reload()
        self._stale = False

    def _checked(self, u):
        u = np.ascontiguousarray(u, dtype=np.float64)
        if u.ndim != 2 or u.shape[1] != len(self):
            raise InvalidArgumentError(f"input must have shape (T, {len(self)}), got {u.shape}")
        ok = (u >= self._lo) & (u <= self._hi)  # NaN fails too
        if not ok.all():
            t, i = np.argwhere(~ok)[0]
            raise InputRangeError(int(t), float(u[t, i]),
                                  (float(self._lo[i]), float(self._hi[i])))
        return u

    def step(self, u: ArrayLike) -> NDArray[np.float64]:
        """One tick: advance channel i by the input u[i].

        Parameters
        ----------
        u : array_like
            One input per channel (V), shape (N,).

        Returns
        -------
        numpy.ndarray
            The N outputs.

        Raises
        ------
        InvalidArgumentError
            If ``u`` does not have N values.
        InputRangeError
            If an input is outside its channel's input range.

        Examples
        --------
        >>> from pihyst.model import ClassicalPI
        >>> ModelBank([ClassicalPI([0], [1.0]), ClassicalPI([0], [2.0])]).step([1, 1]).tolist()
        [1.0, 2.0]
        """
        u = np.asarray(u, dtype=np.float64)
        if u.shape != (len(self),):
            raise InvalidArgumentError(f"input must have {len(self)} values, got shape {u.shape}")
        y = self._array.run(self._checked(u[None, :]))[0]
        self._stale = self.fast
        return y

    def run(self, u: ArrayLike) -> NDArray[np.float64]:
        """T ticks, row t of ``u`` one tick.

        Parameters
        ----------
        u : array_like
            Inputs of shape (T, N) (V).

        Returns
        -------
        numpy.ndarray
            The outputs, shape (T, N).

        Raises
        ------
        InvalidArgumentError
            If ``u`` does not have shape (T, N).
        InputRangeError
            If an input is outside its channel's input range.

        Examples
        --------
        >>> from pihyst.model import ClassicalPI
        >>> ModelBank([ClassicalPI([0], [1.0])]).run([[1.0], [3.0]]).tolist()
        [[1.0], [3.0]]
        """
        y = self._array.run(self._checked(u))
        self._stale = self.fast
        return y

    def __repr__(self):
        return f"ModelBank({len(self)} channels)"


def refuse_delayed(models):
    """InvalidModelError for the first model with an input delay: a bank steps every
    channel by the same tick and has no delay line (docs/fleets.md)."""
    for i, m in enumerate(models):
        if getattr(m, "delay", 0):
            raise InvalidModelError(f"models[{i}] has an input delay of {m.delay} samples: "
                                    f"a bank does not delay its channels (use "
                                    f"model.replace(delay=0) and shift the inputs, or "
                                    f"run the channel on its own)")
