"""pihyst.control: a model and its compensator as python-control systems give pihyst's
own predict and compensate, interconnect (compensator -> model gives the desired
trajectory back), and drive linear dynamics."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from strategies import any_model, random_walk, signals

ct = pytest.importorskip("control", reason="needs python-control: "
                                           "pip install 'pihyst[control]'")

import pihyst  # noqa: E402
from pihyst.control import compensator_state, compensator_system, model_system  # noqa: E402

MULTISLOPE = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
CLASSICAL = pihyst.ClassicalPI([0, 10, 30, 60], [0.3, 0.1, 0.05, 0.02], offset=-1.5)
PWL = pihyst.PiecewiseLinearPI(
    rising=[([0, 150], [0, 150]), ([0, 40, 150], [-20, 10, 100])],
    falling=[([0, 150], [0, 150]), ([0, 60, 150], [10, 50, 130])],
    weights=[0.2, 0.15], input_range=(0, 150))
FAMILIES = {"classical": CLASSICAL, "multislope": MULTISLOPE, "pwl": PWL}


def _respond(system, inputs, x0):
    resp = ct.input_output_response(system, np.arange(len(inputs)), inputs, x0)
    return resp.outputs


@pytest.mark.parametrize("family", FAMILIES)
def test_model_system_is_predict(family):
    model = FAMILIES[family]
    u = np.r_[np.linspace(0, 150, 61), random_walk(300, seed=3)]
    system = model_system(model, dt=0.01)
    assert (system.ninputs, system.noutputs, system.nstates) == (1, 1, model.n_operators)
    assert system.isdtime(strict=True) and system.dt == 0.01
    assert system.state_labels == [f"f[{k}]" for k in range(model.n_operators)]
    resp = ct.input_output_response(system, 0.01 * np.arange(u.size), u,
                                    model.initial_state)
    np.testing.assert_allclose(resp.outputs, model.predict(u), rtol=0, atol=1e-12)
    # the state is the operator state before each sample: f[t-1]
    phi = model.operators(u)
    np.testing.assert_allclose(resp.states[:, 1:], phi[:-1].T, rtol=0, atol=1e-12)


@settings(max_examples=30, deadline=None)
@given(model=any_model(), u=signals(min_size=2, max_size=80), data=st.data())
def test_model_system_is_predict_from_any_state(model, u, data):
    start = data.draw(signals(min_size=1, max_size=10))
    state = model.simulate(start).final_state
    out = _respond(model_system(model), u, state)
    np.testing.assert_allclose(out, model.predict(u, initial_state=state), rtol=0,
                               atol=1e-12)


@pytest.mark.parametrize("family", FAMILIES)
@pytest.mark.parametrize("limits", [{}, {"u_min": 10.0, "u_max": 120.0, "slew_rate": 4.0}])
def test_compensator_system_is_compensate(family, limits):
    model = FAMILIES[family]
    lo, hi = model.predict([0.0])[0], model.predict([150.0])[0]
    t = np.linspace(0, 1, 400)
    desired = lo + (hi - lo) * (0.5 + 0.6 * np.sin(2 * np.pi * 3 * t) * (1 - 0.7 * t))
    system = compensator_system(model, dt=1.0, **limits)   # slew_rate in V/s at dt = 1 s
    assert system.state_labels[-1] == "u_last" and system.nstates == model.n_operators + 1
    x0 = compensator_state(model, u_min=limits.get("u_min"), u_max=limits.get("u_max"))
    ref = pihyst.compensate(model, desired, sample_period=1.0, **limits)
    out = _respond(system, desired, x0)
    np.testing.assert_array_equal(out, ref.voltage)   # the same C steps, bit for bit
    assert ref.n_saturated > 0


@pytest.mark.parametrize("family", FAMILIES)
def test_compensator_then_model_gives_the_desired_trajectory_back(family):
    model = FAMILIES[family]
    u = np.r_[np.linspace(0, 150, 50), random_walk(400, seed=7, step=8.0)]
    desired = model.predict(u)    # reachable: the model's own output
    series = ct.series(compensator_system(model), model_system(model))
    by_name = ct.interconnect([compensator_system(model, name="ff"),
                               model_system(model, name="piezo")],
                              inplist=["ff.desired"], outlist=["piezo.displacement"])
    x0 = [compensator_state(model), model.initial_state]
    for system in (series, by_name):
        out = _respond(system, desired, x0)
        np.testing.assert_allclose(out, desired, rtol=0, atol=1e-9)


def test_a_model_whose_range_excludes_zero_interconnects():
    """Provisional inputs of an interconnection (0 V here) are outside the model's range:
    the iteration settles and the outputs are right."""
    model = pihyst.ClassicalPI([0, 10, 30], [0.3, 0.1, 0.05], input_range=(20, 150),
                               initial_state=[20, 20, 20])
    u = np.r_[np.linspace(20, 150, 40), np.linspace(150, 60, 30), np.linspace(60, 140, 30)]
    desired = model.predict(u)
    series = ct.series(compensator_system(model), model_system(model))
    out = _respond(series, desired, [compensator_state(model), model.initial_state])
    np.testing.assert_allclose(out, desired, rtol=0, atol=1e-9)


def test_compensated_model_through_a_low_pass_is_the_low_pass_of_the_desired():
    """compensator -> model -> linear dynamics: the hysteresis cancels, the dynamics stay."""
    dt = 1e-3
    lowpass = ct.c2d(ct.ss(ct.tf([1], [1 / (2 * np.pi * 54), 1])), dt)
    lowpass = ct.ss(lowpass.A, lowpass.B, lowpass.C, lowpass.D, dt=dt,
                    inputs="displacement", outputs="position", name="beam")
    ff = compensator_system(MULTISLOPE, dt, name="ff")
    piezo = model_system(MULTISLOPE, dt, name="piezo")
    system = ct.interconnect([ff, piezo, lowpass], inplist=["ff.desired"],
                             outlist=["beam.position", "piezo.displacement"])
    t = dt * np.arange(600)
    desired = 20 + 15 * np.sin(2 * np.pi * 5 * t)
    resp = ct.input_output_response(system, t, desired,
                                    [compensator_state(MULTISLOPE), MULTISLOPE.initial_state,
                                     np.zeros(lowpass.nstates)])
    np.testing.assert_allclose(resp.outputs[1], desired, rtol=0, atol=1e-9)
    linear = ct.forced_response(lowpass, t, desired).outputs
    np.testing.assert_allclose(resp.outputs[0], linear, rtol=0, atol=1e-9)
    assert np.max(np.abs(resp.outputs[0] - desired)) > 1.0   # the dynamics did something


def test_an_input_out_of_range_is_an_error_naming_the_time():
    system = model_system(MULTISLOPE, dt=0.5)
    with pytest.raises(pihyst.InputRangeError, match=r"time 1: input 160 is outside"):
        ct.input_output_response(system, np.array([0, 0.5, 1.0, 1.5]), [0, 50, 160, 0])


def test_only_models():
    with pytest.raises(TypeError, match="pihyst model"):
        model_system("model.json")
    with pytest.raises(pihyst.InvalidModelError, match="non-negative"):
        compensator_system(CLASSICAL.replace(weights=[0.3, -0.1, 0.05, 0.02]))


def test_a_delayed_model_is_refused_in_one_line():
    delayed = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028], delay=2)
    for make in (model_system, compensator_system):
        with pytest.raises(pihyst.InvalidModelError, match="input delay of 2 samples") as err:
            make(delayed)
        assert "\n" not in str(err.value)
