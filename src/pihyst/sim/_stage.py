"""Simulated scanning stages: a beam's hysteresis and creep followed by fast dynamics, at a
fixed controller clock (docs/theory/simulated-beams.md, "Stages with dynamics").

Per clock tick n (period T = 1 / rate_hz) a stage chains

    u[n] --converter delay d--> u[n - d] --amplifier slew limit--> v[n]
         --supply quantisation, hysteresis H, creep--> h[n]
         --modes G(s)--> y[n] + sensor noise,

    v[n] = v[n-1] + clip(u[n - d] - v[n-1], -S T, S T)      (S: slew limit, V/s),
    G(s) = sum_i g_i w_i^2 / (s^2 + 2 zeta_i w_i s + w_i^2),  sum_i g_i = 1,

the modes lightly damped (typically 100 Hz - 5 kHz, 1 - 10 % damping; the modal filter of
:func:`pihyst.sim._lti.modes_filter`). Before the first command the converter holds 0 V
(the rest state of every plant). :meth:`Stage.run_periodic` plays one period of voltages
over and over, as a DAQ's or a controller's wave generator does, and returns the last
period measured: the ``run_period`` of :func:`pihyst.learn.learn_periodic`.
"""

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst.exceptions import InvalidArgumentError
from pihyst.sim._plant import Plant, check_finite


