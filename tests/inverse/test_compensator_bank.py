"""CompensatorBank: N channels compensated together give bit for bit the voltages,
displacements and flags of N separate compensators (any families, limits, slew limits,
initial states), on any desired values; every voltage inside its channel's limits."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from tests.strategies import U, any_model

import pihyst
from pihyst.inverse import FLAG_SATURATED_HIGH, FLAG_SLEW, CompensatorBank


@st.composite
def channel(draw):
    model = draw(any_model(nonneg=True))
    lo = draw(st.sampled_from([None, 0.0, 10.0]))
    hi = draw(st.sampled_from([None, U, 120.0]))
    slew = draw(st.sampled_from([None, 0.5, 7.0, np.inf]))
    return model, lo, hi, slew


@settings(max_examples=40, deadline=None)
@given(channels=st.lists(channel(), min_size=1, max_size=6), seed=st.integers(0, 2**32 - 1),
       n_ticks=st.integers(1, 150))
def test_bank_equals_separate_compensators(channels, seed, n_ticks):
    rng = np.random.default_rng(seed)
    models = [c[0] for c in channels]
    u_min, u_max, slew = ([c[i] for c in channels] for i in (1, 2, 3))
    # reachable targets along a voltage walk, jumps, noise, NaN, infinities, far values
    n = len(models)
    desired = np.empty((n_ticks, n))
    for i, m in enumerate(models):
        desired[:, i] = m.predict(np.clip(np.cumsum(rng.normal(0, 8, n_ticks)) % (2 * U),
                                          0, U))
    kind = rng.random(desired.shape)
    desired[kind < 0.1] = rng.uniform(-20, 60, desired.shape)[kind < 0.1]
    desired[kind < 0.03] = np.nan
    desired[kind < 0.02] = np.inf
    desired[kind < 0.01] = -1e300
    bank = CompensatorBank(models, u_min=u_min, u_max=u_max, slew_rate=slew, sample_period=1.0)
    u, y, flags = bank.run(desired)
    for i, m in enumerate(models):
        one = pihyst.Compensator(m, u_min=u_min[i], u_max=u_max[i], slew_rate=slew[i],
                                 sample_period=1.0)
        r = one.run(desired[:, i])
        assert np.array_equal(u[:, i], r.voltage)
        assert np.array_equal(y[:, i], r.displacement)
        assert np.array_equal(flags[:, i], r.flags)
        assert np.array_equal(bank.channels[i].state, r.final_state)
        lo, hi = bank.channels[i].limits
        assert np.all((u[:, i] >= lo) & (u[:, i] <= hi))
        if slew[i] is not None:
            steps = np.abs(np.diff(np.r_[bank.channels[i]._start[1], u[:, i]]))
            assert np.all(steps <= slew[i])
    # tick by tick from the same start: the same bits
    bank.reset()
    ticks = np.array([bank.step(row) for row in desired])
    assert np.array_equal(ticks, u)
    assert np.array_equal(bank.last_flags, flags[-1])
    assert np.array_equal(bank.voltages, u[-1])
    assert np.array_equal(bank.displacements, y[-1])


def test_bank_per_channel_options_and_checks():
    m = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    bank = CompensatorBank([m, m], slew_rate=[5.0, None],
                           sample_period=1.0, initial_voltage=[0.0, 10.0])
    u = bank.step([1.0, 50.0])
    assert u[0] == 5.0 and u[1] == 150.0
    assert list(bank.last_flags) == [FLAG_SLEW, FLAG_SATURATED_HIGH]
    with pytest.raises(ValueError, match="2 values"):
        bank.step([1.0])
    with pytest.raises(ValueError, match="shape"):
        bank.run(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="slew_rate"):
        CompensatorBank([m, m], slew_rate=[1.0], sample_period=1.0)
    with pytest.raises(pihyst.InvalidModelError):
        CompensatorBank([m, pihyst.ClassicalPI([0, 1], [1.0, -0.5])])
