"""Bouc-Wen models with creep (docs/theory/creep.md): the C path (Bouc-Wen core, then the
C lags) equals the Python twin on many models and signals, batch == stepper == chunks,
the step response of the lags in closed form, the output stays non-decreasing in the
voltage at each sample, JSON round trip, values, and one-line errors."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import pihyst
from pihyst.exceptions import InvalidArgumentError, InvalidModelError
from pihyst.model import BoucWenModel, Creep, PIModel


@st.composite
def creeps(draw):
    n = draw(st.integers(1, 6))
    tau = np.sort(10 ** np.array(draw(st.lists(st.floats(-1.5, 3), min_size=n,
                                               max_size=n))))
    share = np.array(draw(st.lists(st.floats(0.01, 1), min_size=n, max_size=n)))
    gain = share / share.sum() * draw(st.floats(0, 0.9))
    return Creep(tau, gain, dt=draw(st.floats(1e-3, 0.5)))


@st.composite
def monotone_models(draw):
    beta = draw(st.floats(0.2, 30))
    gamma = draw(st.floats(-0.9, 0.9)) * beta
    a = draw(st.floats(-15, 15))
    c2 = draw(st.floats(-4, 4))
    d = 2 * beta / (beta + gamma)
    c1 = max(0.0, -2 * c2) - min(a, 0.0) * d + 1e-6 + draw(st.floats(0, 30))
    return BoucWenModel(beta=beta, gamma=gamma, n=draw(st.floats(1, 3)), hysteretic=a,
                        linear=c1, quadratic=c2, offset=draw(st.floats(-5, 5)),
                        creep=draw(creeps()))


def walk(rng, n, lo=0.0, hi=150.0):
    """Ramps, holds and jumps inside [lo, hi]."""
    step = rng.normal(0, 0.03 * (hi - lo), n)
    step[rng.random(n) < 0.3] = 0.0
    step[rng.random(n) < 0.03] *= 30.0
    v = np.cumsum(step) % (2 * (hi - lo))
    return lo + np.where(v > hi - lo, 2 * (hi - lo) - v, v)


def times(rng, n, dt):
    d = dt * rng.uniform(0, 3, n)
    d[rng.random(n) < 0.05] = 0.0
    d[rng.random(n) < 0.02] *= 300.0
    return np.cumsum(d)


@settings(max_examples=40)
@given(model=monotone_models(), seed=st.integers(0, 2**32 - 1), irregular=st.booleans())
def test_c_path_equals_the_twin(model, seed, irregular):
    rng = np.random.default_rng(seed)
    u = walk(rng, 150)
    t = times(rng, 150, model.creep.dt) if irregular else None
    z0 = None if seed % 3 else rng.normal(0, 10, model.creep.n_lags)
    c = model.simulate(u, t=t, creep_state=z0)
    twin = model.twin_simulation(u, t=t, creep_state=z0)
    scale = abs(model.offset) + abs(model.linear) + abs(model.quadratic) + \
        abs(model.hysteretic) * model.z_max + (0 if z0 is None else np.abs(z0).max())
    np.testing.assert_allclose(c.output, twin.output, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(c.final_creep_state, twin.final_creep_state, rtol=0,
                               atol=1e-12 * scale)
    np.testing.assert_array_equal(c.final_state, twin.final_state)


@settings(max_examples=30)
@given(model=monotone_models(), seed=st.integers(0, 2**32 - 1))
def test_output_non_decreasing_in_the_voltage_at_every_sample(model, seed):
    """From any reached state, the next output is non-decreasing in the next voltage."""
    rng = np.random.default_rng(seed)
    res = model.simulate(walk(rng, 40), t=times(rng, 40, model.creep.dt))
    dt = float(rng.uniform(0, 3 * model.creep.dt))
    out = [model.predict([v], initial_state=res.final_state,
                         creep_state=res.final_creep_state, t=[dt])[0]
           for v in np.linspace(0.0, 150.0, 31)]
    assert np.all(np.diff(out) >= -1e-12 * (1.0 + np.max(np.abs(out))))


def model_with_creep(**kw):
    return BoucWenModel(beta=5.0, gamma=1.0, n=1.3, hysteretic=-6.0, linear=40.0,
                        quadratic=2.0, offset=0.5,
                        creep=Creep([0.2, 2.0, 20.0], [0.02, 0.03, 0.04], dt=0.05), **kw)


def test_step_response_closed_form():
    m = model_with_creep()
    h = m.replace(creep=None)
    u = np.r_[0.0, np.full(4000, 100.0)]
    y = m.predict(u)
    h0, h1 = h.predict([0.0])[0], h.predict([0.0, 100.0])[1]
    k = np.arange(1, 4001) * 0.05
    # from rest the settled output steps h0 -> h1: y = h1 - (h1 - h0) sum_i g_i e^(-t/tau_i)
    expect = h1 - (h1 - h0) * (np.exp(-k[:, None] / m.creep.tau) @ m.creep.gain)
    np.testing.assert_allclose(y[1:], expect, rtol=0, atol=1e-12 * abs(h1))
    assert y[0] == pytest.approx(h0, abs=1e-12)


def test_batch_stepper_and_chunks_agree():
    rng = np.random.default_rng(4)
    m = model_with_creep()
    u, t = walk(rng, 800), times(rng, 800, 0.05)
    whole = m.simulate(u, t=t)
    step = m.stepper()
    got = [step.step(u[0])] + [step.step(x, d) for x, d in zip(u[1:], np.diff(t))]
    np.testing.assert_array_equal(got, whole.output)
    np.testing.assert_array_equal(step.creep_state, whole.final_creep_state)
    step.reset()
    assert step.step(u[0]) == got[0]
    # chunks at the fixed interval continue exactly
    whole = m.simulate(u)
    a = m.simulate(u[:300])
    b = m.simulate(u[300:], initial_state=a.final_state, creep_state=a.final_creep_state)
    np.testing.assert_array_equal(np.r_[a.output, b.output], whole.output)
    # a stepper from a given lag state, and reset to another
    s = m.stepper(creep_state=a.final_creep_state, initial_state=a.final_state)
    assert s.step(u[300]) == b.output[0]
    s.reset(state=a.final_state, creep_state=a.final_creep_state)
    assert s.step(u[300]) == b.output[0]


def test_delay_delays_the_input_of_the_hysteresis_and_its_lags():
    m = model_with_creep(delay=3, sample_period=0.05)
    u = walk(np.random.default_rng(5), 200)
    plain = m.replace(delay=0, sample_period=None)
    np.testing.assert_array_equal(m.predict(u), plain.predict(np.r_[[u[0]] * 3, u[:-3]]))


def test_without_creep_nothing_changes():
    m = model_with_creep().replace(creep=None)
    u = walk(np.random.default_rng(0), 300)
    np.testing.assert_array_equal(m.predict(u), m.predict(u, t=np.arange(300.0)))
    assert m.simulate(u).final_creep_state is None
    assert m.stepper().creep_state is None
    assert "creep" not in m.to_dict()


def test_json_round_trip_and_values(tmp_path):
    m = model_with_creep()
    path = tmp_path / "bw.json"
    m.save(path)
    d = json.loads(path.read_text())
    assert d["creep"] == {"tau_s": [0.2, 2.0, 20.0], "gain": [0.02, 0.03, 0.04],
                          "dt_s": 0.05}
    back = pihyst.load_model(path)
    assert back == m and hash(back) == hash(m) and back.creep == m.creep
    assert back != m.replace(creep=None)
    assert m.replace(creep=None).replace(creep=m.creep) == m
    assert "creep=Creep(" in repr(m)
    # files written before Bouc-Wen had creep, and an explicit null, load without it
    d.pop("creep")
    assert PIModel.from_dict(d).creep is None
    assert PIModel.from_dict({**d, "creep": None}).creep is None
    assert m.hysteresis_output(m.initial_state) == m.replace(creep=None).predict([0.0])[0]


@pytest.mark.parametrize("bad,match", [
    ({"tau_s": [1.0, 2.0], "gain": [0.1, -0.01], "dt_s": 0.1}, "negative"),
    ({"tau_s": [1.0, 2.0], "gain": [0.6, 0.4], "dt_s": 0.1}, "less than 1"),
    ({"tau_s": [1.0], "gain": [0.1]}, "missing key 'dt_s'"),
    ([1, 2], "object"),
])
def test_invalid_creep_is_rejected_in_one_line(bad, match):
    d = model_with_creep().to_dict()
    with pytest.raises(InvalidModelError, match=match) as err:
        PIModel.from_dict({**d, "creep": bad}, source="bw.json")
    assert "\n" not in str(err.value) and str(err.value).startswith("bw.json")


def test_bad_times_and_states_are_one_line_errors():
    m = model_with_creep()
    with pytest.raises(ValueError, match="non-decreasing"):
        m.predict([0.0, 1.0, 2.0], t=[0.0, 0.2, 0.1])
    with pytest.raises(ValueError, match="one sample time"):
        m.predict([0.0, 1.0], t=[0.0])
    with pytest.raises(InvalidModelError, match="creep_state"):
        m.predict([0.0], creep_state=[1.0, 2.0])
    with pytest.raises(InvalidArgumentError, match="dt"):
        m.stepper().step(1.0, -0.1)