class Stage(Plant):
    """A plant with modes, a converter delay and an amplifier slew limit, run at a fixed
    clock; build one with :func:`make_stage` (or ``random_plant(seed, dynamics=True)``).

    Parameters
    ----------
    name, hysteresis
        As for :class:`Plant`.
    modes : sequence of (resonance_hz, damping, share)
        The lightly damped modes after the hysteresis (shares normalised to sum 1).
    rate_hz : float
        The controller clock: one voltage per tick.
    delay_samples : int
        Converter delay, whole ticks.
    slew_V_per_s : float or None
        Amplifier slew (current) limit; None: none.
    creep_per_decade, noise_um, quantum_V, seed, summary
        As for :class:`Plant`.

    Raises
    ------
    InvalidArgumentError
        If the clock, the delay or the slew limit is not valid.

    Examples
    --------
    >>> stage = make_stage()
    >>> stage.rate_hz, stage.delay_samples
    (20000.0, 1)
    """

    def __init__(self, name: str, hysteresis: Any, *, modes: Sequence[Sequence[float]],
                 rate_hz: float, delay_samples: int = 0, slew_V_per_s: float | None = None,
                 creep_per_decade: float = 0.0, noise_um: float = 0.0, quantum_V: float = 0.0,
                 seed: int = 0, summary: str = "") -> None:
        if not (math.isfinite(rate_hz) and rate_hz > 0):
            raise InvalidArgumentError(f"rate_hz must be a positive number, got {rate_hz!r}")
        if int(delay_samples) != delay_samples or delay_samples < 0:
            raise InvalidArgumentError(f"delay_samples must be a whole number >= 0, got "
                                       f"{delay_samples!r}")
        if slew_V_per_s is not None and not slew_V_per_s > 0:
            raise InvalidArgumentError(f"slew_V_per_s must be > 0 or None, got {slew_V_per_s!r}")
        self.modes = tuple(tuple(float(v) for v in m) for m in modes)
        self.rate_hz = float(rate_hz)
        self.delay_samples = int(delay_samples)
        self.slew_V_per_s = None if slew_V_per_s is None else float(slew_V_per_s)
        super().__init__(name, hysteresis, modes=self.modes, creep_per_decade=creep_per_decade,
                         noise_um=noise_um, quantum_V=quantum_V, seed=seed, summary=summary)

    @property
    def sample_period(self):
        return 1.0 / self.rate_hz

    @property
    def settle_time_s(self):
        """Five time constants 1 / (zeta w) of the slowest-decaying mode: a transient of
        the modes has fallen below 1 % of its start after that."""
        return max(5.0 / (z * 2 * np.pi * hz) for hz, z, _ in self.modes)

    def reset(self) -> None:
        """Back to the initial rest state, the converter and the amplifier at 0 V and the
        clock at tick 0.

        Examples
        --------
        >>> import numpy as np
        >>> stage = make_stage(noise_um=0.0)
        >>> a = stage.run([50.0, 60.0]); stage.reset()
        >>> bool((stage.run([50.0, 60.0]) == a).all())
        True
        """
        super().reset()
        self._pending = np.zeros(getattr(self, "delay_samples", 0))
        self._amplifier = 0.0
        self._tick = 0

    def hold(self, voltage: float) -> None:
        """As if the stage had been held at ``voltage`` for ever: from the rest state,
        the hysteresis driven there, the creep lags settled at its output, the modes at
        rest, the converter and the amplifier at that voltage (the start of a scan on a
        stage that has been on, without simulating the hours it took).

        Parameters
        ----------
        voltage : float
            The voltage held (V), inside the drive range.

        Raises
        ------
        InvalidArgumentError
            If the voltage is outside the drive range.

        Examples
        --------
        >>> import numpy as np
        >>> stage = make_stage(noise_um=0.0)
        >>> stage.hold(75.0)
        >>> y = stage.run(np.full(100, 75.0))
        >>> bool(np.ptp(y) < 0.01)
        True
        """
        voltage = float(voltage)
        if not self.u_min <= voltage <= self.u_max:
            raise InvalidArgumentError(f"voltage {voltage:g} V is outside the stage's drive "
                                       f"range [{self.u_min:g}, {self.u_max:g}] V")
        self.reset()
        h = float(self.hysteresis.run(np.array([voltage]))[0])
        y = h
        if self._creep is not None:
            self._creep.rest(h)
            y = h * self._creep.dc_gain
        self._beam.rest(y)
        self._pending[:] = voltage
        self._amplifier = voltage

    def settle_on(self, u: ArrayLike) -> None:
        """As if the stage had been playing the period ``u`` over and over for ever: the
        hysteresis from the rest state through two periods (its memory then repeats),
        the creep lags settled at the mean hysteresis output of the period (where a
        long periodic drive leaves the slow ones), the modes at rest at the output, the
        converter and the amplifier at the period's last voltage. The next periods
        settle the rest (the fast lags, the modes' transient): then the stage is in the
        steady state of a scan that has run for hours, without simulating them.

        Parameters
        ----------
        u : array_like
            One period of voltages (V), inside the drive range.

        Examples
        --------
        >>> import numpy as np
        >>> stage = make_stage(noise_um=0.0)
        >>> period = np.r_[np.linspace(0, 150, 50), np.linspace(150, 0, 50)]
        >>> stage.settle_on(period)
        >>> _ = stage.run(np.tile(period, 5))        # the modes' transient dies out
        >>> a, b = stage.run(period), stage.run(period)
        >>> bool(np.abs(a - b).max() < 0.01)
        True
        """
        u = np.asarray(u, dtype=float)
        self.reset()
        h = self.hysteresis.run(np.clip(np.tile(u, 2), self.u_min, self.u_max))[u.size:]
        y = float(h[-1])
        if self._creep is not None:
            self._creep.rest(float(np.mean(h)))
            y = float(self._creep.run(np.array([h[-1]]), np.array([0.0]))[0])
            self._creep._t = None
        self._beam.rest(y)
        self._pending[:] = u[-1]
        self._amplifier = float(u[-1])

    def _amplified(self, u):
        """v of the module notes: the delayed commands through the slew limit."""
        line = np.concatenate((self._pending, u))
        delayed, self._pending = line[:u.size], line[u.size:]
        if self.slew_V_per_s is None:
            self._amplifier = float(delayed[-1])
            return delayed
        step = self.slew_V_per_s / self.rate_hz
        prev = np.concatenate(([self._amplifier], delayed[:-1]))
        if np.all(np.abs(delayed - prev) <= step):
            out = delayed              # within the slew limit: the amplifier follows
        else:
            out = np.empty(u.size)
            v = self._amplifier
            for n, target in enumerate(delayed):
                v += min(max(target - v, -step), step)
                out[n] = v
        self._amplifier = float(out[-1])
        return out

    def run(self, u: ArrayLike, t: ArrayLike | None = None) -> NDArray[np.float64]:
        """Measured displacement (µm) for the commands ``u`` (V), one per clock tick,
        continuing from the last call.

        Parameters
        ----------
        u : array_like
            One voltage per tick (V).
        t : array_like, optional
            Those ticks' times (s), checked against the clock.

        Returns
        -------
        numpy.ndarray
            The measured displacement at each tick (µm).

        Raises
        ------
        InvalidArgumentError
            If ``u`` is not a vector of finite voltages in the drive range, or ``t`` is
            not the next ticks' times.

        Examples
        --------
        >>> import numpy as np
        >>> stage = make_stage(noise_um=0.0)
        >>> stage.run([0.0, 0.0]).shape
        (2,)
        """
        u = np.asarray(u, dtype=float)
        ticks = (self._tick + np.arange(u.size)) / self.rate_hz
        if t is not None and (np.shape(t) != u.shape
                              or not np.allclose(t, ticks, rtol=0, atol=1e-3 / self.rate_hz)):
            raise InvalidArgumentError(f"a stage runs at its clock ({self.rate_hz:g} Hz): t "
                                       f"must be the next {u.size} ticks from {ticks[:1]} s")
        if u.ndim != 1:
            raise InvalidArgumentError(f"u must be one-dimensional, got shape {u.shape}")
        check_finite(u, "voltage")      # before the converter holds it
        if u.size == 0:
            return np.empty(0)
        y = super().run(self._amplified(u), ticks)
        self._tick += u.size
        return y

    def run_periodic(self, u: ArrayLike, periods: int | None = None) -> NDArray[np.float64]:
        """Play one period of voltages ``u`` ``periods`` times in a row (default: enough to
        cover :attr:`settle_time_s`, at least 2) and return the last period measured.

        Parameters
        ----------
        u : array_like
            One period of voltages (V), one per tick.
        periods : int, optional
            How many periods to play (default: enough to settle, at least 2).

        Returns
        -------
        numpy.ndarray
            The displacement over the last period (µm).

        Raises
        ------
        InvalidArgumentError
            As for :meth:`run`.

        Examples
        --------
        >>> import numpy as np
        >>> stage = make_stage(noise_um=0.0)
        >>> stage.run_periodic(np.full(100, 10.0), periods=2).shape
        (100,)
        """
        u = np.asarray(u, dtype=float)
        if periods is None:
            periods = max(2, 1 + math.ceil(self.settle_time_s * self.rate_hz / max(u.size, 1)))
        y = self.run(np.tile(u, int(periods)))
        return y[-u.size:]

    def describe(self) -> str:
        """One paragraph for reports: the beam, then the stage's clock, modes, converter
        delay and slew limit.

        Returns
        -------
        str
            The paragraph.

        Examples
        --------
        >>> "800 Hz" in make_stage().describe()
        True
        """
        modes = ", ".join(f"{hz:g} Hz / {100 * z:g} %" for hz, z, _ in self.modes)
        slew = ("no slew limit" if self.slew_V_per_s is None
                else f"amplifier slew limit {self.slew_V_per_s:g} V/s")
        return (super().describe() + f" Stage at a {self.rate_hz:g} Hz clock: modes {modes}; "
                f"converter delay {self.delay_samples} tick(s); {slew}.")


