"""The CubeSpec fine steering mirror (slow; skipped without the data).

Data: M. Floren, L. Peri, J. De Maeyer, W. De Munter, D. Vandepitte, J.-P. Noel,
"Data-driven state-space identification and nonlinearity assessment of the CubeSpec Fine
Steering Mirror", ISMA-USD 2024 (CC BY 4.0, (c) 2025 M. Floren, KU Leuven); not copied
into the repository.
"""

import numpy as np
import pytest

from pihyst.dynamics import fit_scheduled_state_space, fit_state_space
from pihyst.io import datasets

PERIOD = 8192
PUBLISHED_BLA_300MV = 0.228      # um, the authors' 28-state linear model, test RMS
#: um, the authors' single nonlinear LFR for all levels (trained on all three), test RMSE
PUBLISHED_NL_LFR = {"100mV": 0.0866, "200mV": 0.131, "300mV": 0.169}
PUBLISHED_BLA_ALL_200MV = 0.179  # um, their single linear model of all levels, at 200 mV
INIT_WINDOW = 100                # samples of each period the benchmark leaves out


def records(level, part):
    root = datasets.data_root()
    folder = None if root is None else root / "fsm-cubespec-piezo-mirror"
    if folder is None or not folder.is_dir():
        pytest.skip("FSM data not found (set PIHYST_DATA)")

    u = np.load(folder / f"u_{level}_{part}.npy")
    y = np.load(folder / f"y_{level}_{part}.npy") * 1e6
    # axes: (sample in period, channel, realisation, period)
    return [(np.concatenate([u[:, :, r, 0], u[:, :, r, 1]]),
             np.concatenate([y[:, :, r, 0], y[:, :, r, 1]])) for r in range(u.shape[2])]


@pytest.mark.slow
def test_the_state_space_model_beats_the_published_linear_baseline_at_300mv():
    train, test = records("300mV", "train"), records("300mV", "test")
    model = fit_state_space(train, PERIOD)           # order chosen by validation
    assert model.spectral_radius < 1
    err = np.vstack([model.predict(u)[PERIOD:] - y[PERIOD:] for u, y in test])
    assert np.sqrt(np.mean(err ** 2)) <= PUBLISHED_BLA_300MV


def benchmark_rmse(model, test):
    """The benchmark's test RMSE: steady state, RMS per output, realisation and period
    after each period's first INIT_WINDOW samples, averaged."""
    rms = []
    for u, y in test:
        e = model.predict(np.r_[u[-PERIOD:], u])[PERIOD:] - y
        rms.append(np.sqrt(np.mean(e.reshape(-1, PERIOD, 3)[:, INIT_WINDOW:] ** 2, axis=1)))
    return float(np.mean(rms))


@pytest.mark.heavy          # 6.5 min on the 2-core machine: make test-heavy, not in CI
def test_one_scheduled_model_beats_the_published_nonlinear_lfr_at_the_fitted_levels():
    """Fitted on 100 and 300 mV together: below the published NL-LFR there. 200 mV (not
    fitted; judged when present): below the published linear model of all levels, NOT
    below the NL-LFR (0.156 against 0.131 um, docs/theory/hammerstein.md)."""
    low, high = records("100mV", "train"), records("300mV", "train")
    common = fit_state_space(low + high, PERIOD, order=40, discard=0)
    model = fit_scheduled_state_space([low, high], PERIOD, linear=common, window=1024,
                                      discard=0)
    folder = datasets.data_root() / "fsm-cubespec-piezo-mirror"
    for level in ("100mV", "300mV"):
        assert benchmark_rmse(model, records(level, "test")) < PUBLISHED_NL_LFR[level]
    if (folder / "u_200mV_test.npy").is_file():     # not in the project's copy
        assert benchmark_rmse(model, records("200mV", "test")) < PUBLISHED_BLA_ALL_200MV
