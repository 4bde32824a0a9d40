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
def test_a_record_from_the_zero_state_is_fitted_from_it(name, record):
    truth = _truths()[name]                       # operators start at 0
    if record == "decaying":
        u = signals.decaying_triangles(period_s=60.0, dt=0.1)[1]
    else:
        u = signals.triangle(period_s=60.0, n_cycles=2, dt=0.1)[1]
    result = pihyst.fit(u, truth.predict(u))
    data = result.report.to_dict()["data"]
    assert data["initial_state"] == "zero"
    rms = data["initial_state_choice"]["probe_fitted_rms"]
    assert rms["zero"] < 0.8 * rms["cycled"]
    assert "chosen from the record" in str(result.report)
    assert _stair_error(result.model, truth) < 0.002
    assert np.all(np.asarray(result.model.initial_state) == 0)


@pytest.mark.parametrize("name", ["classical", "multislope"])
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
    result = pihyst.fit(u, truth.predict(u), initial_state="cycled")
    data = result.report.to_dict()["data"]
    assert data["initial_state"] == "cycled" and data["initial_state_choice"] is None
