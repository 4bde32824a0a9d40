"""The exact compensator of a Bouc-Wen model with creep (docs/theory/creep.md): the C
path (csrc/pihyst_bw_creep.c) equals its Python twin on many models and desired signals
(reachable, out of reach, NaN, infinities, irregular sample times, limits, slew); the
model with creep driven by the voltages at the same sample times meets the desired
values where reached; stream == block == chunks; creep_state passes through
compensate and compensator_for; bad input is a one-line error."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import pihyst
from pihyst.exceptions import InvalidArgumentError
from pihyst.inverse import BoucWenCompensator, compensator_for
from pihyst.inverse._boucwen import BoucWenCompensatorTwin
from pihyst.model import BoucWenModel, Creep


@st.composite
def models(draw):
    beta = draw(st.floats(0.1, 30))
    gamma = draw(st.floats(-0.9, 0.9)) * beta
    a = draw(st.floats(-15, 15))
    c2 = draw(st.floats(-4, 4))
    d = 2 * beta / (beta + gamma)
    c1 = max(0.0, -2 * c2) - min(a, 0.0) * d + 1e-6 + draw(st.floats(0, 30))
    n_lags = draw(st.integers(1, 5))
    tau = np.sort(10 ** np.array(draw(st.lists(st.floats(-1.5, 3), min_size=n_lags,
                                               max_size=n_lags))))
    share = np.array(draw(st.lists(st.floats(0.01, 1), min_size=n_lags, max_size=n_lags)))
    creep = Creep(tau, share / share.sum() * draw(st.floats(0, 0.9)),
                  dt=draw(st.floats(1e-3, 0.5)))
    lo = draw(st.floats(-50, 50))
    return BoucWenModel(beta=beta, gamma=gamma, n=draw(st.floats(1, 3)), hysteretic=a,
                        linear=c1, quadratic=c2, offset=draw(st.floats(-5, 5)),
                        input_range=(lo, lo + draw(st.floats(1, 200))), creep=creep)


def voltages(model, rng, n):
    lo, hi = model.input_range
    v = np.cumsum(rng.normal(0, 0.04 * (hi - lo), n) * (rng.random(n) < 0.6))
    v = v % (2 * (hi - lo))
    return lo + np.where(v > hi - lo, 2 * (hi - lo) - v, v)


def times(rng, n, dt):
    d = dt * rng.uniform(0, 3, n)
    d[rng.random(n) < 0.05] = 0.0
    return np.cumsum(d)


def scale_of(model, y):
    return (abs(model.offset) + abs(model.linear) + abs(model.quadratic)
            + abs(model.hysteretic) * model.z_max + float(np.nanmax(np.abs(y), initial=0)))


@settings(max_examples=40)
@given(model=models(), seed=st.integers(0, 2**32 - 1), irregular=st.booleans(),
       limits=st.booleans(), slew=st.booleans())
def test_c_compensator_equals_the_twin(model, seed, irregular, limits, slew):
    rng = np.random.default_rng(seed)
    n = 80
    lo, hi = model.input_range
    y = model.predict(voltages(model, rng, n))
    span_y = float(np.ptp(y)) + 1.0
    y[rng.random(n) < 0.06] = np.nan
    y[rng.random(n) < 0.05] = float(np.nanmax(y)) + span_y          # out of reach
    y[rng.random(n) < 0.03] = -np.inf
    y[rng.random(n) < 0.03] = np.inf
    t = times(rng, n, model.creep.dt) if irregular else None
    kw = {}
    if limits:
        kw.update(u_min=lo + 0.1 * (hi - lo), u_max=hi - 0.2 * (hi - lo))
    if slew:
        kw["slew_rate"] = 0.07 * (hi - lo)
        kw["sample_period"] = 1.0
    c = BoucWenCompensator(model, **kw).run(y, t=t)
    twin = BoucWenCompensatorTwin(model, **kw).run(y, t=t)
    scale = scale_of(model, np.where(np.isfinite(y), y, 0.0))
    np.testing.assert_allclose(c.voltage, twin.voltage, rtol=0, atol=1e-9 * (hi - lo))
    np.testing.assert_allclose(c.displacement, twin.displacement, rtol=0, atol=1e-9 * scale)
    np.testing.assert_array_equal(c.flags, twin.flags)
    np.testing.assert_allclose(c.final_creep_state, twin.final_creep_state, rtol=0,
                               atol=1e-9 * scale)
    # whatever the desired values: inside the limits and the slew bound
    u_min, u_max = c.limits
    assert np.all((c.voltage >= u_min) & (c.voltage <= u_max))
    if slew:
        start = BoucWenCompensator(model, **kw).voltage
        assert np.all(np.abs(np.diff(np.r_[start, c.voltage])) <= kw["slew_rate"])
    assert np.all(np.isfinite(c.displacement))


@settings(max_examples=40)
@given(model=models(), seed=st.integers(0, 2**32 - 1), irregular=st.booleans())
def test_the_model_meets_the_desired_values_on_the_compensator_voltages(model, seed,
                                                                        irregular):
    rng = np.random.default_rng(seed)
    n = 150
    t = times(rng, n, model.creep.dt) if irregular else None
    # the model's own outputs from where the compensator starts (at rest at its initial
    # voltage): reachable; plus a few out of reach
    start = model.replace(creep=None).simulate([BoucWenCompensator(model).voltage])
    m = model.replace(initial_state=start.final_state)
    y = m.predict(voltages(model, rng, n), t=t)
    y[rng.random(n) < 0.03] = float(np.max(y)) + 1.0 + float(np.ptp(y))
    res = pihyst.compensate(m, y, t=t)
    scale = scale_of(m, y)
    reached = res.flags == 0
    assert np.max(np.abs(res.displacement - y)[reached], initial=0) <= 1e-9 * scale
    np.testing.assert_allclose(m.predict(res.voltage, t=t), res.displacement, rtol=0,
                               atol=1e-9 * scale)


def model_with_creep(**kw):
    return BoucWenModel(beta=5.0, gamma=1.0, n=1.3, hysteretic=-6.0, linear=40.0,
                        quadratic=2.0, offset=0.5,
                        creep=Creep([0.2, 2.0, 20.0], [0.02, 0.03, 0.04], dt=0.05), **kw)


def test_stream_block_and_chunks_agree():
    rng = np.random.default_rng(7)
    m = model_with_creep()
    u = voltages(m, rng, 600)
    t = times(rng, 600, 0.05)
    y = m.predict(u, t=t)
    one = pihyst.compensate(m, y, t=t)
    comp = BoucWenCompensator(m)
    got = [comp.step(y[0])] + [comp.step(v, d) for v, d in zip(y[1:], np.diff(t))]
    np.testing.assert_array_equal(got, one.voltage)
    assert comp.displacement == one.displacement[-1]
    np.testing.assert_array_equal(comp.creep_state, one.final_creep_state)
    comp.reset()
    r1 = comp.run(y[:250], t=t[:250])
    r2 = comp.run(y[250:], t=t[250:], t_previous=t[249])
    np.testing.assert_array_equal(np.r_[r1.voltage, r2.voltage], one.voltage)
    np.testing.assert_array_equal(r2.initial_creep_state, r1.final_creep_state)
    # a desired value held: the compensator moves the voltage to cancel the drift
    hold = pihyst.compensate(m, np.r_[np.linspace(m.predict([0.0])[0], 20.0, 50),
                                      np.full(400, 20.0)])
    assert np.all(hold.flags == 0)
    assert np.max(np.abs(hold.displacement[50:] - 20.0)) < 1e-9
    assert hold.voltage[-1] < hold.voltage[50]       # lowered after the rise


def test_creep_state_passes_through_and_is_checked():
    m = model_with_creep()
    z0 = np.array([3.0, 4.0, 5.0])
    y = np.full(20, 10.0)
    a = pihyst.compensate(m, y, creep_state=z0)
    b = compensator_for(m, creep_state=z0).run(y)
    np.testing.assert_array_equal(a.voltage, b.voltage)
    np.testing.assert_array_equal(a.initial_creep_state, z0)
    np.testing.assert_allclose(m.predict(a.voltage, creep_state=z0), a.displacement,
                               atol=1e-12)
    comp = BoucWenCompensator(m, creep_state=z0)
    comp.run(y)
    comp.reset()
    np.testing.assert_array_equal(comp.creep_state, z0)
    for call in (lambda: pihyst.compensate(m.replace(creep=None), y, creep_state=z0),
                 lambda: BoucWenCompensator(m, creep_state=[1.0]),
                 lambda: BoucWenCompensator(m).step(1.0, dt=-1.0),
                 lambda: BoucWenCompensator(m).run(y, t=np.arange(19.0)),
                 lambda: BoucWenCompensator(m).run(y, t=-np.arange(20.0))):
        with pytest.raises(ValueError) as err:
            call()
        assert "\n" not in str(err.value)
    with pytest.raises(InvalidArgumentError, match="no creep"):
        compensator_for(m.replace(creep=None), creep_state=z0)


def test_delayed_model_with_creep_is_compensated_with_preview():
    m = model_with_creep(delay=2, sample_period=0.05)
    rng = np.random.default_rng(9)
    t = np.arange(300) * 0.05
    y = m.replace(delay=0, sample_period=None).predict(voltages(m, rng, 300) * 0.5, t=t)
    res = pihyst.compensate(m, y, t=t)
    reached = res.flags[2:] == 0
    assert np.max(np.abs(res.displacement[2:] - y[2:])[reached]) < 1e-9
    np.testing.assert_allclose(
        m.predict(res.voltage, t=t, pending_input=[res.initial_voltage] * 2),
        res.displacement, atol=1e-9)
