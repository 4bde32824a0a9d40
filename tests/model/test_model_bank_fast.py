"""ModelBank(fast=True): the structure-of-arrays model bank (csrc/pihyst_bank_soa_model.c)
gives bit for bit the outputs and states of N separate steppers: classical channels of up
to 16 operators stepped several at a time, every other channel by its own model, in one
call; chunked or tick by tick."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from tests.strategies import U, any_model, classical_models

import pihyst
from pihyst import _core
from pihyst.model import ModelBank


@settings(max_examples=40, deadline=None)
@given(models=st.lists(st.one_of(classical_models(nonneg=False, max_ops=16),
                                 any_model(nonneg=False)), min_size=1, max_size=11),
       seed=st.integers(0, 2**32 - 1), n_ticks=st.integers(1, 120))
def test_fast_bank_equals_separate_steppers(models, seed, n_ticks):
    rng = np.random.default_rng(seed)
    u = rng.uniform(0.0, U, size=(n_ticks, len(models)))
    u[rng.random(u.shape) < 0.1] = 0.0
    states = [None if rng.random() < 0.5 else m.simulate(rng.uniform(0.0, U, 5)).final_state
              for m in models]
    bank = ModelBank(models, states, fast=True)
    assert bank.fast
    y = bank.run(u)
    for i, m in enumerate(models):
        assert np.array_equal(y[:, i], m.predict(u[:, i], initial_state=states[i]))
        assert np.array_equal(bank.states[i],
                              m.simulate(u[:, i], initial_state=states[i]).final_state)
    bank.reset()
    ticks = np.array([bank.step(row) for row in u])
    assert np.array_equal(ticks, y)


def test_fast_bank_many_channels_and_reset():
    rng = np.random.default_rng(3)
    models = [pihyst.ClassicalPI(np.r_[0.0, np.sort(rng.uniform(1, 140, k - 1))],
                                 rng.uniform(-0.1, 0.4, k), offset=rng.uniform(-2, 2))
              for k in rng.integers(1, 17, 37)]
    models.append(pihyst.ClassicalPI(np.linspace(0, 140, 20), np.full(20, 0.05)))  # K > 16
    bank = ModelBank(models, fast=True)
    u = rng.uniform(0.0, U, size=(300, len(models)))
    y = bank.run(u)
    exact = ModelBank(models).run(u)
    assert np.array_equal(y, exact)
    assert bank._array.n_fast == len(models) - 1
    states = [m.simulate(rng.uniform(0.0, U, 3)).final_state for m in models]
    bank.reset(states)
    assert np.array_equal(bank.run(u), ModelBank(models, states).run(u))


def test_fast_bank_checks():
    a = pihyst.ClassicalPI([0, 10], [1.0, 0.5], input_range=(0.0, 100.0))
    bank = ModelBank([a, a], fast=True)
    with pytest.raises(pihyst.InputRangeError):
        bank.step([120.0, 1.0])
    b = a._new_bank(None)
    with pytest.raises(ValueError, match="distinct"):
        _core.BankSoA([b, b])
    assert ModelBank([], fast=True).run(np.zeros((4, 0))).shape == (4, 0)
