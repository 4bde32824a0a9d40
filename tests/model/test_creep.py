"""Models with creep (docs/theory/creep.md): the C lags against their NumPy twin on many
signals, the closed-form step response, monotonicity in the voltage at every sample
(the property that keeps the inverse exact), the exact compensator with creep under any
input, chunking, the JSON form and validation."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import pihyst
from pihyst import _core, _reference
from pihyst.model import ClassicalPI, Creep, InvalidModelError, MultislopePI, PIModel

from strategies import U, classical_models, multislope_models, pwl_models


@st.composite
def creeps(draw):
    n = draw(st.integers(1, 6))
    tau = np.sort(draw(st.lists(st.floats(0.01, 1e4), min_size=n, max_size=n, unique=True)))
    g = np.array(draw(st.lists(st.floats(0.0, 1.0), min_size=n, max_size=n)))
    total = draw(st.floats(0.0, 0.95))
    g = g / g.sum() * total if g.sum() > 0 else g
    return Creep(tau, g, dt=draw(st.floats(1e-4, 10.0)))


models = st.one_of(classical_models(), multislope_models(), pwl_models())


def voltage_walk(rng, n, lo=0.0, hi=U):
    """Ramps between random levels, with holds (repeated samples) and reversals."""
    u, v = np.empty(n), lo
    target = rng.uniform(lo, hi)
    for i in range(n):
        if rng.random() < 0.03:
            target = rng.uniform(lo, hi)
        if rng.random() < 0.6:
            v = min(v + rng.uniform(0, 4), target) if v < target else \
                max(v - rng.uniform(0, 4), target)
        u[i] = v
    return u


def times(rng, n, dt):
    """Irregular sample times: mostly about dt, some repeats, some long gaps."""
    step = dt * rng.uniform(0.5, 1.5, n)
    step[rng.random(n) < 0.05] = 0.0
    step[rng.random(n) < 0.02] *= 200.0
    return np.cumsum(step)


SIGNALS = 12


@pytest.mark.parametrize("seed", range(SIGNALS))
def test_c_lags_match_numpy_twin(seed):
    rng = np.random.default_rng(seed)
    n_lags = int(rng.integers(1, 9))
    tau = np.sort(10 ** rng.uniform(-2, 4, n_lags))
    gain = rng.dirichlet(np.ones(n_lags)) * rng.uniform(0, 0.95)
    dt0 = 10 ** rng.uniform(-4, 0)
    z0 = rng.normal(0, 5, n_lags)
    fast, slow = _core.Creep(tau, gain, dt0, z0), _reference.Creep(tau, gain, dt0, z0)
    assert fast.beta == pytest.approx(slow.beta, rel=1e-12)
    h = np.cumsum(rng.normal(0, 1, 2000))
    dt = np.diff(times(rng, 2001, dt0))
    for d in (None, dt):
        np.testing.assert_allclose(fast.run(h, d), slow.run(h, d), rtol=0, atol=1e-11)
        np.testing.assert_allclose(fast.state, slow.state, rtol=0, atol=1e-11)
    for y_d, d in zip(rng.normal(0, 10, 50), rng.uniform(0, 2, 50)):
        for dd in (None, float(d)):
            assert fast.target(y_d, dd) == pytest.approx(slow.target(y_d, dd), abs=1e-10)
            assert fast.step(y_d, dd) == pytest.approx(slow.step(y_d, dd), abs=1e-11)


@pytest.mark.parametrize("seed", range(SIGNALS))
def test_c_compensator_with_creep_matches_numpy_twin(seed):
    rng = np.random.default_rng(100 + seed)
    r = np.sort(rng.choice(np.arange(0, 50, 5.0), 4, replace=False))
    args = {"family": "multislope", "thresholds": r, "weights": rng.uniform(0, 0.3, 4),
            "shape": (U, 0.8, 1.2, 0.5), "offset": 0.5, "u_min": 0.0, "u_max": U}
    tau, gain = np.array([0.3, 3.0, 30.0]), rng.dirichlet(np.ones(3)) * 0.3
    lo, hi, step = (0.0, U, np.inf) if seed % 2 else (10.0, 140.0, 8.0)
    y_d = rng.uniform(-2, 30, 300)
    y_d[rng.choice(300, 20)] = rng.choice([np.nan, np.inf, -np.inf, 1e300], 20)
    dt = None if seed % 3 == 0 else rng.uniform(0, 1, 300)
    fast_c = _core.Compensator(_core.Bank(**args), lo, hi, step, lo)
    slow_c = _reference.Compensator(_reference.Bank(**args), lo, hi, step, lo)
    z0 = np.full(3, fast_c.output)
    u_f, y_f, fl_f = _core.Creep(tau, gain, 0.1, z0).compensate(fast_c, y_d, dt)
    u_s, y_s, fl_s = _reference.Creep(tau, gain, 0.1, z0).compensate(slow_c, y_d, dt)
    np.testing.assert_allclose(u_f, u_s, rtol=0, atol=1e-8)
    np.testing.assert_allclose(y_f, y_s, rtol=0, atol=1e-8)
    np.testing.assert_array_equal(fl_f, fl_s)
    assert np.all((u_f >= lo) & (u_f <= hi))
    assert np.all(np.abs(np.diff(np.r_[lo, u_f])) <= step)


def test_step_response_closed_form():
    creep = Creep([0.5, 5.0, 50.0], [0.02, 0.03, 0.05], dt=0.01)
    m = ClassicalPI([0.0], [0.2], creep=creep)
    u = np.r_[0.0, np.full(20000, 100.0)]
    y = m.predict(u)
    k = np.arange(1, 20001) * 0.01
    # from rest at H = 0 the hysteresis output jumps to 20:
    # y = 20 (1 - sum_i g_i exp(-t / tau_i))
    expect = 20.0 * (1 - np.exp(-k[:, None] / creep.tau) @ creep.gain)
    np.testing.assert_allclose(y[1:], expect, rtol=1e-12)
    # with the lags settled at the hysteresis output, a held voltage keeps it
    settled = m.predict(np.full(50, 70.0), initial_state=[70.0], creep_state=[14.0] * 3)
    np.testing.assert_allclose(settled, 14.0, rtol=1e-15)


@settings(max_examples=60)
@given(models, creeps(), st.integers(0, 2**32 - 1))
def test_output_non_decreasing_in_the_voltage_at_every_sample(model, creep, seed):
    """From any reached state, the next output is non-decreasing in the next voltage."""
    m = model.replace(creep=creep)
    rng = np.random.default_rng(seed)
    u = voltage_walk(rng, 60)
    t = times(rng, 60, creep.dt)
    res = m.simulate(u, t=t)
    nxt = np.linspace(0.0, U, 41)
    dt = float(rng.uniform(0, 3 * creep.dt))
    out = [m.predict([v], initial_state=res.final_state, creep_state=res.final_creep_state,
                     t=[dt])[0] for v in nxt]
    scale = 1.0 + np.max(np.abs(out))
    assert np.all(np.diff(out) >= -1e-12 * scale)


@settings(max_examples=60)
@given(models, creeps(), st.integers(0, 2**32 - 1), st.booleans())
def test_compensator_with_creep_is_exact_and_within_limits(model, creep, seed, irregular):
    m = model.replace(creep=creep)
    rng = np.random.default_rng(seed)
    u = voltage_walk(rng, 200)
    t = times(rng, 200, creep.dt) if irregular else None
    # a start the model can be in at 0 V (a random initial state may lie outside the
    # envelopes there; the model clamps it at the first sample, the compensator at 0 V)
    m = m.replace(initial_state=model.simulate([0.0]).final_state)
    z0 = np.full(creep.n_lags, m.hysteresis_output(m.initial_state))
    y = m.predict(u, t=t, creep_state=z0)
    res = pihyst.compensate(m, y, t=t, creep_state=z0)
    scale = 1.0 + np.max(np.abs(y))
    assert np.max(np.abs(res.displacement - y)) <= 1e-9 * scale
    # the displacement reported is the model's prediction for the voltages chosen
    np.testing.assert_allclose(m.predict(res.voltage, t=t, creep_state=z0), res.displacement,
                               rtol=0, atol=1e-9 * scale)
    # garbage in: the voltage never leaves the limits or the slew limit
    wild = rng.choice([np.nan, np.inf, -np.inf, 1e300, -1e300, 0.0, scale, -scale], 100)
    out = pihyst.compensate(m, wild, u_min=5.0, u_max=140.0, slew_rate=7.0, sample_period=1.0,
                            initial_voltage=5.0, t=None if t is None else t[:100])
    assert np.all((out.voltage >= 5.0) & (out.voltage <= 140.0))
    assert np.all(np.abs(np.diff(np.r_[5.0, out.voltage])) <= 7.0)
    assert np.all(np.isfinite(out.displacement))


def test_chunks_continue_exactly():
    rng = np.random.default_rng(3)
    m = MultislopePI([0, 20, 40], [0.2, 0.05, 0.03],
                     creep=Creep([0.2, 2.0, 20.0], [0.03, 0.02, 0.04], dt=0.05))
    u, t = voltage_walk(rng, 1000), times(rng, 1000, 0.05)
    # chunks at the fixed interval continue exactly (the first sample of a chunk comes
    # creep.dt after the previous one)
    whole = m.simulate(u)
    a = m.simulate(u[:400])
    b = m.simulate(u[400:], initial_state=a.final_state, creep_state=a.final_creep_state)
    np.testing.assert_allclose(np.r_[a.output, b.output], whole.output, atol=1e-12)
    # irregular times: chunks continue exactly given the previous sample's time
    whole = m.simulate(u, t=t)
    a = m.simulate(u[:400], t=t[:400])
    b = m.simulate(u[400:], t=t[400:], t_previous=t[399], initial_state=a.final_state,
                   creep_state=a.final_creep_state)
    np.testing.assert_allclose(np.r_[a.output, b.output], whole.output, atol=1e-12)
    with pytest.raises(ValueError, match="before t_previous"):
        m.simulate(u[400:], t=t[400:], t_previous=t[401])
    # irregular times: the stepper, one interval per sample, equals the batch run
    step = m.stepper()
    got = [step.step(u[0])] + [step.step(x, d) for x, d in zip(u[1:], np.diff(t))]
    np.testing.assert_allclose(got, whole.output, atol=1e-12)
    np.testing.assert_allclose(step.creep_state, whole.final_creep_state, atol=1e-12)
    # the compensator: one run == two chunks (fixed interval) == steps (irregular)
    y = m.predict(u)
    one = pihyst.compensate(m, y)
    comp = pihyst.Compensator(m)
    r1, r2 = comp.run(y[:500]), comp.run(y[500:])
    np.testing.assert_array_equal(np.r_[r1.voltage, r2.voltage], one.voltage)
    np.testing.assert_array_equal(r2.initial_creep_state, r1.final_creep_state)
    assert np.max(np.abs(one.displacement - y)) < 1e-9
    y = whole.output
    one = pihyst.compensate(m, y, t=t)
    comp = pihyst.Compensator(m)
    got = [comp.step(y[0])] + [comp.step(v, d) for v, d in zip(y[1:], np.diff(t))]
    np.testing.assert_array_equal(got, one.voltage)
    assert comp.displacement == one.displacement[-1]


def test_without_creep_nothing_changes():
    m = ClassicalPI([0, 10, 30], [0.3, 0.2, 0.1])
    u = voltage_walk(np.random.default_rng(0), 300)
    assert m.creep is None
    np.testing.assert_array_equal(m.predict(u), m.predict(u, t=np.arange(300.0)))
    assert m.simulate(u).final_creep_state is None
    assert "creep" not in m.to_dict()
    assert pihyst.compensate(m, m.predict(u)).final_creep_state is None


def test_json_round_trip_and_equality(tmp_path):
    creep = Creep([1.0, 10.0, 100.0], [0.01, 0.02, 0.03], dt=0.1)
    m = MultislopePI([0, 20, 40], [0.2, 0.05, 0.03], creep=creep)
    path = tmp_path / "m.json"
    m.save(path)
    d = json.loads(path.read_text())
    assert d["creep"] == {"tau_s": [1.0, 10.0, 100.0], "gain": [0.01, 0.02, 0.03], "dt_s": 0.1}
    back = pihyst.load_model(path)
    assert back == m and back.creep == creep
    assert back != m.replace(creep=None)
    assert hash(back) == hash(m)
    assert "creep=Creep(" in repr(m)
    assert PIModel.from_dict({**d, "creep": None}).creep is None


@pytest.mark.parametrize("bad,match", [
    ({"tau_s": [1.0, 0.0], "gain": [0.1, 0.1], "dt_s": 0.1}, "> 0 s"),
    ({"tau_s": [1.0, 2.0], "gain": [0.1, -0.01], "dt_s": 0.1}, "negative"),
    ({"tau_s": [1.0, 2.0], "gain": [0.6, 0.4], "dt_s": 0.1}, "less than 1"),
    ({"tau_s": [1.0], "gain": [0.1], "dt_s": 0.0}, "dt_s"),
    ({"tau_s": [1.0], "gain": [0.1]}, "missing key 'dt_s'"),
    ({"tau_s": [1.0], "gain": [0.1], "dt_s": 0.1, "extra": 1}, "unknown key"),
    ({"tau_s": [1.0, 2.0], "gain": [0.1], "dt_s": 0.1}, "one per time constant"),
    ({"tau_s": [], "gain": [], "dt_s": 0.1}, "at least one"),
    ([1, 2], "object"),
])
def test_invalid_creep_is_rejected_with_its_reason(bad, match):
    d = ClassicalPI([0.0], [1.0]).to_dict()
    with pytest.raises(InvalidModelError, match=match):
        PIModel.from_dict({**d, "creep": bad})


def test_sample_times_are_checked():
    m = ClassicalPI([0.0], [1.0], creep=Creep([1.0], [0.1], dt=0.1))
    with pytest.raises(ValueError, match="non-decreasing"):
        m.predict([0.0, 1.0, 2.0], t=[0.0, 0.2, 0.1])
    with pytest.raises(ValueError, match="one sample time"):
        m.predict([0.0, 1.0], t=[0.0])
    with pytest.raises(ValueError, match="finite"):
        pihyst.compensate(m, [0.0, 1.0], t=[0.0, np.nan])
