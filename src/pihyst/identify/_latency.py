"""Real-time cost of a fitted model: the latency of its exact compensator, measured.

A candidate model runs in a controller as its exact compensator
(:class:`pihyst.Compensator` for a PI model, :class:`pihyst.inverse.BoucWenCompensator`
for Bouc-Wen; both in C), one desired displacement in, one voltage out, every sample. Its
cost per sample depends on the trajectory: following a smooth trajectory the inverse moves
little between samples (**typical**); a desired displacement drawn at random every sample
makes it cross the most operator breakpoints and reversals (**worst case**). Both are
measured here, in blocks of the compensator's ``run`` (the C loop; no Python per sample),
sized to take about ``BLOCK_SECONDS`` each, the median of ``REPEATS`` blocks, so a
candidate costs a few milliseconds to measure and a passing disturbance on the machine
does not count (a compensator slower than ``SLOW_SECONDS`` per sample is timed on the
probe's ``PROBE_SAMPLES`` samples alone).
"""

import time
from dataclasses import dataclass

import numpy as np

from pihyst.inverse import compensator_for

BLOCK_SECONDS = 1e-3
REPEATS = 3
PROBE_SAMPLES = 8
# a compensator slower than this per sample (a Bouc-Wen model with a sharp shape: 0.3 s
# in Python, still milliseconds in C for jumps) is measured by the probe alone
SLOW_SECONDS = 1e-3
MIN_SAMPLES, MAX_SAMPLES = 32, 4000
TRACKING_PERIOD = 400        # samples per cycle of the tracking trajectory


@dataclass(frozen=True)
class Latency:
    """Compensator time per sample, in seconds: along a tracking trajectory (typical)
    and with a random desired displacement every sample (worst case)."""

    typical: float
    worst: float

    def to_dict(self):
        return {"typical_us": 1e6 * self.typical, "worst_us": 1e6 * self.worst,
                "measured": "the model's compensator's run (C): median time per sample of "
                            f"{REPEATS} blocks; typical: a sine over 5-95 % of the output "
                            f"range, {TRACKING_PERIOD} samples per cycle; worst case: a "
                            "random desired displacement every sample"}


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
    """:class:`Latency` of ``model``'s compensator."""
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

    return Latency(typical=_time(comp, tracking), worst=_time(comp, jumps))
