"""ModelBank: N channels stepped together give bit for bit the outputs of N separate
steppers (any families, sizes, initial states), chunked or tick by tick; input checks."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from tests.strategies import U, any_model

import pihyst
from pihyst.model import ModelBank


@settings(max_examples=40, deadline=None)
@given(models=st.lists(any_model(nonneg=False), min_size=1, max_size=6),
       seed=st.integers(0, 2**32 - 1), n_ticks=st.integers(1, 120))
def test_bank_equals_separate_steppers(models, seed, n_ticks):
    rng = np.random.default_rng(seed)
    u = rng.uniform(0.0, U, size=(n_ticks, len(models)))
    u[rng.random(u.shape) < 0.1] = 0.0
    states = [None if rng.random() < 0.5 else m.simulate(rng.uniform(0.0, U, 5)).final_state
              for m in models]
    bank = ModelBank(models, states)
    y = bank.run(u)
    for i, m in enumerate(models):
        expected = m.predict(u[:, i], initial_state=states[i])
        assert np.array_equal(y[:, i], expected)
        assert np.array_equal(bank.states[i],
                              m.simulate(u[:, i], initial_state=states[i]).final_state)
    # tick by tick from the same start: the same bits
    bank.reset()
    ticks = np.array([bank.step(row) for row in u])
    assert np.array_equal(ticks, y)


def test_bank_checks_its_input():
    a = pihyst.ClassicalPI([0, 10], [1.0, 0.5], input_range=(0.0, 100.0))
    b = pihyst.ClassicalPI([0, 10], [1.0, 0.5])
    bank = ModelBank([a, b])
    with pytest.raises(ValueError, match="shape"):
        bank.step([1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="shape"):
        bank.run(np.zeros((3, 3)))
    with pytest.raises(pihyst.InputRangeError):
        bank.step([120.0, 120.0])    # channel 0's range ends at 100 V
    with pytest.raises(pihyst.InputRangeError):
        bank.step([np.nan, 1.0])
    assert np.array_equal(bank.step([50.0, 120.0]), [a.predict([50.0])[0],
                                                     b.predict([120.0])[0]])
    with pytest.raises(TypeError):
        ModelBank([a, "b"])
    with pytest.raises(ValueError, match="initial_states"):
        ModelBank([a, b], [None])
    assert ModelBank([]).run(np.zeros((4, 0))).shape == (4, 0)
