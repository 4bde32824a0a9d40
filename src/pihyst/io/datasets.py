"""Readers for the measured data sets kept next to the repository (not shipped).

The sets live in ``$PIHYST_DATA`` or, in a source checkout, in ``../shared/data``
relative to the repository root; each folder's SOURCE.md documents the columns. These
readers apply what SOURCE.md prescribes and nothing more:

- ``p885``: PI P-885.91 stack (``dbo-pi-p885-micromanipulator/Model_Vi_Do.dat``): input
  column 1 (V, 0-3.6 V at the amplifier), displacement column 5 (um, absolute offset
  included); the sensor lags one sample, so y[k+1] is paired with u[k]. 200 Hz, 1 Hz
  sine, 40 cycles.
- ``p885_test``: the same stack's feedforward test (``Test_Vi_Do_Di.dat``): voltage
  column 1, displacement column 5, lag-corrected the same way, up to the end of the
  stretch without compensation (``P885_TEST_UNCOMPENSATED``: samples 5052-10269,
  amplitude growing to +-20 um, with interior reversals), so that a model run from the
  first sample reaches that stretch in the state the record's history left it in.
- ``smarthysteresis``: piezo actuator, 150 V 1 Hz sine
  (``smarthysteresis-piezo-sine150V1Hz/hysteresis_v_150_1hz.csv``): time column 1,
  displacement column 2 (um), drive voltage column 3 (V, +-150 V); the voltage steps from
  0 to -87 V at t = 3.2572 s, and the first second after the step is dropped.

Both return ``(u, y)`` as float arrays.
"""

import os
from pathlib import Path

import numpy as np

P885_DIR = "dbo-pi-p885-micromanipulator"
SMART_DIR = "smarthysteresis-piezo-sine150V1Hz"
SMART_SETTLE_S = 1.0
P885_TEST_UNCOMPENSATED = (5052, 10269)   # SOURCE.md: no inverse compensation


def data_root():
    """The folder of the measured sets, or None if there is none: ``$PIHYST_DATA`` if set,
    else ``../shared/data`` relative to the repository root of this source checkout."""
    env = os.environ.get("PIHYST_DATA")
    if env:
        return Path(env) if Path(env).is_dir() else None
    repo = Path(__file__).resolve().parents[3]   # src/pihyst/io/datasets.py
    candidate = repo.parent / "shared" / "data"
    return candidate if candidate.is_dir() else None


def p885(root=None):
    """The P-885.91 identification run, lag-corrected: u[k] (V), y[k+1] (um)."""
    root = Path(root) if root is not None else data_root()
    a = np.loadtxt(root / P885_DIR / "Model_Vi_Do.dat")
    # the capacitive sensor lags by one sample: y[k+1] belongs to u[k]
    return a[:-1, 0].copy(), a[1:, 4].copy()


def p885_test(root=None):
    """The P-885.91 feedforward test up to the end of its uncompensated stretch,
    lag-corrected: u[k] (V), y[k+1] (um); the stretch is
    ``u[slice(*P885_TEST_UNCOMPENSATED)]``."""
    root = Path(root) if root is not None else data_root()
    a = np.loadtxt(root / P885_DIR / "Test_Vi_Do_Di.dat")
    end = P885_TEST_UNCOMPENSATED[1]
    return a[:end, 0].copy(), a[1:end + 1, 4].copy()


def smarthysteresis(root=None):
    """The SmartHysteresis 150 V sine, from one second after the voltage step on."""
    root = Path(root) if root is not None else data_root()
    a = np.genfromtxt(root / SMART_DIR / "hysteresis_v_150_1hz.csv", delimiter=",")
    t, y, u = a[:, 1], a[:, 2], a[:, 3]
    step = np.flatnonzero(u != 0)[0]
    start = np.searchsorted(t, t[step] + SMART_SETTLE_S)
    return u[start:].copy(), y[start:].copy()
