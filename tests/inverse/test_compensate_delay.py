"""Compensation of a delayed model: pihyst.compensate previews the trajectory (v[k] =
P^-1[y_d](k + d), the last d voltages held), so that predict(compensate(y_d)) == y_d on
samples d..; the limits still hold for any input; block by block (PreviewRun) equals
whole; the streaming Compensator takes the target d samples ahead; the rig's programs
preview it while the PID compares with the present target."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pihyst
from pihyst import Compensator, compensate
from pihyst.inverse import PreviewRun
from pihyst.model import BoucWenModel, Creep
from pihyst.rig._programs import FeedbackProgram, FeedforwardProgram

from strategies import U, classical_models, multislope_models, pwl_models

SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])
PAPER_MULTISLOPE = pihyst.load_model("examples/paper_table1_multislope.json")
MODELS = st.one_of(classical_models(), multislope_models(), pwl_models())
DELAYS = st.integers(1, 6)


@st.composite
def voltage_walks(draw, lo=0.0, hi=U):
    n = draw(st.integers(1, 100))
    return np.array(draw(st.lists(st.one_of(st.floats(lo, hi), st.sampled_from([lo, hi])),
                                  min_size=n, max_size=n)))


def conditioning(model):
    if model.family != "pwl":
        steep = float(np.sum(model.weights) * max(getattr(model, "b", 1.0), 1.0))
    else:
        steep = float(sum(w * max(np.max(np.abs(np.diff(y) / np.diff(x)), initial=0.0)
                                  for x, y in (r, f))
                          for w, r, f in zip(model.weights, model.rising, model.falling)))
    return 1e-9 + 64 * np.finfo(float).eps * steep * U


@SETTINGS
@given(MODELS, voltage_walks(), DELAYS)
def test_round_trip_on_samples_d_onwards(model, u, d):
    y_d = model.predict(np.r_[0.0, u])[1:]          # reachable from the start at 0 V
    delayed = model.replace(delay=d)
    result = compensate(delayed, y_d)
    n = y_d.size
    assert result.voltage.size == n and result.displacement.size == n
    # the delayed model's own prediction for the voltages, from where the run started
    # (the initial voltage held before it)
    predicted = delayed.predict(result.voltage, initial_state=result.initial_state,
                                pending_input=np.full(d, result.initial_voltage))
    np.testing.assert_array_equal(result.displacement, predicted)
    np.testing.assert_allclose(predicted[d:], y_d[d:], rtol=0, atol=conditioning(model))
    # preview: voltage k is the undelayed compensator's for desired k + d; the last d hold
    plain = compensate(model, y_d[d:])
    np.testing.assert_array_equal(result.voltage[:max(n - d, 0)], plain.voltage)
    held = result.voltage[max(n - d - 1, 0):]
    assert np.all(held == held[0])
    assert not result.flags[:d].any()


@SETTINGS
@given(st.sampled_from([PAPER_MULTISLOPE, pihyst.ClassicalPI([0, 20, 50], [0.3, 0.2, 0.1])]),
       st.lists(st.one_of(st.floats(-1e6, 1e6), st.just(np.nan), st.just(np.inf)),
                min_size=1, max_size=60),
       DELAYS, st.floats(1.0, 50.0), st.one_of(st.none(), st.floats(0.5, 20.0)))
def test_limits_and_slew_hold_for_any_input(model, desired, d, lo, slew):
    hi = lo + 60.0
    result = compensate(model.replace(delay=d), desired, u_min=lo, u_max=hi, slew_rate=slew,
                        sample_period=1.0)
    v = result.voltage
    assert np.all((v >= lo) & (v <= hi))
    if slew is not None:
        steps = np.abs(np.diff(np.r_[result.initial_voltage, v]))
        assert np.all(steps <= slew * (1 + 1e-12))


@SETTINGS
@given(st.sampled_from([PAPER_MULTISLOPE]), voltage_walks(), DELAYS, st.data())
def test_block_by_block_equals_whole(model, u, d, data):
    y_d = model.predict(u)
    delayed = model.replace(delay=d)
    whole = compensate(delayed, y_d)
    cuts = sorted(data.draw(st.lists(st.integers(0, y_d.size), max_size=4)))
    run = PreviewRun(Compensator(delayed), d)
    parts = [run.feed(y_d[a:b]) for a, b in zip([0, *cuts], [*cuts, y_d.size])]
    parts.append(run.feed([], last=True))
    for name in ("desired", "voltage", "displacement", "flags", "saturated"):
        np.testing.assert_array_equal(np.concatenate([getattr(p, name) for p in parts]),
                                      getattr(whole, name))


def test_the_streaming_compensator_takes_the_target_d_ahead():
    d = 3
    delayed = PAPER_MULTISLOPE.replace(delay=d)
    y_d = PAPER_MULTISLOPE.predict(np.r_[np.linspace(0, 150, 40), np.linspace(150, 30, 30)])
    comp = Compensator(delayed)
    assert comp.delay == d
    v = [comp.step(y_d[k + d]) for k in range(y_d.size - d)]
    np.testing.assert_array_equal(v, compensate(delayed, y_d).voltage[:-d])


def test_a_trajectory_shorter_than_the_delay_holds_the_initial_voltage():
    r = compensate(PAPER_MULTISLOPE.replace(delay=5), [1.0, 2.0], initial_voltage=10.0)
    np.testing.assert_array_equal(r.voltage, [10.0, 10.0])
    assert r.final_voltage == 10.0 and not r.flags.any()


def test_a_model_with_creep_and_a_delay_round_trips_at_its_sample_times():
    d = 2
    m = PAPER_MULTISLOPE.replace(creep=Creep([0.1, 1.0], [0.02, 0.03], dt=0.01), delay=d,
                                 sample_period=0.01)
    t = np.arange(80) * 0.01
    y_d = 5 + 4 * np.sin(np.linspace(0, 6, 80))
    r = compensate(m, y_d, t=t)
    predicted = m.predict(r.voltage, t=t, initial_state=r.initial_state,
                          pending_input=np.zeros(d))
    np.testing.assert_allclose(predicted[d:], y_d[d:], rtol=0, atol=1e-9)
    np.testing.assert_allclose(r.displacement, predicted, rtol=0, atol=1e-12)
    # at half the period the delay is 4 samples
    t2 = np.arange(80) * 0.005
    r2 = compensate(m, y_d, t=t2)
    predicted = m.predict(r2.voltage, t=t2, initial_state=r2.initial_state,
                          pending_input=np.zeros(4))
    np.testing.assert_allclose(predicted[4:], y_d[4:], rtol=0, atol=1e-9)
    with pytest.raises(pihyst.exceptions.InvalidArgumentError, match="not a whole number"):
        compensate(m, y_d, t=np.arange(80) * 0.003)


def test_bouc_wen_compensation_previews_too():
    d = 2
    bw = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0, delay=d)
    y_d = bw.replace(delay=0).predict(np.r_[0.0, np.linspace(0, 150, 30),
                                            np.linspace(150, 40, 20)])[1:]
    r = compensate(bw, y_d)
    predicted = bw.predict(r.voltage, initial_state=r.initial_state,
                           pending_input=np.zeros(d))
    np.testing.assert_allclose(predicted[d:], y_d[d:], rtol=0, atol=1e-7)
    assert pihyst.inverse.BoucWenCompensator(bw).delay == d


def test_the_analytic_inverse_is_not_the_compensator_of_a_delayed_model():
    # the voltages of a delayed model need preview: compensate() does it
    m = pihyst.ClassicalPI([0, 20, 50], [0.3, 0.2, 0.1], delay=2)
    y_d = m.replace(delay=0).predict(np.linspace(0, 150, 20))
    np.testing.assert_allclose(m.predict(compensate(m, y_d).voltage)[2:], y_d[2:], atol=1e-9)


# ---------------------------------------------------------------- the rig's programs
def _ticks(program, measured=None):
    program.initial_voltage()
    program.start()
    return np.array([program.command(k, None if measured is None else measured[k])[1]
                     for k in range(program.n_ticks)])


def test_feedforward_program_previews_a_delayed_model():
    d = 3
    delayed = PAPER_MULTISLOPE.replace(delay=d)
    desired = PAPER_MULTISLOPE.predict(np.r_[np.linspace(0, 120, 30), np.linspace(120, 20, 25)])
    program = FeedforwardProgram(delayed, desired, 0.0, 150.0)
    volts = _ticks(program)
    comp = Compensator(delayed)
    comp.reset(*program._start)
    expected = PreviewRun(comp, d).feed(desired, last=True).voltage
    np.testing.assert_array_equal(volts, expected)
    refs = [program.command(k, None)[0] for k in range(3)]
    assert refs == list(desired[:3])                  # the reference is the present one


def test_feedback_compares_the_measurement_with_the_present_target():
    # a measurement equal to the present target: no correction, the feedforward only
    d = 2
    delayed = PAPER_MULTISLOPE.replace(delay=d)
    desired = PAPER_MULTISLOPE.predict(np.r_[np.linspace(0, 120, 30), np.linspace(120, 20, 25)])
    ff = _ticks(FeedforwardProgram(delayed, desired, 0.0, 150.0))
    fb = _ticks(FeedbackProgram(delayed, desired, 0.0, 150.0, dt=1e-3, kp=0.5, ki=10.0),
                measured=desired)
    np.testing.assert_array_equal(fb, ff)
