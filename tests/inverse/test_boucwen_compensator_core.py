"""The C core's Bouc-Wen compensator against its Python twin (BoucWenCompensatorTwin) on
many models and desired signals (reachable, out of reach, NaN, infinities, holds), with
and without limits and a slew limit: the same voltages, displacements and flags (to
rounding), every voltage inside the limits and the slew bound, and the round trip
predict(compensate(y_d)) == y_d where y_d is reachable."""

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from pihyst.exceptions import InvalidModelError
from pihyst.inverse import BoucWenCompensator, compensator_for
from pihyst.inverse._boucwen import BoucWenCompensatorTwin
from pihyst.model import BoucWenModel


@st.composite
def monotone_models(draw):
    beta = draw(st.floats(0.05, 40))       # the twin's substeps are Python (see there)
    gamma = draw(st.floats(-0.95, 0.95)) * beta
    a = draw(st.floats(-20, 20))
    c2 = draw(st.floats(-5, 5))
    d = 2 * beta / (beta + gamma)
    need = max(0.0, -2 * c2) - min(a, 0.0) * d
    c1 = need * (1 + 1e-9) + 1e-9 + draw(st.floats(0, 30))
    lo = draw(st.floats(-50, 50))
    return BoucWenModel(beta=beta, gamma=gamma, n=draw(st.floats(1, 4)), hysteretic=a,
                        linear=c1, quadratic=c2, offset=draw(st.floats(-5, 5)),
                        input_range=(lo, lo + draw(st.floats(1, 200))))


def desired(model, seed, n=80):
    lo, hi = model.input_range
    y = model.predict(np.linspace(lo, hi, 50))
    y_lo, y_hi = float(y.min()), float(y.max())
    rng = np.random.default_rng(seed)
    span = y_hi - y_lo
    walk = y_lo + span * np.abs((np.cumsum(rng.normal(0, 0.08, n)) + 0.5) % 2 - 1)
    walk[rng.uniform(size=n) < 0.08] = np.nan
    walk[rng.uniform(size=n) < 0.05] = y_hi + span          # out of reach
    walk[rng.uniform(size=n) < 0.05] = -np.inf
    walk[rng.uniform(size=n) < 0.03] = np.inf
    hold = rng.uniform(size=n) < 0.1
    walk[1:][hold[1:]] = walk[:-1][hold[1:]]
    return walk


def options(model, draw_limits, draw_slew):
    lo, hi = model.input_range
    out = {}
    if draw_limits:
        out["u_min"], out["u_max"] = lo + 0.1 * (hi - lo), hi - 0.2 * (hi - lo)
    if draw_slew:
        out["slew_rate"] = 0.07 * (hi - lo)
        out["sample_period"] = 1.0
    return out


@settings(max_examples=40)
@given(model=monotone_models(), seed=st.integers(0, 2**16), limits=st.booleans(),
       slew=st.booleans())
# nearly flat at saturation: the bracket closes on adjacent voltages 5 ulps of output off
@example(model=BoucWenModel(beta=27.0, gamma=0.0, hysteretic=1.0, linear=1e-9,
                            input_range=(48.0, 49.0)), seed=0, limits=False, slew=False)
def test_c_compensator_equals_the_twin(model, seed, limits, slew):
    yd = desired(model, seed)
    kw = options(model, limits, slew)
    c = BoucWenCompensator(model, **kw).run(yd)
    twin = BoucWenCompensatorTwin(model, **kw).run(yd)
    span = model.input_range[1] - model.input_range[0]
    scale = (abs(model.offset) + abs(model.linear) + abs(model.quadratic)
             + abs(model.hysteretic) * model.z_max)
    np.testing.assert_allclose(c.voltage, twin.voltage, rtol=0, atol=1e-9 * span)
    np.testing.assert_allclose(c.displacement, twin.displacement, rtol=0, atol=1e-9 * scale)
    assert np.array_equal(c.flags, twin.flags)
    np.testing.assert_allclose(c.final_state, twin.final_state, rtol=0, atol=1e-9 * span)
    # limits and slew, whatever the input
    u_min, u_max = c.limits
    assert np.all((c.voltage >= u_min) & (c.voltage <= u_max))
    if slew:
        u0 = BoucWenCompensator(model, **kw).voltage
        assert np.all(np.abs(np.diff(np.r_[u0, c.voltage])) <= kw["slew_rate"])
    # the round trip: where reached, the model's output for the voltages is y_d, to the
    # compensator's tolerance or, where its bracket closed on two adjacent voltages, to
    # the output change over a few ulps of voltage (plus the output's rounding)
    reached = c.flags == 0
    eps = np.finfo(float).eps
    slope_max = (abs(model.linear) + 2 * abs(model.quadratic) + abs(model.hysteretic) * 2
                 * model.beta / (model.beta + model.gamma)) / span
    tol = (16 * 4 * eps * (np.abs(yd) + scale)
           + 8 * eps * (np.abs(c.voltage) + span) * slope_max)
    assert np.all(np.abs(c.displacement - yd)[reached & np.isfinite(yd)]
                  <= tol[reached & np.isfinite(yd)])
    start = BoucWenCompensator(model, **kw)
    y_again = model.predict(c.voltage, initial_state=start.state)
    np.testing.assert_allclose(y_again, c.displacement, rtol=0, atol=1e-12 * scale)


@settings(max_examples=20)
@given(model=monotone_models(), seed=st.integers(0, 2**16))
def test_step_equals_run_and_reset_restarts(model, seed):
    yd = desired(model, seed, n=60)
    comp = BoucWenCompensator(model, slew_rate=0.1 * np.ptp(model.input_range), sample_period=1.0)
    stepped = [comp.step(v) for v in yd]
    flags_last = comp.last_flags
    comp.reset()
    res = comp.run(yd)
    assert np.array_equal(stepped, res.voltage) and res.flags[-1] == flags_last
    state, volts = comp.state, comp.voltage
    more = comp.run(yd[:10]).voltage
    comp.reset(state=state)
    assert np.array_equal(comp.run(yd[:10]).voltage, more) and comp.voltage == more[-1]
    assert volts == res.voltage[-1]


def test_reset_to_a_state_and_a_voltage():
    m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
    c, twin = BoucWenCompensator(m, u_min=10.0), BoucWenCompensatorTwin(m, u_min=10.0)
    for comp in (c, twin):
        comp.reset(state=(0.0, 0.1), voltage=42.0)    # the state's u is below the limits
    assert np.array_equal(c.state, twin.state) and c.displacement == twin.displacement
    assert c.step(math.nan) == 42.0 and c.last_flags == c.FLAG_NAN
    with pytest.raises(ValueError, match="outside the limits"):
        c.reset(voltage=5.0)


def test_non_monotone_models_are_refused_by_both():
    m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=10.0)
    for cls in (BoucWenCompensator, BoucWenCompensatorTwin, compensator_for):
        with pytest.raises(InvalidModelError, match="monotone"):
            cls(m)


def test_compensator_for_picks_the_family_and_refuses_creep_state():
    m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
    assert type(compensator_for(m)) is BoucWenCompensator
    with pytest.raises(ValueError, match="no creep"):
        compensator_for(m, creep_state=[0.0])


def test_banks_refuse_bouc_wen_models_with_one_line():
    from pihyst.inverse import CompensatorBank
    m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
    with pytest.raises(ValueError, match="not BoucWenModel"):
        CompensatorBank([m, m])
