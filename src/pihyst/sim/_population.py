"""A population of random simulated actuators (docs/theory/simulated-beams.md).

:func:`random_plant` draws one actuator from a seed: hysteresis (a Preisach model with a
random asymmetric density and reversible part, or a Bouc-Wen model with exponent n in
[1, 2] and random beta, gamma, some with strong remanence, 10-20 % of the range), creep
(none, or 0.3-3 % per decade), sensor noise, supply quantisation and a sample rate from
200 Hz to 10 kHz (log-uniform). The same seed always gives the same actuator; the
description says what was drawn.

With ``dynamics=True`` the actuator is a scanning :class:`~pihyst.sim.Stage` (the same
hysteresis, creep and noise, drawn first and identically): one or two lightly damped
modes (the first 100 Hz - 5 kHz, damping 1 - 10 %, both log-uniform; a second one with
probability 1/2 at 1.5 - 4 times the first, sharing 10 - 30 % of the static gain), a
clock of 10 - 100 kHz (log-uniform, at least 10 times the first mode), a converter delay
of 0 - 2 ticks and an amplifier slew limit of 50 - 500 kV/s (log-uniform), drawn from a
stream of their own so that ``dynamics=False`` draws exactly what it always drew.
"""

from typing import Any

import numpy as np

from pihyst.sim._boucwen import BoucWen
from pihyst.sim._plant import SUPPLY_STEP_V, U_MAX, Plant
from pihyst.sim._preisach import Preisach
from pihyst.sim._stage import Stage

__all__ = ["random_plant"]

RATE_RANGE_HZ = (200.0, 10_000.0)
MODE_RANGE_HZ = (100.0, 5_000.0)
DAMPING_RANGE = (0.01, 0.10)
CLOCK_RANGE_HZ = (10_000.0, 100_000.0)
SLEW_RANGE_V_PER_S = (5e4, 5e5)


def _log_uniform(rng, lo, hi):
    return float(10 ** rng.uniform(np.log10(lo), np.log10(hi)))


def _stage_dynamics(seed):
    """Modes, clock, converter delay and slew limit of a stage (module notes)."""
    rng = np.random.default_rng([0x5EED, int(seed), 1])
    f1 = _log_uniform(rng, *MODE_RANGE_HZ)
    modes = [(f1, _log_uniform(rng, *DAMPING_RANGE), 1.0)]
    if rng.random() < 0.5:
        share = float(rng.uniform(0.1, 0.3))
        modes = [(f1, modes[0][1], 1.0 - share),
                 (f1 * float(rng.uniform(1.5, 4.0)), _log_uniform(rng, *DAMPING_RANGE), share)]
    clock = _log_uniform(rng, max(CLOCK_RANGE_HZ[0], 10 * f1), CLOCK_RANGE_HZ[1])
    return {"modes": modes, "rate_hz": clock, "delay_samples": int(rng.integers(0, 3)),
            "slew_V_per_s": _log_uniform(rng, *SLEW_RANGE_V_PER_S)}


def _preisach(rng):
    """Random asymmetric density terms, a non-decreasing reversible part, maybe a warp."""
    while True:
        n_terms = int(rng.integers(1, 3))
        terms = [(float(rng.uniform(20.0, 90.0)), float(rng.uniform(-4.0, 1.0)),
                  float(rng.uniform(-1.0, 4.0))) for _ in range(n_terms)]
        c1 = float(rng.uniform(5.0, 35.0))
        c2 = float(rng.uniform(-0.4 * c1, 20.0))
        reversible = [c1, c2]
        if rng.random() < 0.3:
            reversible.append(float(rng.uniform(-0.3, 0.3) * c1))
        warp = float(rng.uniform(0.0, 0.7)) if rng.random() < 0.3 else 0.0
        try:
            h = Preisach(U_MAX, terms, reversible=reversible, warp=warp)
        except ValueError:       # reversible part not monotone: draw again
            continue
        desc = {"kind": "preisach", "terms": terms, "reversible": reversible, "warp": warp}
        return h, desc


def _rise_and_rest(h):
    """(rise from rest at 0 V to u_max, rest displacement at 0 V after the full cycle)."""
    h.reset()
    rest = float(h.run(np.array([0.0]))[0])
    top = float(h.run(np.array([U_MAX]))[0])
    h.reset()
    return top - rest, rest


