"""Hammerstein (classical PI per input + linear dynamics) against a linear-only model of
the same order, on the CubeSpec fine steering mirror and on a simulated beam with its
54 Hz mode.

1. FSM (fsm-cubespec-piezo-mirror in $PIHYST_DATA or ../shared/data; skipped when absent).
   Data: M. Floren, L. Peri, J. De Maeyer, W. De Munter, D. Vandepitte, J.-P. Noel,
   "Data-driven state-space identification and nonlinearity assessment of the CubeSpec
   Fine Steering Mirror", ISMA-USD 2024 (CC BY 4.0). Per amplitude: fitted on the 6
   training realisations (both periods, from rest), judged on the 3 test realisations'
   second period (steady state); RMS error per output channel and over all three, in um,
   beside the published baselines (linear BLA, 28 states: 0.228 um at 300 mV; nonlinear
   LFR: 0.0866 / 0.169 um at 100 / 300 mV).
2. Simulated beam (make_plant("paper-beam", dynamics=True), creep, noise, quantisation):
   fitted on a 20 s sweep 0.5-60 Hz at 2 kHz, 5-145 V with a slow amplitude envelope;
   judged on sines of 1, 10, 30, 50 Hz over 5-145 V (after the first period), RMS error
   in % of the measured range.

Run: PIHYST_DATA=/path/to/data python benchmarks/bench_fsm.py
"""

import time

import numpy as np

from pihyst.dynamics import fit_hammerstein, fit_linear, predict_linear
from pihyst.io import datasets
from pihyst.sim import make_plant

FSM_DIR = "fsm-cubespec-piezo-mirror"
FSM_ORDER = 16          # na = nb per output
PUBLISHED = {"100mV": {"BLA": None, "LFR": 0.0866}, "300mV": {"BLA": 0.228, "LFR": 0.169}}
PERIOD = 8192


def fsm_records(root, level, part):
    """Realisations as (u, y) with both periods in time order; y in um."""
    u = np.load(root / FSM_DIR / f"u_{level}_{part}.npy")
    y = np.load(root / FSM_DIR / f"y_{level}_{part}.npy") * 1e6
    # axes: (sample in period, channel, realisation, period)
    return [(np.concatenate([u[:, :, r, 0], u[:, :, r, 1]]),
             np.concatenate([y[:, :, r, 0], y[:, :, r, 1]])) for r in range(u.shape[2])]


def fsm(order=FSM_ORDER):
    root = datasets.data_root()
    if root is None or not (root / FSM_DIR).is_dir():
        print(f"FSM data not found ({FSM_DIR} in $PIHYST_DATA or ../shared/data): skipped")
        return
    print(f"FSM, MISO per output, na = nb = {order}; test RMS error (um), 2nd period")
    for level in ("100mV", "300mV"):
        train, test = fsm_records(root, level, "train"), fsm_records(root, level, "test")
        t0 = time.perf_counter()
        a, b = fit_linear(train, order, order)
        t_lin = time.perf_counter() - t0
        t0 = time.perf_counter()
        ham = fit_hammerstein(train, order, order, refinements=2)
        t_ham = time.perf_counter() - t0
        for name, predict, elapsed in (("linear", lambda u: predict_linear(a, b, u), t_lin),
                                       ("hammerstein", ham.predict, t_ham)):
            err = np.vstack([predict(u)[PERIOD:] - y[PERIOD:] for u, y in test])
            per = np.sqrt(np.mean(err ** 2, axis=0))
            pub = PUBLISHED[level]
            ref = ", ".join(f"{k} {v:.3f}" for k, v in pub.items() if v is not None)
            print(f"  {level} {name:<12} ch1 {per[0]:.3f}  ch2 {per[1]:.3f}  ch3 {per[2]:.3f}"
                  f"  all {np.sqrt(np.mean(err ** 2)):.3f} um   (published: {ref})"
                  f"  fit {elapsed:.0f} s")


def beam_sweep(fs=2000.0, duration=20.0, f0=0.5, f1=60.0):
    t = np.arange(0.0, duration, 1 / fs)
    # exponential sweep f0 -> f1, amplitude envelope for minor loops
    phase = 2 * np.pi * f0 * duration / np.log(f1 / f0) * (
        np.exp(t / duration * np.log(f1 / f0)) - 1)
    return t, 75 - 70 * np.cos(phase) * (0.6 + 0.4 * np.cos(2 * np.pi * t / 7))


def beam_sine(f, fs=2000.0):
    t = np.arange(0.0, max(3 / f, 1.0) + 1 / f, 1 / fs)
    return t, 75 - 70 * np.cos(2 * np.pi * f * t)


def beam(orders=((2, 3), (4, 4))):
    t, u = beam_sweep()
    y = make_plant("paper-beam", seed=1, dynamics=True).run(u, t)
    print("\nSimulated beam with its 54 Hz mode: RMS error in % of range on sines")
    for na, nb in orders:
        a, b = fit_linear([(u, y)], na, nb)
        ham = fit_hammerstein([(u, y)], na, nb, n_operators=6, input_range=[(0.0, 150.0)],
                              refinements=2)
        for f in (1, 10, 30, 50):
            ts, us = beam_sine(f)
            ys = make_plant("paper-beam", seed=5, dynamics=True).run(us, ts)
            k = ts >= 1 / f
            span = np.ptp(ys)
            lin = 100 * np.sqrt(np.mean((predict_linear(a, b, us)[k, 0] - ys[k]) ** 2)) / span
            hm = 100 * np.sqrt(np.mean((ham.predict(us)[k, 0] - ys[k]) ** 2)) / span
            print(f"  na {na} nb {nb}  {f:>2} Hz  linear {lin:6.2f} %   hammerstein "
                  f"{hm:6.2f} %")


if __name__ == "__main__":
    print(__doc__.split("\n\n")[0])
    fsm()
    beam()
