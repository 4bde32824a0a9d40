"""Creep benchmark: the four simulated beams with creep, fitted with and without creep
(pihyst.fit, default choice) on a record, judged on voltage staircases and desired
staircases held 10 s and 60 s per level (docs/theory/creep.md).

Validation: the model's prediction against the beam's response to the voltage staircase.
Tracking: the beam driven by the compensator's voltages for a staircase of desired
displacements (2-95 % of the model's rise). Mean absolute error in % of the range.
Target (the accuracy issue, item 2): within 0.1 % where creep costs up to 0.5 %.
Also times the C creep path against its NumPy twin.

Run: python benchmarks/bench_creep.py [RECORD]   (RECORD: decaying_triangles (default),
triangle, growing_sine)
"""

import sys
import time
import warnings

import numpy as np

import pihyst
from pihyst import _core, _reference
from pihyst.exceptions import PihystWarning
from pihyst.sim import PLANT_NAMES, make_plant, signals


def pct(err, ref):
    return 100.0 * float(np.mean(np.abs(err))) / float(np.ptp(ref))


def accuracy(record):
    print(f"record: {record}; mean absolute error, % of range (without -> with creep)")
    print(f"{'beam':<11} {'hold':>5}  {'validation':>17}  {'tracking':>17}  creep gains")
    for name in (sys.argv[2].split(",") if len(sys.argv) > 2 else PLANT_NAMES):
        beam = make_plant(name, seed=1)
        t, u = getattr(signals, record)()
        y = beam.run(u, t)
        models = (pihyst.fit(u, y).model, pihyst.fit(u, y, t=t, creep=True).model)
        for hold in (10.0, 60.0):
            ts, us = signals.staircase(step_s=hold)
            row = []
            for m in models:
                beam.reset()
                ys = beam.run(us, ts)
                val = pct(m.predict(us, t=ts) - ys, ys)
                rise = m.predict(np.array([0.0, m.input_range[1]]))
                lo = rise[0] + 0.02 * (rise[1] - rise[0])
                hi = rise[0] + 0.95 * (rise[1] - rise[0])
                td, yd = signals.staircase(u_min=lo, u_max=hi, step_s=hold)
                comp = pihyst.compensate(m, yd, t=td)
                beam.reset()
                row.append((val, pct(beam.run(comp.voltage, td) - yd, yd)))
            (v0, k0), (v1, k1) = row
            print(f"{name:<11} {hold:>4.0f}s  {v0:7.3f} -> {v1:6.3f}  {k0:7.3f} -> {k1:6.3f}  "
                  f"sum {models[1].creep.gain.sum():.3f} ({models[1].creep.n_lags} lags)",
                  flush=True)


def speed():
    n, lags = 1_000_000, 9
    rng = np.random.default_rng(0)
    tau = 0.1 * 10 ** (0.5 * np.arange(lags))
    gain = np.full(lags, 0.01)
    h = np.cumsum(rng.normal(0, 0.01, n))
    c = _core.Creep(tau, gain, 1e-3, np.zeros(lags))
    t0 = time.perf_counter()
    c.run(h)
    fast = time.perf_counter() - t0
    dt = np.full(n, 1e-3)
    t0 = time.perf_counter()
    c.run(h, dt)
    fast_dt = time.perf_counter() - t0
    m = 20_000
    r = _reference.Creep(tau, gain, 1e-3, np.zeros(lags))
    t0 = time.perf_counter()
    r.run(h[:m])
    slow = (time.perf_counter() - t0) * n / m
    print(f"\ncreep lags, {lags} lags, 10^6 samples: C fixed interval {1e3 * fast:.1f} ms, "
          f"C per-sample interval {1e3 * fast_dt:.1f} ms, NumPy twin {slow:.1f} s "
          f"(x{slow / fast:.0f}, x{slow / fast_dt:.0f})")


if __name__ == "__main__":
    warnings.simplefilter("ignore", PihystWarning)
    accuracy(sys.argv[1] if len(sys.argv) > 1 else "decaying_triangles")
    speed()
