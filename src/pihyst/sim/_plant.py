"""Simulated piezo beams standing in for the paper's rig (docs/theory/simulated-beams.md).

A plant chains, per sample,

    u --supply (10 mV steps)--> u_q --hysteresis H--> creep --beam dynamics--> + sensor noise

- hysteresis: a Preisach model with an asymmetric density and a reversible part
  (:class:`pihyst.sim._preisach.Preisach`) or a Bouc-Wen model that keeps a remanent
  displacement (:class:`pihyst.sim._boucwen.BoucWen`); never a PI model, so fitting
  PI models to its data proves something;
- creep: y = H + sum_i c_i z_i with first-order lags z_i of H (time constants at half
  decades, 0.1 s .. 3000 s), i.e. about ``creep_per_decade`` of each change per decade of
  time (:func:`pihyst.sim._lti.creep_filter`);
- beam dynamics (off by default): w^2 / (s^2 + 2 zeta w s + w^2); the cantilever's first
  bending mode, 1.875^2 / (2 pi L^2) sqrt(E t^2 / (12 rho)) ~ 54 Hz for 80 x 0.75 mm
  PZT-5H (E ~ 60 GPa, rho ~ 7500 kg/m^3), negligible at the paper's 300 s period;
- sensor: Gaussian noise, sigma 0.01 um (the paper's laser sensor repeats to 0.02 um).

Every plant starts at rest at 0 V after a full 0 -> u_max -> 0 cycle (docs/interfaces.md):
hysteresis memory of that cycle, creep settled. Noise comes from a generator seeded by
``seed``, so a plant's output is a deterministic function of the seed and the calls.

Examples
--------
>>> from pihyst.sim import make_plant
>>> from pihyst.sim.signals import triangle
>>> t, u = triangle()                     # 0 -> 150 -> 0 V in 300 s
>>> beam = make_plant("paper-beam", seed=1)
>>> y = beam.run(u, t)
>>> bool(43 < y.max() < 47)
True
"""

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst.exceptions import InvalidArgumentError
from pihyst.sim._boucwen import BoucWen
from pihyst.sim._lti import beam_filter, creep_filter, modes_filter
from pihyst.sim._preisach import Preisach
from pihyst.sim._runs import checked_seed

U_MAX = 150.0
SUPPLY_STEP_V = 0.01          # the paper's DC supply resolution
NOISE_UM = 0.01               # sensor noise, standard deviation
BEAM_RESONANCE_HZ = 54.0
BEAM_DAMPING = 0.02


def check_finite(values, what):
    """InvalidArgumentError naming the first sample of ``values`` that is not finite."""
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise InvalidArgumentError(f"sample {bad[0]}: {what} {values[bad[0]]} is not a "
                                   f"finite number")


