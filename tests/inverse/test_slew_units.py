"""The slew limit is in V/s everywhere (docs/interfaces.md): converted to a step per sample
at the sample period given, taken from the sample times, or from the model."""

import numpy as np
import pytest

import pihyst
from pihyst.inverse import CompensatorBank

MODEL = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])


def steps(voltage, start=0.0):
    return np.abs(np.diff(np.r_[start, voltage]))


def test_volts_per_second_times_the_sample_period():
    comp = pihyst.Compensator(MODEL, slew_rate=2e4, sample_period=1e-4)
    assert comp.max_step == pytest.approx(2.0) and comp.slew_rate == 2e4
    u = comp.run(np.full(20, 25.0)).voltage
    assert steps(u).max() == pytest.approx(2.0)
    assert u[0] == pytest.approx(2.0)


def test_compensate_takes_the_period_from_the_sample_times():
    t = np.arange(50) * 1e-3
    result = pihyst.compensate(MODEL, np.full(50, 25.0), slew_rate=1e3, t=t)
    assert result.slew_rate == 1e3 and result.max_step == pytest.approx(1.0)
    assert steps(result.voltage).max() == pytest.approx(1.0)
    same = pihyst.compensate(MODEL, np.full(50, 25.0), slew_rate=1e3,
                             sample_period=float(np.diff(t).min()))
    np.testing.assert_array_equal(result.voltage, same.voltage)


def test_the_models_sample_period_or_creep_dt_by_default():
    timed = MODEL.replace(sample_period=1e-3)
    assert pihyst.Compensator(timed, slew_rate=500.0).max_step == pytest.approx(0.5)
    creep = MODEL.replace(creep=pihyst.model.Creep([0.1], [0.05], dt=2e-3))
    assert pihyst.Compensator(creep, slew_rate=500.0).max_step == pytest.approx(1.0)


def test_no_period_no_slew_limit_in_volts_per_sample():
    with pytest.raises(ValueError, match="V/s.*sample_period"):
        pihyst.Compensator(MODEL, slew_rate=5.0)
    with pytest.raises(ValueError, match="sample_period must be a positive"):
        pihyst.Compensator(MODEL, slew_rate=5.0, sample_period=0.0)
    with pytest.raises(ValueError, match="V/s.*sample times t"):
        pihyst.compensate(MODEL, [1.0, 2.0], slew_rate=5.0)


def test_bank_channels_in_volts_per_second():
    bank = CompensatorBank([MODEL, MODEL], slew_rate=[1e4, None], sample_period=1e-4)
    u = bank.step([25.0, 25.0])
    assert u[0] == pytest.approx(1.0) and u[1] > 1.0
