"""The input delay of a model (pihyst.model._delay): a parameter like the others (==,
JSON, replace), y[k] = P[u](k - d) in predict, simulate and the stepper, checked against
an independent shift of the undelayed model; another sample period converted or refused;
banks refuse delayed models."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import pihyst
from pihyst.exceptions import InvalidArgumentError
from pihyst.inverse import CompensatorBank
from pihyst.model import BoucWenModel, ClassicalPI, ModelBank, PIModel

from strategies import any_model, signals

M = ClassicalPI([0, 10, 30, 150], [0.008, 0.252, 0.019, 0.582])
BW = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
DELAYS = st.integers(0, 6)


def shifted_reference(model, u, d):
    """y[k] = P[u](max(k - d, 0)): the undelayed model's output, shifted by d samples
    and held at its first value (the model run on its own input, then indexed)."""
    y = model.replace(delay=0).predict(u)
    return y[np.maximum(np.arange(u.size) - d, 0)]


# ---------------------------------------------------------------- a parameter
@pytest.mark.parametrize("model", [M, BW], ids=["classical", "bouc-wen"])
def test_delay_is_a_parameter_compared_written_and_read(model):
    d = model.replace(delay=3, sample_period=1e-3)
    assert d.delay == 3 and d.sample_period == 1e-3
    assert d != model and d == model.replace(delay=3, sample_period=0.001)
    assert hash(d) == hash(model.replace(delay=3, sample_period=1e-3))
    assert d != model.replace(delay=3)              # the period is part of it
    data = d.to_dict()
    assert data["delay_samples"] == 3 and data["sample_period_s"] == 1e-3
    back = PIModel.from_dict(json.loads(json.dumps(data)))
    assert back == d and back.delay == 3
    assert "delay=3" in repr(d) and "sample_period=0.001" in repr(d)


@pytest.mark.parametrize("model", [M, BW], ids=["classical", "bouc-wen"])
def test_no_delay_is_omitted_so_old_files_load_unchanged(model):
    data = model.to_dict()
    assert "delay_samples" not in data and "sample_period_s" not in data
    assert "delay" not in repr(model)
    loaded = PIModel.from_dict(data)
    assert loaded == model and loaded.delay == 0 and loaded.sample_period is None


def test_example_model_files_load_without_a_delay():
    for name in ("paper_table1_classical", "paper_table1_multislope"):
        m = pihyst.load_model(f"examples/{name}.json")
        assert m.delay == 0 and m.sample_period is None


@pytest.mark.parametrize("kw, match", [
    ({"delay": -1}, "delay must be a whole number"),
    ({"delay": 1.5}, "delay must be a whole number"),
    ({"delay": True}, "delay must be a whole number"),
    ({"delay": "3"}, "delay must be a whole number"),
    ({"delay": float("nan")}, "delay must be a whole number"),
    ({"sample_period": 0.0}, "sample_period must be a finite number of seconds > 0"),
    ({"sample_period": -1e-3}, "sample_period must be a finite"),
    ({"sample_period": float("inf")}, "sample_period must be a finite"),
    ({"sample_period": "1ms"}, "sample_period must be a number"),
])
@pytest.mark.parametrize("model", [M, BW], ids=["classical", "bouc-wen"])
def test_bad_delays_are_refused_in_one_line(model, kw, match):
    with pytest.raises(pihyst.InvalidModelError, match=match) as err:
        model.replace(**kw)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("key, value, says", [
    ("delay_samples", -2, "m.json: delay_samples must be a whole number"),
    ("delay_samples", 2_000_000, "m.json: delay_samples = 2e\\+06 is more than the 1,000,000"),
    ("sample_period_s", 0, "m.json: sample_period_s must be a finite number of seconds > 0"),
])
@pytest.mark.parametrize("model", [M, BW], ids=["classical", "bouc-wen"])
def test_a_bad_delay_in_a_file_names_the_file_and_key(model, key, value, says):
    data = {**model.to_dict(), "delay_samples": 1, key: value}
    with pytest.raises(pihyst.InvalidModelError, match=says):
        PIModel.from_dict(data, "m.json")


def test_a_whole_float_delay_is_accepted():
    assert M.replace(delay=2.0).delay == 2 and isinstance(M.replace(delay=2.0).delay, int)


# ---------------------------------------------------------------- runs
@settings(max_examples=60, deadline=None)
@given(any_model(), signals(max_size=120), DELAYS)
def test_predict_is_the_undelayed_output_shifted(model, u, d):
    delayed = model.replace(delay=d)
    np.testing.assert_array_equal(delayed.predict(u), shifted_reference(model, u, d))


@settings(max_examples=40, deadline=None)
@given(any_model(), signals(max_size=80), DELAYS, st.data())
def test_stepper_and_chunks_equal_the_whole_run(model, u, d, data):
    delayed = model.replace(delay=d)
    whole = delayed.predict(u)
    s = delayed.stepper()
    np.testing.assert_array_equal([s.step(x) for x in u], whole)
    s.reset()                                         # the FIFO restarts too
    np.testing.assert_array_equal([s.step(x) for x in u], whole)
    cut = data.draw(st.integers(0, u.size))
    first = delayed.simulate(u[:cut])
    second = delayed.simulate(u[cut:], initial_state=first.final_state,
                              pending_input=first.pending_input)
    np.testing.assert_array_equal(np.r_[first.output, second.output], whole)


def test_pending_input_says_what_the_output_has_not_shown():
    d = M.replace(delay=3)
    u = np.array([10.0, 20.0, 30.0, 40.0, 50.0])
    r = d.simulate(u)
    np.testing.assert_array_equal(r.pending_input, [30.0, 40.0, 50.0])
    np.testing.assert_array_equal(r.final_state, M.simulate(u[:2]).final_state)
    short = d.simulate(u[:1], pending_input=[5.0, 6.0, 7.0])
    np.testing.assert_array_equal(short.pending_input, [6.0, 7.0, 10.0])
    np.testing.assert_array_equal(short.output, M.predict([5.0]))
    assert M.simulate(u).pending_input is None
    with pytest.raises(InvalidArgumentError, match="pending_input must have 3 values"):
        d.predict(u, pending_input=[1.0])
    with pytest.raises(pihyst.InputRangeError):
        d.predict(u, pending_input=[1.0, 2.0, 999.0])


def test_a_stepper_with_given_pending_inputs_applies_them_first():
    s = M.replace(delay=2).stepper(pending_input=[40.0, 80.0])
    out = [s.step(x) for x in (0.0, 0.0, 0.0)]
    np.testing.assert_array_equal(out, M.predict([40.0, 80.0, 0.0]))
    np.testing.assert_array_equal(s.pending_input, [0.0, 0.0])


def test_a_model_with_creep_delays_its_input():
    creep = pihyst.model.Creep([0.1, 1.0], [0.02, 0.03], dt=0.01)
    m = M.replace(creep=creep)
    u = np.r_[np.linspace(0, 150, 40), np.full(30, 150.0), np.linspace(150, 20, 40)]
    d = 4
    # the definition: the undelayed model run on u delayed by d, u[0] held before
    reference = m.predict(np.r_[np.full(d, u[0]), u[:-d]])
    delayed = m.replace(delay=d)
    np.testing.assert_allclose(delayed.predict(u), reference, rtol=0, atol=1e-12)
    s = delayed.stepper()
    np.testing.assert_allclose([s.step(x) for x in u], reference, rtol=0, atol=1e-12)


@settings(max_examples=15, deadline=None)
@given(signals(max_size=60), DELAYS)
def test_bouc_wen_predict_and_stepper_shift_too(u, d):
    delayed = BW.replace(delay=d)
    np.testing.assert_allclose(delayed.predict(u), shifted_reference(BW, u, d), rtol=0,
                               atol=1e-12)
    s = delayed.stepper()
    np.testing.assert_allclose([s.step(x) for x in u], delayed.predict(u), rtol=0, atol=1e-9)


# ---------------------------------------------------------------- sample periods
def test_the_delay_converts_to_another_period_when_exact():
    m = M.replace(delay=3, sample_period=1e-3)
    assert m.delay_at(1e-3) == 3 and m.delay_at(5e-4) == 6 and m.delay_at(3e-3) == 1
    assert m.delay_at(t=np.arange(10) * 2.5e-4) == 12
    assert M.replace(delay=3).delay_at(7e-4) == 3            # period unknown: as it is
    assert M.delay_at(7e-4) == 0


@pytest.mark.parametrize("model", [M, BW], ids=["classical", "bouc-wen"])
def test_another_sample_rate_is_refused_in_one_line(model):
    m = model.replace(delay=3, sample_period=1e-3)
    u = np.linspace(0, 150, 50)
    with pytest.raises(InvalidArgumentError, match=r"delay of 3 samples at 0.001 s .* not "
                       r"a whole number of samples at 0.0007 s") as err:
        m.predict(u, t=np.arange(50) * 7e-4)
    assert "\n" not in str(err.value)
    with pytest.raises(InvalidArgumentError, match="not uniform"):
        m.predict(u, t=np.cumsum(np.r_[0, np.tile([1e-3, 2e-3], 25)[:49]]))
    with pytest.raises(InvalidArgumentError, match="not a whole number"):
        m.stepper(sample_period=2e-3)


def test_a_prediction_at_half_the_period_doubles_the_delay():
    m = M.replace(delay=3, sample_period=1e-3)
    u = np.linspace(0, 150, 60)
    np.testing.assert_array_equal(m.predict(u, t=np.arange(60) * 5e-4),
                                  shifted_reference(M, u, 6))
    s = m.stepper(sample_period=5e-4)
    assert s.delay == 6
    np.testing.assert_array_equal([s.step(x) for x in u], shifted_reference(M, u, 6))


# ---------------------------------------------------------------- banks
def test_banks_refuse_delayed_models():
    with pytest.raises(pihyst.InvalidModelError, match=r"models\[1\] has an input delay of "
                       r"2 samples: a bank does not delay its channels"):
        ModelBank([M, M.replace(delay=2)])
    with pytest.raises(pihyst.InvalidModelError, match=r"models\[0\] has an input delay"):
        CompensatorBank([M.replace(delay=1)])
    ModelBank([M, M.replace(sample_period=1e-3)])       # a period alone is no delay
