"""MIMO Hammerstein models with state-space dynamics, from multisine records."""

import numpy as np
import pytest
from tests.dynamics.test_state_space import PERIOD, multisine, random_system

from pihyst.dynamics import StateSpaceHammerstein, fit_hammerstein_ss, fit_state_space
from pihyst.exceptions import InvalidArgumentError
from pihyst.model import ClassicalPI

THRESHOLDS = [0.0, 0.5, 1.0, 1.5]


def plant(rng):
    hyst = (ClassicalPI(THRESHOLDS, [0.5, 0.3, 0.15, 0.05], input_range=(-6.0, 6.0)),
            ClassicalPI(THRESHOLDS, [0.6, 0.1, 0.2, 0.1], input_range=(-6.0, 6.0)))
    return StateSpaceHammerstein(hysteresis=hyst, dynamics=random_system(rng, 6, 2, 2))


def records(model, rng, n=6):
    out = []
    for _ in range(n):
        u = multisine(rng, 2)
        out.append((u, model.predict(u)))
    return out


def _fit(refinements):
    rng = np.random.default_rng(0)
    true = plant(rng)
    recs = records(true, rng)
    linear = fit_state_space(recs, PERIOD, 8)     # the order validation chooses here
    ham = fit_hammerstein_ss(recs, PERIOD, thresholds=[THRESHOLDS] * 2,
                             input_range=[(-6.0, 6.0)] * 2, linear=linear,
                             refinements=refinements)
    u = multisine(rng, 2)
    y = true.predict(u)
    e_lin = np.sqrt(np.mean((linear.predict(u) - y)[PERIOD:] ** 2))
    e_ham = np.sqrt(np.mean((ham.predict(u) - y)[PERIOD:] ** 2))
    assert all(np.all(H.weights >= 0) for H in ham.hysteresis)
    assert ham.dynamics.spectral_radius < 1
    return true, ham, e_lin, e_ham


def test_fits_a_noiseless_hammerstein_far_better_than_the_linear_model():
    _, _, e_lin, e_ham = _fit(4)
    assert e_ham < 0.1 * e_lin


@pytest.mark.slow
def test_recovers_a_noiseless_hammerstein_system():
    true, ham, e_lin, e_ham = _fit(20)
    # the alternation converges to the true weights (normalised to sum 1, as here)
    assert e_ham < 1e-3 * e_lin
    for fitted, known in zip(ham.hysteresis, true.hysteresis):
        assert np.allclose(fitted.weights, known.weights, atol=1e-3)


def test_round_trips_through_a_dict():
    rng = np.random.default_rng(1)
    m = plant(rng)
    back = StateSpaceHammerstein.from_dict(m.to_dict())
    u = multisine(rng, 2)
    assert np.allclose(back.predict(u), m.predict(u))


def test_a_linear_start_of_the_wrong_shape_is_refused():
    rng = np.random.default_rng(2)
    recs = records(plant(rng), rng, n=3)
    with pytest.raises(InvalidArgumentError, match="linear must be a StateSpace model with 2"):
        fit_hammerstein_ss(recs, PERIOD, linear=random_system(rng, 4, 3, 2))
