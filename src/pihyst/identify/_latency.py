"""Real-time cost of a fitted model: the latency of its exact compensator, from a cost
model of its structure (what the choice uses) or measured (benchmarks only).

A candidate model runs in a controller as its exact compensator
(:class:`pihyst.Compensator` for a PI model, :class:`pihyst.inverse.BoucWenCompensator`
for Bouc-Wen; both in C), one desired displacement in, one voltage out, every sample. Its
cost per sample depends on the trajectory: following a smooth trajectory the inverse moves
little between samples (**typical**); a desired displacement drawn at random every sample
makes it cross the most operator breakpoints and reversals (**worst case**).

The fit decides on :func:`estimate_latency`, never on a clock, so that the same record
gives the same model on every run and machine. The cost model counts what the C
compensator does per sample:

- a PI model (classical, multislope, pwl; KP kernels are pwl operators): every operator is
  updated once (K operators), and the breakpoints of the output y(u) are walked from the
  last voltage to the one that solves the sample: few while tracking, up to every vertex
  of every envelope (V, the envelopes' polyline vertices, 2 per operator for a classical
  play) on a jump; each creep lag (L) is advanced once,

      t_typical = A0 + A_K K + A_V V + A_L L,      t_worst = B0 + B_K K + B_V V + B_L L;

- a Bouc-Wen model: Newton's method on the Runge-Kutta step of the model, whose substeps
  H = min(1/256, 1/(32 (beta + |gamma|))) of the range (model._boucwen.substep) set the
  work: m = ceil(|dx| / H) substeps for an input change dx, so

      t = C0 + C_S m(dx) + C_L L,

  with dx the largest change per sample of the tracking sine (typical) and a third of the
  range (the mean jump of a uniform random target: worst case).

The coefficients were calibrated once by ``benchmarks/calibrate_latency.py`` (the
compensators' run timed on classical K = 2..128, multislope, pwl and KP models, Bouc-Wen
shapes from sharpness 2 to 200, with and without creep), a non-negative least-squares fit
to the median of three timings; that script prints the fit's residuals and the
estimate beside the measurement for each model. :func:`measure_latency` times a
compensator (blocks of its ``run``, the C loop, about ``BLOCK_SECONDS`` each, the median
of ``REPEATS``) for the benchmarks and that calibration.
"""

import math
import time
from dataclasses import dataclass

import numpy as np

TRACKING_PERIOD = 400        # samples per cycle of the tracking trajectory

# Calibrated by benchmarks/calibrate_latency.py (2026-12-01, x86-64, one core of a
# 2-core machine; seconds per sample): see the module notes.
PI_TYPICAL = {"base": 3.0e-8, "operator": 1.6e-9, "vertex": 2.0e-10, "lag": 4.0e-9}
PI_WORST = {"base": 4.0e-8, "operator": 1.0e-9, "vertex": 1.6e-9, "lag": 4.0e-9}
BW_TYPICAL = {"base": 2.0e-7, "substep": 4.0e-8, "lag": 1.6e-8}
BW_WORST = {"base": 2.0e-7, "substep": 2.0e-7, "lag": 1.6e-8}
# the per-sample input changes the Bouc-Wen estimate assumes (fractions of the range):
# the tracking sine's largest step (a 5-95 % sine of TRACKING_PERIOD samples) and the
# mean distance between two uniform random targets
BW_TRACKING_STEP = 0.9 * math.pi / TRACKING_PERIOD
BW_JUMP = 1.0 / 3.0

# measurement (benchmarks and calibration only)
BLOCK_SECONDS = 1e-3
REPEATS = 3
PROBE_SAMPLES = 8
# a compensator slower than this per sample (a Bouc-Wen model with a sharp shape) is
# measured by the probe alone
SLOW_SECONDS = 1e-3
MIN_SAMPLES, MAX_SAMPLES = 32, 4000


