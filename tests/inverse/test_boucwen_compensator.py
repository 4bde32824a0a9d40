"""The Bouc-Wen compensator: exact inverse, limits and slew on every output."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pihyst import compensate
from pihyst.exceptions import InvalidModelError
from pihyst.inverse import BoucWenCompensator
from pihyst.model import BoucWenModel


@st.composite
def monotone_models(draw):
    beta = draw(st.floats(0.3, 60))
    gamma = draw(st.floats(-0.9, 0.9)) * beta
    n = draw(st.floats(1, 3))
    a = draw(st.floats(-20, 20))
    d = 2 * beta / (beta + gamma)
    c2 = draw(st.floats(-5, 5))
    # c_1 large enough for min(c_1, c_1 + 2 c_2) + min(a, 0) D >= 0, plus some margin
    # (a relative one too: with no margin at all, rounding can make the bound -1e-115)
    need = max(0.0, -2 * c2) - min(a, 0.0) * d
    c1 = need * (1 + 1e-9) + 1e-9 + draw(st.floats(0, 30))
    lo = draw(st.floats(-50, 50))
    return BoucWenModel(beta=beta, gamma=gamma, n=n, hysteretic=a, linear=c1, quadratic=c2,
                        offset=draw(st.floats(-5, 5)), input_range=(lo, lo + draw(
                            st.floats(1, 200))))


def walk(model, seed, n=60):
    lo, hi = model.input_range
    rng = np.random.default_rng(seed)
    v = lo + (hi - lo) * np.abs(np.cumsum(rng.normal(0, 0.2, n))) % (2 * (hi - lo))
    return np.where(v > hi, 2 * hi - v + 0 * lo, v).clip(lo, hi)


@settings(max_examples=15)
@given(model=monotone_models(), seed=st.integers(0, 2**16))
def test_inverse_of_model_output_reproduces_the_output(model, seed):
    # inverse(model(u)) == u in output: the compensator reaches every reachable value
    u = walk(model, seed)
    y = model.predict(u, initial_state=(u[0], model.initial_state[1]))
    comp = BoucWenCompensator(model, initial_voltage=u[0],
                              initial_state=(u[0], model.initial_state[1]))
    res = comp.run(y)
    scale = abs(model.offset) + abs(model.linear) + abs(model.quadratic) + \
        abs(model.hysteretic) * model.z_max
    reached = res.flags == 0
    # only a value at the very edge of the range may saturate (rounding)
    assert np.all(reached | (np.abs(res.desired - res.displacement) <= 1e-9 * scale))
    assert np.max(np.abs(res.displacement - y)) <= 1e-12 * (scale + np.abs(y).max())
    # the displacement reported is the model's for the voltages returned
    assert np.max(np.abs(model.predict(res.voltage, initial_state=(u[0], model.initial_state[
        1])) - res.displacement)) <= 1e-12 * scale


@settings(max_examples=15)
@given(model=monotone_models(), desired=st.lists(
    st.one_of(st.floats(-1e6, 1e6), st.just(float("nan")), st.just(float("inf")),
              st.just(-float("inf"))), min_size=1, max_size=40),
    slew=st.one_of(st.none(), st.floats(1e-3, 50)), margin=st.floats(0, 0.4))
def test_limits_and_slew_hold_whatever_the_input(model, desired, slew, margin):
    lo, hi = model.input_range
    u_min, u_max = lo + margin * (hi - lo) / 2, hi - margin * (hi - lo) / 2
    res = compensate(model, desired, u_min=u_min, u_max=u_max, slew_rate=slew, sample_period=1.0)
    assert np.all((res.voltage >= u_min) & (res.voltage <= u_max))
    if slew is not None:
        steps = np.abs(np.diff(np.r_[res.initial_voltage, res.voltage]))
        assert np.all(steps <= slew)
    nan = np.isnan(res.desired)
    assert np.array_equal(res.nan_held, nan)


def test_saturation_and_slew_flags():
    m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
    res = compensate(m, [1e3, -1e3, 20.0])
    assert res.saturated_high[0] and res.voltage[0] == 150.0
    assert res.saturated_low[1] and res.voltage[1] == 0.0
    assert res.flags[2] == 0 and abs(res.displacement[2] - 20.0) < 1e-12
    res = compensate(m, [20.0, 20.0], slew_rate=5.0, sample_period=1.0)
    assert res.slew_limited[0] and res.voltage[0] == 5.0


def test_a_non_monotone_model_is_refused():
    m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-30.0, linear=10.0)
    with pytest.raises(InvalidModelError, match="monotone"):
        BoucWenCompensator(m)
