"""``initial_state="auto"`` on a record that starts at the bottom of its range: at rest
after a full cycle, or from the zero state, whichever the record shows
(identify/_start_state.py, docs/theory/identification.md)."""

import numpy as np
import pytest

import pihyst
from pihyst.identify import cycled_state
from pihyst.model import ClassicalPI, MultislopePI
from pihyst.sim import signals

STAIRS = signals.staircase(step_s=40.0, dt=0.1)[1]


def _truths():
    return {"classical": ClassicalPI([0.0, 10.0, 25.0, 45.0], [0.15, 0.06, 0.04, 0.03]),
            "wide classical": ClassicalPI([0.0, 5.0, 20.0, 40.0, 60.0],
                                          [0.1, 0.08, 0.05, 0.05, 0.04]),
            # its operators return to 0 at the bottom: its zero state is its rest state
            "multislope": MultislopePI([0.0, 12.0, 30.0, 45.0], [0.2, 0.05, 0.05, 0.02])}


def _stair_error(model, truth):
    y = truth.predict(STAIRS)
    return float(np.mean(np.abs(model.predict(STAIRS) - y)) / np.ptp(y))


@pytest.mark.parametrize("name", ["classical", "wide classical"])
@pytest.mark.parametrize("record", ["decaying", "triangle"])
@pytest.mark.parametrize("noise", [0.0, 0.005])
def test_a_record_from_the_zero_state_is_fitted_from_it(name, record, noise):
    truth = _truths()[name]                       # operators start at 0
    if record == "decaying":
        u = signals.decaying_triangles(period_s=60.0, dt=0.1)[1]
    else:
        u = signals.triangle(period_s=60.0, n_cycles=2, dt=0.1)[1]
    y = truth.predict(u)
    y = y + noise * np.ptp(y) * np.random.default_rng(0).normal(size=y.size)
    result = pihyst.fit(u, y)
    data = result.report.to_dict()["data"]
    assert data["initial_state"] == "zero"
    rms = data["initial_state_choice"]["probe_fitted_rms"]
    assert set(rms) == {"cycled", "zero"} and rms["zero"] < 0.5 * rms["cycled"]
    assert _stair_error(result.model, truth) < (0.002 if noise == 0 else 0.005)
    assert np.all(np.asarray(result.model.initial_state) == 0)


# the start-state probe is a classical PI whatever the actuator: the multislope truth
# is the same decision on another loop shape (18 s on a loaded machine)
@pytest.mark.parametrize("name", ["classical",
                                  pytest.param("multislope", marks=pytest.mark.slow)])
def test_a_record_at_rest_stays_cycled(name):
    zero = _truths()[name]
    truth = zero.replace(initial_state=cycled_state(zero, 150.0))
    u = signals.decaying_triangles(period_s=60.0, dt=0.1)[1]
    result = pihyst.fit(u, truth.predict(u))
    assert result.report.to_dict()["data"]["initial_state"] == "cycled"
    assert _stair_error(result.model, truth) < 0.002


def test_a_given_state_is_not_second_guessed():
    truth = _truths()["classical"]
    u = signals.decaying_triangles(period_s=60.0, dt=0.1)[1]
    # decided before any family is fitted: one family shows it (every family took 18 s)
    result = pihyst.fit(u, truth.predict(u), initial_state="cycled", family="classical")
    data = result.report.to_dict()["data"]
    assert data["initial_state"] == "cycled" and data["initial_state_choice"] is None


def _plays_from_zero(u, r, w):
    """A user's classical PI: play operators initialised at 0 (not pihyst's code)."""
    f = np.zeros(len(r))
    out = np.empty(len(u))
    for k, uk in enumerate(u):
        f = np.maximum(uk - r, np.minimum(uk + r, f))
        out[k] = w @ f
    return out


def _sine_growing_from(mid, amplitude, n=3000, cycles=6):
    k = np.arange(n)
    return mid - amplitude * (k / (n - 1)) * np.cos(2 * np.pi * cycles * k / n)


@pytest.mark.parametrize("lo, hi", [(0.0, 150.0), (-100.0, 100.0)])
def test_a_sine_growing_from_mid_range_is_fitted_whole(lo, hi):
    # the first full sweep of the range comes at the very end: "settle" left 21 samples
    # to fit (a one-operator model, 3-19 % of range off); the record is fitted whole from
    # the start state the probe fits best
    r = np.array([0.0, 10.0, 25.0, 45.0, 60.0]) * (hi - lo) / 150
    w = np.array([0.3, 0.1, 0.08, 0.05, 0.04])
    u = _sine_growing_from((lo + hi) / 2, (hi - lo) / 2)
    y = _plays_from_zero(u, r, w)
    result = pihyst.fit(u, y, family="classical", input_range=(lo, hi))
    data = result.report.to_dict()["data"]
    assert data["initial_state"] == "zero"
    rms = data["initial_state_choice"]["probe_fitted_rms"]
    assert set(rms) == {"rise", "fall", "zero"} and rms["zero"] == min(rms.values())
    assert data["settle_samples"] == 0            # fitted whole, not from a settling sweep
    assert result.model.n_operators >= 3
    # other signals, both started by a full cycle (which wipes out either start state)
    rng = np.random.default_rng(0)
    levels = np.r_[lo, hi, lo, rng.uniform(lo, hi, 12)]
    test = np.interp(np.linspace(0, levels.size - 1, 3000), np.arange(levels.size), levels)
    truth = _plays_from_zero(test, r, w)
    err = result.model.predict(test) - truth
    err = err[1000:] - np.mean(err[1000:])
    assert np.mean(np.abs(err)) < 0.002 * np.ptp(truth)


def test_a_record_that_never_reaches_the_ends_of_a_given_range():
    # input_range wider than the record: "settle" never completes (was an IndexError)
    r = np.array([0.0, 10.0, 25.0])
    u = _sine_growing_from(75.0, 60.0)
    y = _plays_from_zero(u, r, np.array([0.3, 0.1, 0.1]))
    result = pihyst.fit(u, y, family="classical", input_range=(0.0, 150.0))
    assert result.report.to_dict()["data"]["initial_state"] in ("rise", "fall", "zero")
    with pytest.raises(pihyst.FitError, match="only 0 samples remain"):
        pihyst.fit(u, y, family="classical", input_range=(0.0, 150.0), initial_state="settle")
