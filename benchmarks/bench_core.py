"""Benchmark of the forward model: pihyst's public predict() against a NumPy loop.

For N = 1,000,000 samples and K = 4, 16, 64 operators, classical and multislope:
time of ``model.predict`` (best of several runs), operator updates per second, and the
ratio to a NumPy reference (time-outer loop, operators vectorized) measured in the
same run. The NumPy loop is timed on 100,000 samples and scaled to N (it is linear
in N). Targets (issue 2): K = 16 in <= 8 ms per 1e6 samples (>= 2e9 operator
updates/s), >= 300x the NumPy reference.

Run: python benchmarks/bench_core.py
"""

import time

import numpy as np
from timing import best_time

import pihyst

N = 1_000_000
N_REFERENCE = 100_000
U = 150.0


def numpy_classical(r, w, u):
    # f[t] = max(u[t] - r, min(u[t] + r, f[t-1])),  y[t] = w . f[t]
    f = np.zeros_like(r)
    y = np.empty(u.size)
    for t, v in enumerate(u):
        f = np.maximum(v - r, np.minimum(v + r, f))
        y[t] = w @ f
    return y


def numpy_multislope(r, w, u, a=0.8, b=1.2, h=0.5):
    # R = max(a(u - r), b u - r - (b - 1)U),  F = min(b u, a u + (1 - a)U - (1 - a h) r)
    f = np.zeros_like(r)
    y = np.empty(u.size)
    for t, v in enumerate(u):
        rise = np.maximum(a * (v - r), b * v - r - (b - 1) * U)
        fall = np.minimum(b * v, a * v + (1 - a) * U - (1 - a * h) * r)
        f = np.maximum(rise, np.minimum(fall, f))
        y[t] = w @ f
    return y


def main():
    rng = np.random.default_rng(0)
    # a random walk with many minor loops, reflected into [0, U]
    u = np.abs(np.cumsum(rng.normal(0, 2.0, N)) % (2 * U) - U)
    u = U - u
    print(f"forward model, N = {N:,} samples (NumPy reference timed on {N_REFERENCE:,}, "
          "scaled)")
    print(f"{'family':<11} {'K':>3} {'predict ms':>11} {'updates/s':>11} "
          f"{'NumPy s':>9} {'ratio':>7}  check")
    for family in ("classical", "multislope"):
        for k in (4, 16, 64):
            w = rng.uniform(0, 0.1, k)
            if family == "classical":
                r = np.linspace(0, U, k, endpoint=False)
                model = pihyst.ClassicalPI(r, w)
                ref = numpy_classical
            else:
                r = np.linspace(0, 50, k)
                model = pihyst.MultislopePI(r, w)
                ref = numpy_multislope
            t_fast = best_time(lambda: model.predict(u), 15)
            t0 = time.perf_counter()
            y_ref = ref(r, w, u[:N_REFERENCE])
            t_ref = (time.perf_counter() - t0) * N / N_REFERENCE
            err = np.max(np.abs(model.predict(u[:N_REFERENCE]) - y_ref))
            target = "  (target <= 8 ms, >= 300x)" if k == 16 else ""
            print(f"{family:<11} {k:>3} {t_fast * 1e3:>11.2f} {N * k / t_fast:>11.3g} "
                  f"{t_ref:>9.2f} {t_ref / t_fast:>6.0f}x  max|diff| {err:.1e}{target}")


if __name__ == "__main__":
    main()