class Plant:
    """A simulated piezo beam; build one with :func:`make_plant`.

    Parameters
    ----------
    name : str
        Variant name.
    hysteresis : Preisach or BoucWen
        Rate-independent hysteresis (um for V).
    creep_per_decade : float
        Creep per decade of time (fraction of each change); 0 turns creep off.
    noise_um : float
        Sensor noise standard deviation (um); 0 turns it off.
    quantum_V : float
        Supply resolution (V); 0 passes voltages unchanged.
    dynamics : tuple (resonance_hz, damping) or None
        Second-order beam dynamics.
    modes : sequence of (resonance_hz, damping, share) or None
        Several modes instead (:func:`pihyst.sim._lti.modes_filter`; a stage's).
    seed : int
        Seed of the noise generator.
    summary : str
        What the variant stands for (used by :meth:`describe`).

    Examples
    --------
    >>> from pihyst.sim import make_plant
    >>> plant = make_plant("paper-beam")
    >>> plant.name, plant.u_max
    ('paper-beam', 150.0)
    """

    def __init__(self, name: str, hysteresis: Any, *,
                 creep_per_decade: float = 0.0, noise_um: float = 0.0, quantum_V: float = 0.0,
                 dynamics: tuple[float, float] | None = None,
                 modes: Sequence[Sequence[float]] | None = None, seed: int = 0,
                 summary: str = "") -> None:
        self.name = name
        self.hysteresis = hysteresis
        self.u_min = 0.0
        self.u_max = float(hysteresis.u_max)
        self.creep_per_decade = float(creep_per_decade)
        self.noise_um = float(noise_um)
        self.quantum_V = float(quantum_V)
        self.dynamics = dynamics
        self.seed = seed
        self.summary = summary
        self._creep = creep_filter(self.creep_per_decade) if self.creep_per_decade > 0 else None
        self._t: float | None = None
        self._beam: Any = (modes_filter(modes) if modes else
                      beam_filter(*dynamics) if dynamics else None)
        self.reset()

    def reset(self) -> None:
        """Back to the initial rest state (0 V after a full cycle, creep settled, noise
        generator re-seeded): the same calls then give the same output again.

        Examples
        --------
        >>> from pihyst.sim import make_plant
        >>> plant = make_plant("paper-beam")
        >>> a = plant.run([50.0], [1.0]); plant.reset()
        >>> bool(plant.run([50.0], [1.0]) == a)
        True
        """
        self.hysteresis.reset()
        h_rest = float(self.hysteresis.run(np.array([0.0]))[0])
        self.hysteresis.reset()
        y_rest = h_rest
        if self._creep is not None:
            self._creep.rest(h_rest)
            y_rest = h_rest * self._creep.dc_gain
        if self._beam is not None:
            self._beam.rest(y_rest)
        self._rest_output = y_rest
        self._t = None
        self._rng = np.random.default_rng(self.seed)

    @property
    def rest_displacement(self):
        """Displacement at rest at 0 V (um, noise-free): 0 unless the beam is remanent."""
        return self._rest_output

    def run(self, u: ArrayLike, t: ArrayLike) -> NDArray[np.float64]:
        """Measured displacement (µm) for the voltages ``u`` (V) at times ``t`` (s).

        Continues from the current state: ``t`` must not go backwards, also across
        calls. Voltages must lie in [u_min, u_max] (after supply quantisation).

        Parameters
        ----------
        u : array_like
            Voltages (V).
        t : array_like
            Their times (s), of the same length, not decreasing.

        Returns
        -------
        numpy.ndarray
            The measured displacement at each sample (µm).

        Raises
        ------
        InvalidArgumentError
            If ``u`` and ``t`` are not vectors of one length, not finite, a voltage is
            outside the drive range or the time goes backwards.

        Examples
        --------
        >>> from pihyst.sim import make_plant
        >>> y = make_plant("paper-beam").run([0.0, 150.0], [0.0, 150.0])
        >>> bool(40 < y[-1] < 50)
        True
        """
        u = np.asarray(u, dtype=float)
        t = np.asarray(t, dtype=float)
        if u.ndim != 1 or t.shape != u.shape:
            raise InvalidArgumentError(f"u and t must be one-dimensional and of equal length, got "
                             f"shapes {u.shape} and {t.shape}")
        check_finite(u, "voltage")
        check_finite(t, "time")
        if u.size == 0:
            return np.empty(0)
        back = np.flatnonzero(np.diff(t) < 0)
        if back.size:
            raise InvalidArgumentError(f"sample {back[0] + 1}: time goes backwards "
                             f"({t[back[0]]:g} s -> {t[back[0] + 1]:g} s)")
        if self._t is not None and t[0] < self._t:
            raise InvalidArgumentError(f"time {t[0]:g} s is before the previous run's last sample "
                             f"({self._t:g} s); call reset() to start again")
        # u_q = q round(u / q): the supply's resolution
        uq = np.round(u / self.quantum_V) * self.quantum_V if self.quantum_V > 0 else u
        tol = 1e-9 * self.u_max
        bad = np.flatnonzero((uq < self.u_min - tol) | (uq > self.u_max + tol))
        if bad.size:
            raise InvalidArgumentError(f"sample {bad[0]}: voltage {u[bad[0]]:g} V is outside the "
                             f"beam's drive range [{self.u_min:g}, {self.u_max:g}] V")
        uq = np.clip(uq, self.u_min, self.u_max)
        y = self.hysteresis.run(uq)
        if self._creep is not None:
            y = self._creep.run(y, t)
        if self._beam is not None:
            y = self._beam.run(y, t)
        if self.noise_um > 0:
            y = y + self.noise_um * self._rng.standard_normal(y.size)
        self._t = float(t[-1])
        return y

    def describe(self) -> str:
        """One paragraph for reports: what the beam is and what it adds.

        Returns
        -------
        str
            The paragraph.

        Examples
        --------
        >>> from pihyst.sim import make_plant
        >>> make_plant("paper-beam").describe().startswith("Simulated beam 'paper-beam'")
        True
        """
        parts = [f"Simulated beam '{self.name}': {self.summary}"]
        parts.append(f"Drive range {self.u_min:g}-{self.u_max:g} V")
        parts.append(f"supply quantisation {self.quantum_V * 1000:g} mV" if self.quantum_V
                     else "no supply quantisation")
        parts.append(f"creep {100 * self.creep_per_decade:g} % per time decade (first-order "
                     f"lags 0.1-3000 s driven by the hysteretic output)"
                     if self._creep else "no creep")
        parts.append(f"sensor noise sigma {self.noise_um:g} µm" if self.noise_um
                     else "no sensor noise")
        parts.append(f"second-order beam dynamics ({self.dynamics[0]:g} Hz, damping "
                     f"{self.dynamics[1]:g})" if self.dynamics
                     else "modes after the hysteresis" if self._beam else "no beam dynamics")
        return parts[0] + " " + "; ".join(parts[1:]) + (
            f". Starts at rest at 0 V after a full 0-{self.u_max:g}-0 V cycle; noise seed "
            f"{self.seed}.")

    def __repr__(self):
        return f"<Plant {self.name!r}: {type(self.hysteresis).__name__}>"