def make_stage(name: str = "paper-beam", *,
               modes: Sequence[Sequence[float]] = ((800.0, 0.04),), rate_hz: float = 20_000.0,
               delay_samples: int = 1, slew_V_per_s: float | None = None,
               noise_um: float = 0.005, creep: bool = True, quantisation: bool = True,
               seed: int = 0) -> Stage:
    """A simulated stage: the hysteresis and creep of the beam ``name`` (one of
    :data:`pihyst.sim.PLANT_NAMES`) followed by ``modes`` ((hz, damping) or (hz, damping,
    share) each), a converter delay, an amplifier slew limit, at ``rate_hz``.

    The default is the resonant stage of the scanning issue: the paper beam's hysteresis,
    one 800 Hz mode with 4 % damping, one tick of converter delay, a 20 kHz clock and
    0.005 µm sensor noise.

    Parameters
    ----------
    name : str
        The beam whose hysteresis and creep the stage has.
    modes : sequence of tuple
        (hz, damping) or (hz, damping, share) of each mode.
    rate_hz : float
        The clock (Hz): one voltage per tick.
    delay_samples : int
        Converter delay (ticks).
    slew_V_per_s : float, optional
        Amplifier slew limit (V/s); None: none.
    noise_um : float
        Sensor noise standard deviation (µm).
    creep : bool
        Keep the beam's creep.
    quantisation : bool
        Quantise voltages to the supply's 10 mV steps.
    seed : int
        Seed of the noise generator.

    Returns
    -------
    Stage
        The stage, at rest at 0 V.

    Raises
    ------
    InvalidArgumentError
        If ``name`` is not a beam or another argument is not valid.

    Examples
    --------
    >>> import numpy as np
    >>> stage = make_stage(noise_um=0.0)
    >>> y = stage.run_periodic(np.full(200, 75.0))
    >>> bool(np.ptp(y) < 0.1)       # held at 75 V: the step's slow tail moves it < 0.1 um
    True
    """
    from pihyst.sim._plant import _VARIANTS, SUPPLY_STEP_V
    from pihyst.sim._runs import checked_seed
    seed = checked_seed(seed)
    if not isinstance(name, str) or name not in _VARIANTS:
        raise InvalidArgumentError(f"unknown plant {name!r:.40}; choose one of "
                                   f"{', '.join(_VARIANTS)}")
    modes = [tuple(m) + (1.0,) * (3 - len(m)) for m in modes]
    factory, creep_per_decade, summary = _VARIANTS[name]
    return Stage(f"{name}-stage", factory(), modes=modes, rate_hz=rate_hz,
                 delay_samples=delay_samples, slew_V_per_s=slew_V_per_s,
                 creep_per_decade=creep_per_decade if creep else 0.0, noise_um=noise_um,
                 quantum_V=SUPPLY_STEP_V if quantisation else 0.0, seed=seed, summary=summary)
