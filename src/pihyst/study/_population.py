"""A population study: fit and compensate random simulated actuators, judged on signals
the fit never saw (benchmarks/bench_population.py, tests/study/test_population.py).

For one actuator (:func:`pihyst.sim.random_plant`), at its own sample rate:

1. a record of the kind users make, chosen by the seed: the paper's triangle (two
   cycles), decaying triangles, or a sine of growing amplitude; its period is set so a
   cycle has about ``samples_per_cycle`` samples (0.5-300 s);
2. ``pihyst.fit`` on it (the default choice), with the record's sample times (creep
   then fitted and kept where the held-back cycles say it helps) and without them;
3. judged on random level ramps (at the record's rate of change) and on a staircase held
   10-60 s per level (the level changes at most every 10 ms, so the held levels are
   sampled at up to 100 Hz): **validation**, the model's prediction against the
   actuator's response to the voltage signal; **tracking**, the actuator driven with the
   compensator's voltages for the same shapes as desired displacements (2-95 % of the
   model's rise), against the desired values. Errors are mean absolute errors in % of the
   signal's range.
"""

from dataclasses import dataclass, field

import numpy as np

from pihyst.identify import fit
from pihyst.inverse import compensate
from pihyst.sim import random_plant, signals

RECORD_KINDS = ("triangle", "decaying-triangles", "growing-sine")
JUDGED = ("ramps", "staircase")


@dataclass
class PlantResult:
    """Errors of one actuator: ``errors[(creep, task, signal)]`` in % of range, with
    ``creep`` True (fitted with the sample times: creep where it helps) or False
    (without them), ``task`` "validation"/"tracking", ``signal`` in :data:`JUDGED`."""

    seed: int
    description: dict
    record: str
    errors: dict = field(default_factory=dict)
    families: dict = field(default_factory=dict)
    creep_gain: float = 0.0

    def mean(self, creep, task):
        return float(np.mean([self.errors[(creep, task, s)] for s in JUDGED]))


def _pct(err, ref):
    return 100.0 * float(np.mean(np.abs(err))) / float(np.ptp(ref))


def record_for(seed, rate_hz, samples_per_cycle=10_000):
    """(kind, t, u): the seed's record at ``rate_hz``."""
    rng = np.random.default_rng([0x7EC, int(seed)])
    kind = RECORD_KINDS[int(rng.integers(len(RECORD_KINDS)))]
    dt = 1.0 / rate_hz
    period = float(np.clip(samples_per_cycle * dt, 0.5, 300.0))
    if kind == "triangle":
        t, u = signals.triangle(period_s=period, n_cycles=2, dt=dt)
    elif kind == "decaying-triangles":
        t, u = signals.decaying_triangles(period_s=period, dt=dt)
    else:
        t, u = signals.growing_sine(period_s=period, n_cycles=5, dt=dt)
    return kind, t, u, period


def judged_signals(seed, rate_hz, period, lo, hi, fine=False):
    """The random-ramp and staircase signals between ``lo`` and ``hi``; the staircase at
    up to 100 Hz, or at the record's rate when ``fine`` (a model with a delay runs only
    at sample times its delay is a whole number of)."""
    rng = np.random.default_rng([0x51C, int(seed)])
    dt = 1.0 / rate_hz
    ramps = signals.random_ramps(u_min=lo, u_max=hi, n_ramps=12,
                                 rate=(hi - lo) / (period / 2), dt=dt,
                                 seed=int(rng.integers(1 << 30)))
    stairs = signals.staircase(u_min=lo, u_max=hi, n_steps=6,
                               step_s=float(rng.uniform(10.0, 60.0)),
                               dt=dt if fine else max(dt, 0.01))
    return {"ramps": ramps, "staircase": stairs}


def evaluate_plant(seed, samples_per_cycle=10_000):
    """Fit, validate and track one random actuator, fitted with and without the record's
    sample times (with them, the default fit keeps creep where it helps)."""
    plant, desc = random_plant(seed)
    kind, t, u, period = record_for(seed, desc["rate_hz"], samples_per_cycle)
    y = plant.run(u, t)
    result = PlantResult(seed=int(seed), description=desc, record=kind)
    for creep in (False, True):
        # the drive range is known: a record whose peak sample falls just short of u_max
        # must not shrink the model's input range below the signals it is judged on
        span = (0.0, plant.u_max)
        fitted = fit(u, y, t=t if creep else None, input_range=span)
        model = fitted.model
        result.families[creep] = model.metadata["fit"]["family"]
        creeps = getattr(model, "creep", None) is not None
        if creeps:
            result.creep_gain = float(model.creep.gain.sum())
        # the rise without the delay, whose output would still be the held first input
        rise = model.replace(delay=0).predict(np.array([0.0, model.input_range[1]]))
        lo, hi = rise[0] + 0.02 * (rise[1] - rise[0]), rise[0] + 0.95 * (rise[1] - rise[0])
        fine = creeps and model.delay != 0
        voltages = judged_signals(seed, desc["rate_hz"], period, 0.0, plant.u_max, fine)
        desired = judged_signals(seed, desc["rate_hz"], period, lo, hi, fine)
        for name in JUDGED:
            tv, uv = voltages[name]
            plant.reset()
            measured = plant.run(uv, tv)
            result.errors[(creep, "validation", name)] = _pct(
                model.predict(uv, **({"t": tv} if creeps else {})) - measured, measured)
            td, yd = desired[name]
            comp = compensate(model, yd, t=td if creeps else None)
            plant.reset()
            result.errors[(creep, "tracking", name)] = _pct(plant.run(comp.voltage, td) - yd,
                                                            yd)
        plant.reset()
    return result