# ----------------------------------------------------------------------------- variants
# Each entry: hysteresis factory, creep per decade, summary.
#
# paper-beam: least-squares fit (with its creep, on the 300 s triangle) of the loop of the
# paper's Table 1 multislope model scaled to the beam's 45 um at 150 V: a smooth loop of
# ~20 % width that closes at the origin, with the slow-fast rising and hold-then-fall
# falling branches of the paper's Fig. 7.
_VARIANTS = {
    "paper-beam": (
        lambda: Preisach(U_MAX, [(52.61, -0.7544, 0.5377)], reversible=(20.0, 4.65)),
        0.01,
        "Preisach hysteresis (asymmetric density mu = A exp(p alpha + q beta) plus a "
        "reversible part) calibrated to the paper's PZT-5H beam: about 45 µm at 150 V, a "
        "lens-shaped loop about 20 % of the range wide that closes at the origin."),
    "lens": (
        lambda: Preisach(U_MAX, [(95.0, -3.6, 3.1)], reversible=(26.0,)),
        0.02,
        "Preisach hysteresis with a density concentrated near the diagonal (nearly "
        "symmetric, narrow lens-shaped loop closing at both ends) and a linear reversible "
        "part."),
    "s-shaped": (
        lambda: Preisach(U_MAX, [(61.0, -1.5, 1.0)], reversible=(9.0, 36.0, -24.0),
                         warp=0.7),
        0.02,
        "Preisach hysteresis on a warped input (relays concentrated at mid-range) with an "
        "S-shaped reversible part: flat ends, steep middle, a saturating S-shaped loop."),
    "remanent": (
        lambda: BoucWen(U_MAX, d=0.28, alpha=0.42, beta=0.035, gamma=0.008, c2=4.0),
        0.01,
        "Bouc-Wen hysteresis (n = 1) whose loop does not close: after the initial cycle "
        "the beam rests at a remanent displacement at 0 V, and minor loops drift."),
}

PLANT_NAMES = tuple(_VARIANTS)


def make_plant(name: str = "paper-beam", *, seed: int = 0, noise: bool = True,
               creep: bool = True, quantisation: bool = True, dynamics: bool = False) -> "Plant":
    """A simulated beam at rest at 0 V after a full cycle.

    Parameters
    ----------
    name : str
        One of :data:`PLANT_NAMES`: ``"paper-beam"`` (default; calibrated to the paper),
        ``"lens"``, ``"s-shaped"``, ``"remanent"`` (Bouc-Wen).
    seed : int
        Noise seed: the output is deterministic for a seed.
    noise, creep, quantisation, dynamics : bool
        Sensor noise (sigma 0.01 um), creep, 10 mV supply quantisation, second-order beam
        dynamics (54 Hz, off by default).

    Returns
    -------
    Plant

    Examples
    --------
    >>> import numpy as np
    >>> beam = make_plant("remanent", noise=False)
    >>> round(float(beam.run(np.array([0.0]), np.array([0.0]))[0]), 2) > 0
    True
    """
    seed = checked_seed(seed)
    if not isinstance(name, str) or name not in _VARIANTS:
        raise InvalidArgumentError(f"unknown plant {name!r:.40}; choose one of "
                                   f"{', '.join(PLANT_NAMES)}")
    factory, creep_per_decade, summary = _VARIANTS[name]
    return Plant(name, factory(), creep_per_decade=creep_per_decade if creep else 0.0,
                 noise_um=NOISE_UM if noise else 0.0,
                 quantum_V=SUPPLY_STEP_V if quantisation else 0.0,
                 dynamics=(BEAM_RESONANCE_HZ, BEAM_DAMPING) if dynamics else None,
                 seed=seed, summary=summary)
