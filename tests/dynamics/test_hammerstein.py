"""Hammerstein models: hysteresis then linear dynamics, against linear-only fits."""

import numpy as np
import pytest
from scipy.signal import lfilter

from pihyst.dynamics import fit_hammerstein, fit_linear, predict_linear
from pihyst.dynamics._linear import stabilized
from pihyst.io import datasets
from pihyst.model import ClassicalPI


def test_stabilized_reflects_unstable_poles():
    a = np.poly([1.25, 0.5])
    s = stabilized(a)
    assert np.allclose(sorted(np.abs(np.roots(s))), [0.5, 0.8])


def test_fits_a_noise_free_hammerstein_better_than_linear():
    rng = np.random.default_rng(0)
    n = 6000
    u = 75 + 60 * np.sin(np.cumsum(rng.uniform(0.002, 0.05, n))) * \
        np.abs(np.sin(np.arange(n) / 900))
    H = ClassicalPI([0, 15, 30, 45], [0.3, 0.25, 0.15, 0.1], input_range=(0.0, 150.0))
    h = H.predict(u, initial_state=np.zeros(4))
    r, theta = 0.97, 0.2           # a lightly damped mode
    a = np.poly([r * np.exp(1j * theta), r * np.exp(-1j * theta)]).real
    b = np.array([0.0, 0.5, 0.4]) * a.sum() / 0.9
    y = lfilter(b, a, h)
    lin = fit_linear([(u, y)], 2, 3)
    ham = fit_hammerstein([(u, y)], 2, 3, thresholds=[[0, 15, 30, 45]],
                          input_range=[(0.0, 150.0)])
    e_lin = np.sqrt(np.mean((predict_linear(*lin, u)[:, 0] - y) ** 2))
    e_ham = np.sqrt(np.mean((ham.predict(u)[:, 0] - y) ** 2))
    # the alternating fit improves on the linear model it starts from, but stalls short
    # of the true weights (docs/theory/hammerstein.md: a joint output-error refinement is
    # missing), so this checks the improvement, not the recovery
    assert e_ham < 0.8 * e_lin
    assert np.all(ham.hysteresis[0].weights >= 0)


def _sweep(fs, f0, f1, amplitude, envelope, seed, duration=20.0):
    from pihyst.sim import make_plant
    t = np.arange(0, duration, 1 / fs)
    phase = 2 * np.pi * f0 * duration / np.log(f1 / f0) * (
        np.exp(t / duration * np.log(f1 / f0)) - 1)
    env = 0.6 + 0.4 * np.cos(2 * np.pi * t / 7) if envelope else 1.0
    u = 75 - amplitude * np.cos(phase) * env
    u = np.r_[np.linspace(0.0, u[0], int(2 * fs), endpoint=False), u]
    t = np.arange(u.size) / fs
    return u, make_plant("paper-beam", seed=seed, dynamics=True).run(u, t)


@pytest.mark.slow
def test_hammerstein_beats_linear_of_the_same_order_on_the_beam():
    # the protocol of benchmarks/bench_fsm.py: a large slow sweep and a small fast one
    from pihyst.sim import make_plant
    fs = 2000.0
    recs = [_sweep(fs, 0.5, 20.0, 70.0, True, 1), _sweep(fs, 10.0, 100.0, 8.0, False, 2)]
    lin = fit_linear(recs, 2, 3)
    ham = fit_hammerstein(recs, 2, 3, n_operators=6, input_range=[(0.0, 150.0)],
                          refinements=3)
    e_lin, e_ham = [], []
    for f in (1, 10, 30):
        ts = np.arange(0, max(3 / f, 1.0) + 1 / f, 1 / fs)
        us = 75 - 70 * np.cos(2 * np.pi * f * ts)
        ys = make_plant("paper-beam", seed=5, dynamics=True).run(us, ts)
        k = ts >= 1 / f
        e_lin.append(np.sqrt(np.mean((predict_linear(*lin, us)[k, 0] - ys[k]) ** 2)))
        e_ham.append(np.sqrt(np.mean((ham.predict(us)[k, 0] - ys[k]) ** 2)))
    assert np.mean(e_ham) < np.mean(e_lin)


@pytest.mark.slow
def test_hammerstein_beats_linear_of_the_same_order_on_the_fsm():
    root = datasets.data_root()
    folder = None if root is None else root / "fsm-cubespec-piezo-mirror"
    if folder is None or not folder.is_dir():
        pytest.skip("FSM data not found (set PIHYST_DATA)")

    def records(part):
        u = np.load(folder / f"u_300mV_{part}.npy")
        y = np.load(folder / f"y_300mV_{part}.npy") * 1e6
        return [(np.concatenate([u[:, :, r, 0], u[:, :, r, 1]]),
                 np.concatenate([y[:, :, r, 0], y[:, :, r, 1]])) for r in range(u.shape[2])]

    train, test = records("train"), records("test")
    order = 8
    lin = fit_linear(train, order, order, period=8192)
    ham = fit_hammerstein(train, order, order, period=8192, refinements=2)
    e_lin = np.vstack([predict_linear(*lin, u)[8192:] - y[8192:] for u, y in test])
    e_ham = np.vstack([ham.predict(u)[8192:] - y[8192:] for u, y in test])
    assert np.sqrt(np.mean(e_ham ** 2)) < np.sqrt(np.mean(e_lin ** 2))
