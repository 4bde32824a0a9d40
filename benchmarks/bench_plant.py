"""Speed of the simulated beams (samples per second), against a NumPy reference.

The reference is the textbook discretised Preisach model: a grid of relays updated with
vectorised NumPy for every sample. pihyst's plant evaluates the same kind of model
exactly through its reversal stack, vectorised along monotone runs.

Run: python benchmarks/bench_plant.py
"""

import time

import numpy as np

from pihyst.sim import PLANT_NAMES, make_plant
from pihyst.sim.signals import random_ramps, triangle


def rate(fn, n_samples, repeat=3):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return n_samples / best


def relay_grid_reference(u, n=60):
    """Per-sample NumPy relay grid (n x n plane): y = sum of mu over the relays that are on."""
    g = (np.arange(n) + 0.5) / n
    alpha, beta = np.meshgrid(g, g, indexing="ij")
    keep = alpha >= beta
    alpha, beta = alpha[keep], beta[keep]
    mu = np.exp(-0.75 * alpha + 0.54 * beta) / n ** 2
    on = np.zeros(alpha.size, dtype=bool)
    y = np.empty(u.size)
    for i, x in enumerate(u / 150.0):
        on |= alpha <= x
        on &= beta < x
        y[i] = mu[on].sum()
    return y


def main():
    signals = {
        "triangle 300 s, dt 1 ms": triangle(dt=0.001),
        "random ramps, dt 10 ms": random_ramps(n_ramps=200, dt=0.01, seed=0),
    }
    rng = np.random.default_rng(0)
    walk = np.clip(75 + np.cumsum(rng.normal(0, 1, 100_000)), 0, 150)
    signals["random walk (reversal every ~2 samples)"] = (np.arange(walk.size) * 0.01, walk)

    t_ref, u_ref = signals["random ramps, dt 10 ms"]
    u_ref = u_ref[:5000]
    for n in (300, 60):          # 0.5 V and 2.5 V relay spacing; the last one is the ratio's
        ref = rate(lambda: relay_grid_reference(u_ref, n), u_ref.size, repeat=1)
        print(f"NumPy reference ({n} x {n} relay grid, per-sample update): "
              f"{ref:,.0f} samples/s")
    print(f"{'plant':12s} {'signal':42s} {'samples':>10s} {'samples/s':>12s} {'x ref':>7s}")
    for name in PLANT_NAMES:
        for label, (t, u) in signals.items():
            plant = make_plant(name)

            def go():
                plant.reset()
                plant.run(u, t)
            r = rate(go, u.size)
            print(f"{name:12s} {label:42s} {u.size:10,d} {r:12,.0f} {r / ref:7.0f}")


if __name__ == "__main__":
    main()