@dataclass(frozen=True)
class Latency:
    """Compensator time per sample, in seconds: along a tracking trajectory (typical)
    and with a random desired displacement every sample (worst case); ``how`` says
    whether it was estimated from the structure or measured."""

    typical: float
    worst: float
    how: str = "estimated"

    def to_dict(self):
        if self.how == "estimated":
            text = ("estimated from the model's structure (operators, envelope vertices, "
                    "creep lags; Bouc-Wen: Runge-Kutta substeps) by a cost model "
                    "calibrated on the C compensators (identify/_latency.py); typical: a "
                    f"sine over 5-95 % of the output range, {TRACKING_PERIOD} samples per "
                    "cycle; worst case: a random desired displacement every sample")
        else:
            text = (f"the model's compensator's run (C): median time per sample of "
                    f"{REPEATS} blocks; typical: a sine over 5-95 % of the output range, "
                    f"{TRACKING_PERIOD} samples per cycle; worst case: a random desired "
                    "displacement every sample")
        return {"typical_us": 1e6 * self.typical, "worst_us": 1e6 * self.worst,
                self.how: text}


def structure(model):
    """The counts the cost model takes: {"operators", "vertices", "lags"} for a PI model,
    {"substeps_typical", "substeps_worst", "lags"} for Bouc-Wen."""
    lags = 0 if model.creep is None else int(model.creep.tau.size)
    if model.family == "bouc-wen":
        from pihyst.model._boucwen import substep

        h = substep(model.beta, model.gamma)
        return {"substeps_typical": math.ceil(BW_TRACKING_STEP / h),
                "substeps_worst": math.ceil(BW_JUMP / h), "lags": lags}
    return {"operators": int(model.n_operators), "vertices": _vertices(model),
            "lags": lags}


def _vertices(model):
    if model.family == "pwl":
        return int(sum(len(x) for x, _ in model.rising) + sum(len(x) for x, _ in
                                                              model.falling))
    per_operator = 4 if model.family == "multislope" else 2   # envelope corners
    return per_operator * int(model.n_operators)


def estimate_latency(model):
    """:class:`Latency` of ``model``'s compensator by the cost model (module notes):
    deterministic, the same for the same model on every machine."""
    s = structure(model)
    if model.family == "bouc-wen":
        def cost(c, m):
            return c["base"] + c["substep"] * m + c["lag"] * s["lags"]
        return Latency(typical=cost(BW_TYPICAL, s["substeps_typical"]),
                       worst=cost(BW_WORST, s["substeps_worst"]))

    def pi_cost(c):
        return (c["base"] + c["operator"] * s["operators"] + c["vertex"] * s["vertices"]
                + c["lag"] * s["lags"])
    return Latency(typical=pi_cost(PI_TYPICAL), worst=pi_cost(PI_WORST))


def _per_sample(comp, desired):
    comp.reset()
    t0 = time.perf_counter()
    comp.run(desired)
    return (time.perf_counter() - t0) / desired.size


def _time(comp, make):
    """Median time per sample of ``make(n)`` blocks of about BLOCK_SECONDS."""
    probe = _per_sample(comp, make(PROBE_SAMPLES))
    if probe > SLOW_SECONDS:
        return probe
    n = int(np.clip(BLOCK_SECONDS / max(probe, 1e-9), MIN_SAMPLES, MAX_SAMPLES))
    return float(np.median([_per_sample(comp, make(n)) for _ in range(REPEATS)]))


def measure_latency(model, seed=0):
    """:class:`Latency` of ``model``'s compensator, timed (``how="measured"``): for
    benchmarks and the cost model's calibration; the fit never decides on it."""
    from pihyst.inverse import compensator_for

    lo, hi = model.input_range
    comp = compensator_for(model)
    # outputs the model reaches after a full cycle: its major loop's ends
    # (without the delay, whose output would still be the held first input)
    y_lo, y_hi = model.replace(delay=0).predict(np.array([lo, hi, lo]))[[0, 1]]
    y_lo, y_hi = min(y_lo, y_hi), max(y_lo, y_hi)
    mid, half = 0.5 * (y_lo + y_hi), 0.45 * (y_hi - y_lo)
    rng = np.random.default_rng(seed)

    def tracking(n):
        return mid - half * np.cos(2 * np.pi * np.arange(n) / TRACKING_PERIOD)

    def jumps(n):
        return rng.uniform(mid - half, mid + half, n)

    return Latency(typical=_time(comp, tracking), worst=_time(comp, jumps), how="measured")