def _remanence(h):
    """Remanent displacement at 0 V after the full cycle, in % of the 0 -> u_max rise."""
    rise, rest = _rise_and_rest(h)
    return 100.0 * rest / max(rise, 1e-12)


def _bouc_wen(rng, strong):
    """Random Bouc-Wen with n in [1, 2]; ``strong``: remanence 10-20 % of the range."""
    for _ in range(200):
        n = float(rng.uniform(1.0, 2.0))
        d = float(rng.uniform(0.2, 0.35))
        rho = float(rng.uniform(-0.6, 0.6))              # gamma / beta
        alpha = float(rng.uniform(0.3, 1.0) * (1 + rho) / 2)   # 2 alpha beta/(beta+gamma) <= 1
        # |h| saturates at h_sat = (alpha d / (beta + gamma))^(1/n): choose h_sat, get beta
        h_sat = float(rng.uniform(0.05, 0.45) * d * U_MAX)
        beta = alpha * d / (h_sat ** n * (1 + rho))
        c2 = float(rng.uniform(0.0, 8.0))
        h = BoucWen(U_MAX, d=d, alpha=alpha, beta=beta, gamma=rho * beta, c2=c2, n=n)
        rem = _remanence(h)
        if (10.0 <= rem <= 20.0) if strong else (1.0 <= rem < 10.0):
            desc = {"kind": "bouc-wen", "n": n, "d": d, "alpha": alpha, "beta": beta,
                    "gamma": rho * beta, "c2": c2, "remanence_pct": rem,
                    "strong_remanence": bool(strong)}
            return h, desc
    raise RuntimeError("no Bouc-Wen parameters with the requested remanence found")


def random_plant(seed: int, *, dynamics: bool = False) -> tuple[Plant, dict[str, Any]]:
    """A random simulated actuator and a description of what was drawn.

    Returns ``(plant, description)``: a :class:`~pihyst.sim.Plant` at rest at 0 V after a
    full cycle, and a dict with ``kind`` (``"preisach"`` or ``"bouc-wen"``), the
    hysteresis parameters, ``creep_per_decade``, ``noise_um``, ``rate_hz`` (the sample
    rate its records are made at) and ``remanence_pct``. ``dynamics=True``: a
    :class:`~pihyst.sim.Stage` (module notes), whose description adds ``modes``,
    ``delay_samples`` and ``slew_V_per_s`` and whose ``rate_hz`` is its clock.

    Parameters
    ----------
    seed : int
        The seed: the same seed gives the same actuator.
    dynamics : bool, default False
        Draw a stage with modes, a converter delay and a slew limit.

    Returns
    -------
    plant : Plant or Stage
        The actuator.
    description : dict
        What was drawn.

    Examples
    --------
    >>> plant, desc = random_plant(3)
    >>> desc["kind"] in ("preisach", "bouc-wen"), 200 <= desc["rate_hz"] <= 10000
    (True, True)
    """
    rng = np.random.default_rng([0x5EED, int(seed)])
    kind = rng.choice(["preisach", "preisach", "bouc-wen", "bouc-wen-remanent"])
    if kind == "preisach":
        hyst, desc = _preisach(rng)
    else:
        hyst, desc = _bouc_wen(rng, strong=kind == "bouc-wen-remanent")
    creep = 0.0 if rng.random() < 0.2 else float(rng.uniform(0.003, 0.03))
    rise, _ = _rise_and_rest(hyst)
    noise = float(10 ** rng.uniform(-4.3, -3.0) * rise)   # 0.005 .. 0.1 % of the range
    rate = float(10 ** rng.uniform(*np.log10(RATE_RANGE_HZ)))
    desc.setdefault("remanence_pct", _remanence(hyst))
    desc.update({"creep_per_decade": creep, "noise_um": noise, "rate_hz": rate,
                 "range_um": rise, "seed": int(seed)})
    summary = (f"random {desc['kind']} actuator (seed {seed}): creep "
               f"{100 * creep:.2g} %/decade, noise {noise:.3g} µm, {rate:.0f} Hz")
    options: dict[str, Any] = dict(creep_per_decade=creep, noise_um=noise, quantum_V=SUPPLY_STEP_V,
                   seed=int(seed), summary=summary)
    if not dynamics:
        return Plant(f"random-{seed}", hyst, **options), desc
    stage: dict[str, Any] = _stage_dynamics(seed)
    desc.update(stage)
    return Stage(f"random-stage-{seed}", hyst, **stage, **options), desc
