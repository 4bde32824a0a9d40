"""CompensatorBank(fast=True): the structure-of-arrays bank (csrc/pihyst_bank_soa.c),
where classical channels step their model's analytic inverse and every other channel,
and every tick that would leave a limit, runs the exact compensator. Against separate
compensators on any channels and desired values: voltages and displacements equal to
1e-9 of the range, flags equal (but for slew-limited vs saturated where the slew
window ends at a limit to rounding), every voltage inside its limits and slew limit, the
channels' states up to date when read. Against the NumPy twin
(pihyst._reference.CompensatorSoA) likewise."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from tests.strategies import U, any_model

import pihyst
from pihyst import _core, _reference
from pihyst.inverse import (
    FLAG_NAN,
    FLAG_SATURATED_HIGH,
    FLAG_SATURATED_LOW,
    FLAG_SLEW,
    CompensatorBank,
)


def random_classical(rng, k=None, offset=None):
    """A classical model with r_0 = 0 and w_0 > 0 (the fast path), some weights 0."""
    k = int(rng.integers(1, 20)) if k is None else k
    r = np.r_[0.0, np.sort(rng.choice(np.arange(1, 1500), k - 1, replace=False)) / 10.0]
    w = rng.uniform(0.0, 0.1, k) * (rng.random(k) > 0.15)
    w[0] = rng.uniform(0.05, 0.4)
    off = rng.uniform(-3, 3) if offset is None else offset
    return pihyst.ClassicalPI(r, w, offset=off)


def desired_values(models, n_ticks, rng):
    """Reachable targets along voltage walks, jumps, noise, NaN, infinities, far values."""
    desired = np.empty((n_ticks, len(models)))
    for i, m in enumerate(models):
        walk = np.clip(np.cumsum(rng.normal(0, 8, n_ticks)) % (2 * U), 0, U)
        desired[:, i] = m.predict(walk)
    kind = rng.random(desired.shape)
    desired[kind < 0.1] = rng.uniform(-20, 60, desired.shape)[kind < 0.1]
    desired[kind < 0.03] = np.nan
    desired[kind < 0.02] = np.inf
    desired[kind < 0.01] = -1e300
    repeat = (kind > 0.95)[1:]  # the same value again: a hold
    desired[1:][repeat] = desired[:-1][repeat]
    return desired


def assert_same_flags(flags, expected, u, limits):
    """Equal flags, except where the slew window ends at a limit to rounding: there a
    voltage that differs by rounding may find the window's end just inside the limit
    (slew-limited, and saturated too when out of reach) or on it (saturated); either is
    at the limit."""
    lo, hi = limits
    differ = flags != expected
    at_limit = np.minimum(np.abs(u - lo), np.abs(u - hi)) <= 1e-9 * (hi - lo)
    pairs = {frozenset(p) for p in zip(flags[differ], expected[differ], strict=True)}
    assert pairs <= {frozenset({FLAG_SLEW, saturated}) for saturated in (
        FLAG_SATURATED_HIGH, FLAG_SATURATED_LOW)} | {frozenset({FLAG_SLEW | saturated,
        saturated}) for saturated in (FLAG_SATURATED_HIGH, FLAG_SATURATED_LOW)}
    assert np.all(at_limit[differ])


def check_against_separate(models, u_min, u_max, slew, desired):
    bank = CompensatorBank(models, u_min=u_min, u_max=u_max, slew_rate=slew,
                           sample_period=1.0, fast=True)
    u, y, flags = bank.run(desired)
    for i, m in enumerate(models):
        one = pihyst.Compensator(m, u_min=u_min[i], u_max=u_max[i], slew_rate=slew[i],
                                 sample_period=1.0)
        r = one.run(desired[:, i])
        lo, hi = one.limits
        np.testing.assert_allclose(u[:, i], r.voltage, rtol=0, atol=1e-9 * (hi - lo))
        scale = 1.0 + np.max(np.abs(m.predict(np.array([lo, hi]))))
        np.testing.assert_allclose(y[:, i], r.displacement, rtol=0, atol=1e-9 * scale)
        assert_same_flags(flags[:, i], r.flags, u[:, i], (lo, hi))
        assert np.all((u[:, i] >= lo) & (u[:, i] <= hi))
        if slew[i] is not None:
            assert np.all(np.abs(np.diff(np.r_[bank.channels[i]._start[1], u[:, i]])) <= slew[i])
        # read through bank.channels: brought up to date
        np.testing.assert_allclose(bank.channels[i].state, r.final_state, rtol=0,
                                   atol=1e-9 * (hi - lo))
        assert bank.channels[i].voltage == u[-1, i]
    return bank, u, y, flags


@st.composite
def channel(draw):
    if draw(st.integers(0, 3)) == 0:
        model = draw(any_model(nonneg=True))
    else:
        model = random_classical(np.random.default_rng(draw(st.integers(0, 2**32 - 1))))
    lo = draw(st.sampled_from([None, 0.0, 10.0]))
    hi = draw(st.sampled_from([None, U, 120.0]))
    slew = draw(st.sampled_from([None, 0.5, 7.0, np.inf]))
    return model, lo, hi, slew


@settings(max_examples=40, deadline=None)
@given(channels=st.lists(channel(), min_size=1, max_size=11), seed=st.integers(0, 2**32 - 1),
       n_ticks=st.integers(1, 150))
def test_fast_bank_equals_separate_compensators(channels, seed, n_ticks):
    models = [c[0] for c in channels]
    u_min, u_max, slew = ([c[i] for c in channels] for i in (1, 2, 3))
    desired = desired_values(models, n_ticks, np.random.default_rng(seed))
    bank, u, y, flags = check_against_separate(models, u_min, u_max, slew, desired)
    # tick by tick from the same start: the same voltages
    bank.reset()
    ticks = np.array([bank.step(row) for row in desired])
    assert np.array_equal(ticks, u)
    assert np.array_equal(bank.last_flags, flags[-1])


def test_fast_bank_many_classical_channels():
    """Many channels (several groups and a partial one), all on the fast path."""
    rng = np.random.default_rng(5)
    models = [random_classical(rng) for _ in range(23)]
    n = len(models)
    u_min = [None] * n
    u_max = list(rng.choice([U, 130.0], n))
    slew = [None if i % 3 else 2.0 for i in range(n)]
    desired = desired_values(models, 600, rng)
    bank, *_ = check_against_separate(models, u_min, u_max, slew, desired)
    assert bank.n_fast == n


def test_fast_path_selection_and_state_joining():
    rng = np.random.default_rng(7)
    fast = random_classical(rng, k=6)
    w0_zero = pihyst.ClassicalPI([0, 10, 20], [0.0, 0.2, 0.1])
    r0_pos = pihyst.ClassicalPI([2, 10, 20], [0.3, 0.2, 0.1])
    ill = pihyst.ClassicalPI([0, 10, 20], [1e-4, 0.2, 0.1])  # w_0 < sum w / 1024
    multi = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    # a state that is not 1-Lipschitz in r: exact path until the voltage sweeps it out
    odd = pihyst.ClassicalPI([0, 40, 41, 80], [0.3, 0.1, 0.1, 0.1])
    models = [fast, w0_zero, r0_pos, ill, multi, odd]
    states = [None] * 5 + [[0.0, 0.0, 30.0, 0.0]]
    bank = CompensatorBank(models, initial_state=states, fast=True)
    assert bank.fast and bank.n_fast == 1
    assert "1 on the fast path" in repr(bank)
    bank.step([m.predict(np.array([100.0]))[0] for m in models])
    assert bank.n_fast == 2  # the odd state was swept out by a voltage near 100
    assert not CompensatorBank(models).fast and CompensatorBank(models).n_fast == 0


def test_fast_bank_holds_and_flags():
    m = pihyst.ClassicalPI([0, 10, 30, 60], [0.2, 0.05, 0.04, 0.03])
    bank = CompensatorBank([m, m, m], slew_rate=[5.0, None, None], sample_period=1.0, fast=True)
    u = bank.step([1.5, np.nan, 50.0])
    assert u[0] == 5.0 and u[1] == 0.0 and u[2] == 150.0
    assert list(bank.last_flags) == [8, FLAG_NAN, 2]
    before = bank.voltages
    u = bank.step(bank.displacements)  # the outputs themselves: every channel holds
    assert np.array_equal(u, before) and not np.any(bank.last_flags)
    bank.reset()
    assert np.array_equal(bank.voltages, [0.0, 0.0, 0.0])


def test_fast_bank_against_numpy_twin():
    rng = np.random.default_rng(11)
    models = [random_classical(rng, k=int(k)) for k in (1, 3, 8, 16, 5)]
    models.append(pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028]))
    limits = [(0.0, U, np.inf), (10.0, 120.0, np.inf), (0.0, U, 3.0), (0.0, 140.0, 1.0),
              (0.0, U, np.inf), (0.0, U, np.inf)]
    desired = desired_values(models, 120, rng)
    fast_c = [_core.Compensator(m._new_bank(None), lo, hi, s, lo)
              for m, (lo, hi, s) in zip(models, limits, strict=True)]
    twin_c = [_reference.Compensator(_reference.Bank(m.family, weights=m.weights,
                                                     offset=m.offset, u_min=0.0, u_max=U,
                                                     **m._bank_args()),
                                     lo, hi, s, lo)
              for m, (lo, hi, s) in zip(models, limits, strict=True)]
    fast = _core.CompensatorSoA(fast_c)
    twin = _reference.CompensatorSoA(twin_c)
    assert fast.n_fast == twin.n_fast == 5
    u, y, flags = fast.run(desired)
    u_t, y_t, flags_t = twin.run(desired)
    np.testing.assert_allclose(u, u_t, rtol=0, atol=1e-9 * U)
    np.testing.assert_allclose(y, y_t, rtol=0, atol=1e-9 * 40)
    assert np.array_equal(flags, flags_t)
    fast.sync()
    twin.sync()
    for a, b in zip(fast_c, twin_c, strict=True):
        np.testing.assert_allclose(a.state, b.state, rtol=0, atol=1e-9 * U)


def test_fast_bank_checks():
    m = pihyst.ClassicalPI([0, 10], [0.3, 0.1])
    bank = CompensatorBank([m, m], fast=True)
    with pytest.raises(ValueError, match="2 values"):
        bank.step([1.0])
    with pytest.raises(ValueError, match="shape"):
        bank.run(np.zeros((3, 3)))
    c = _core.Compensator(m._new_bank(None), 0.0, U, np.inf, 0.0)
    with pytest.raises(ValueError, match="distinct"):
        _core.CompensatorSoA([c, c])
    empty = _core.CompensatorSoA([])
    assert empty.run(np.zeros((4, 0)))[0].shape == (4, 0)
