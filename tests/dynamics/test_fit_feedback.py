"""One model for several amplitudes as a feedback loop around fixed dynamics
(pihyst.dynamics._fit_feedback)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pihyst.dynamics import StateSpace, fit_feedback_state_space, fit_state_space
from pihyst.dynamics._fit_feedback import closed_loop, feedback_response, feedback_scheduled
from pihyst.exceptions import FitError, InvalidArgumentError

PERIOD = 256


def random_plant(rng, n=4, p=2, m=2):
    """A random stable system."""
    A = rng.normal(size=(n, n))
    A *= rng.uniform(0.3, 0.9) / np.abs(np.linalg.eigvals(A)).max()
    return StateSpace(A, rng.normal(size=(n, m)), rng.normal(size=(p, n)),
                      rng.normal(size=(p, m)))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), delta=st.floats(0.0, 1.0),
       p=st.integers(1, 3), m=st.integers(1, 3))
def test_closed_loop_is_the_feedback_of_the_response(seed, delta, p, m):
    """The loop's state-space model has the response G0 (I + d H_z)^-1,
    H_z = C_z (zI - A)^-1 B."""
    rng = np.random.default_rng(seed)
    G0 = random_plant(rng, n=int(rng.integers(1, 6)), p=p, m=m)
    Cz = 0.1 * rng.normal(size=(m, G0.order))
    Hz = StateSpace(G0.A, G0.B, Cz, np.zeros((m, m)))
    omega = np.linspace(0.01, 3.1, 9)
    expected = feedback_response(G0.response(omega), Hz.response(omega), delta)
    np.testing.assert_allclose(closed_loop(G0, Cz, delta).response(omega), expected,
                               rtol=1e-8, atol=1e-10 * np.abs(expected).max())


def multisine(seed, scale, m):
    rng = np.random.default_rng(seed)
    k = np.arange(1, PERIOD // 2 - 10)
    phase = rng.uniform(0, 2 * np.pi, (k.size, m))
    t = np.arange(2 * PERIOD)
    u = np.cos(2 * np.pi * t[:, None, None] * k[None, :, None] / PERIOD + phase).sum(axis=1)
    return scale * u / np.sqrt(np.mean(u ** 2))


G_TRUE = StateSpace([[0.6, -0.7, 0.0], [0.7, 0.6, 0.0], [0.0, 0.0, 0.3]],
                    [[1.0, 0.2], [0.0, 1.0], [0.5, -0.4]], [[1.0, 0.0, 0.3], [0.2, 1.0, 0.0]],
                    [[0.1, 0.0], [0.0, 0.05]])
CZ_TRUE = np.array([[0.06, -0.04, 0.03], [0.02, 0.05, -0.05]])


def records(scale, delta, seeds):
    """Steady-state records of the loop at ``delta`` (two periods, the first settles)."""
    plant = closed_loop(G_TRUE, CZ_TRUE, delta)
    out = []
    for s in seeds:
        u = multisine(s, scale, 2)
        y = plant.predict(np.vstack([u, u]))[u.shape[0]:]
        out.append((u, y))
    return out


def test_fit_recovers_the_loop_and_the_level_between():
    """Fitted on the lowest and highest level from a start 3 % off, it recovers both
    and the middle one (not fitted; the loop is linear in the amplitude there)."""
    low, high = records(0.1, 0.0, (1, 2, 3)), records(0.3, 1.0, (4, 5, 6))
    start = StateSpace(G_TRUE.A * 0.97, G_TRUE.B * 1.03, G_TRUE.C, G_TRUE.D)
    model = fit_feedback_state_space([high, low], PERIOD, start, window=PERIOD,
                                     discard=1, max_nfev=200, n_anchors=17)
    assert model.amplitudes[-1] / model.amplitudes[0] == pytest.approx(3.0, rel=0.01)
    omega = np.linspace(0.05, 3.0, 7)
    for a, delta in ((model.amplitudes[0], 0.0), (model.amplitudes[-1], 1.0)):
        np.testing.assert_allclose(model.at(a).response(omega),
                                   closed_loop(G_TRUE, CZ_TRUE, delta).response(omega),
                                   atol=1e-6)
    a_mid = np.mean(model.amplitudes[[0, -1]])
    middle = closed_loop(G_TRUE, CZ_TRUE, 0.5).response(omega)
    err = np.abs(model.at(a_mid).response(omega) - middle).max()
    # the anchors' linear interpolation of the loop's modes: close, not exact
    assert err < 1e-3 * np.abs(middle).max()
    # one linear model of both levels misses the middle by far more
    joint = fit_state_space(low + high, PERIOD, order=3)
    assert np.abs(joint.response(omega) - middle).max() > 30 * err


def test_fit_refuses_one_level_and_equal_levels():
    low = records(0.1, 0.0, (1, 2))
    with pytest.raises(InvalidArgumentError, match="two levels"):
        fit_feedback_state_space([low], PERIOD, G_TRUE)
    with pytest.raises(InvalidArgumentError, match="differ"):
        fit_feedback_state_space([low, low], PERIOD, G_TRUE)
    with pytest.raises(InvalidArgumentError, match="n_anchors"):
        fit_feedback_state_space([low, records(0.3, 1.0, (3, 4))], PERIOD, G_TRUE,
                                 n_anchors=1)


def test_the_jacobian_is_the_residuals_derivative(monkeypatch):
    """The analytic Jacobian of the joint fit against central differences, away from
    the start."""
    import scipy.optimize

    seen = {}
    original = scipy.optimize.least_squares

    def spy(fun, x0, jac=None, **options):
        seen.update(fun=fun, jac=jac, x0=x0)
        return original(fun, x0, jac=jac, **options)

    monkeypatch.setattr(scipy.optimize, "least_squares", spy)
    start = StateSpace(G_TRUE.A * 0.97, G_TRUE.B * 1.03, G_TRUE.C, G_TRUE.D)
    fit_feedback_state_space([records(0.1, 0.0, (1, 2, 3)), records(0.3, 1.0, (4, 5, 6))],
                             PERIOD, start, window=PERIOD, max_nfev=1)
    x = seen["x0"] + 0.01 * np.random.default_rng(0).normal(size=seen["x0"].size)
    h = 1e-7
    numeric = np.column_stack([(seen["fun"](x + e) - seen["fun"](x - e)) / (2 * h)
                               for e in np.eye(x.size) * h])
    J = seen["jac"](x)
    assert np.abs(J - numeric).max() < 1e-6 * np.abs(J).max()


def test_an_unstable_loop_or_one_whose_modes_change_kind_is_refused():
    lag = StateSpace([[0.5]], [[1.0]], [[1.0]], [[0.0]])      # A_delta = 0.5 + delta
    with pytest.raises(FitError, match="unstable at delta 0.500"):
        feedback_scheduled(lag, [[-1.0]], (0.1, 0.3), window=100)
    with pytest.raises(FitError, match="change kind"):          # the pair turns real
        feedback_scheduled(G_TRUE, 30 * CZ_TRUE, (0.1, 0.3), window=100)
