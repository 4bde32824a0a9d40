"""MIMO state-space identification from multisines: BLA, FSID, order by validation."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from pihyst.dynamics import StateSpace, estimate_bla, fit_state_space, fsid
from pihyst.dynamics._statespace import stabilized
from pihyst.exceptions import InvalidArgumentError

PERIOD = 256


def random_system(rng, order=6, m=2, p=2):
    """A stable real system in modal form: complex pole pairs of radius 0.5-0.95."""
    blocks = []
    for _ in range(order // 2):
        r, th = rng.uniform(0.5, 0.95), rng.uniform(0.1, 2.8)
        blocks.append(r * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]]))
    A = np.zeros((order, order))
    for k, blk in enumerate(blocks):
        A[2 * k:2 * k + 2, 2 * k:2 * k + 2] = blk
    return StateSpace(A, rng.normal(size=(order, m)), rng.normal(size=(p, order)),
                      rng.normal(size=(p, m)))


def multisine(rng, m, periods=3, period=PERIOD):
    """Random-phase full multisine on every line but DC and Nyquist, per input."""
    L = period // 2 + 1
    X = np.zeros((L, m), complex)
    X[1:-1] = np.exp(2j * np.pi * rng.uniform(size=(L - 2, m)))
    one = np.fft.irfft(X, n=period, axis=0)
    one /= one.std(axis=0)
    return np.tile(one, (periods, 1))


def records(system, rng, n_records=5, noise=0.0):
    out = []
    for _ in range(n_records):
        u = multisine(rng, system.n_inputs)
        y = system.predict(u)
        out.append((u, y + noise * y.std() * rng.normal(size=y.shape)))
    return out


def relative_response_error(model, system):
    w = 2 * np.pi * np.arange(1, PERIOD // 2) / PERIOD
    return np.linalg.norm(model.response(w) - system.response(w)) / \
        np.linalg.norm(system.response(w))


def test_the_bla_of_a_linear_system_is_its_response():
    rng = np.random.default_rng(1)
    system = random_system(rng)
    frf = estimate_bla(records(system, rng), PERIOD)
    assert frf.G.shape == (PERIOD // 2 - 1, 2, 2)
    assert np.allclose(frf.G, system.response(frf.omega), atol=1e-8)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fsid_recovers_a_noiseless_system_and_its_order(seed):
    rng = np.random.default_rng(seed)
    system = random_system(rng, order=6, m=2, p=3)
    recs = records(system, rng)
    model, sel = fit_state_space(recs, PERIOD, orders=range(2, 13, 2), return_selection=True)
    assert sel.chosen == 6 and model.order == 6
    assert relative_response_error(model, system) < 1e-6
    assert np.allclose(np.sort_complex(np.linalg.eigvals(model.A)),
                       np.sort_complex(np.linalg.eigvals(system.A)), atol=1e-6)
    u = multisine(rng, 2)
    assert np.allclose(model.predict(u), system.predict(u), atol=1e-6 * system.predict(u).std())


def test_fsid_recovers_a_noisy_system():
    rng = np.random.default_rng(3)
    system = random_system(rng, order=8, m=3, p=3)
    recs = records(system, rng, n_records=6, noise=0.01)
    model, sel = fit_state_space(recs, PERIOD, orders=range(2, 17, 2), return_selection=True)
    assert 8 <= sel.chosen <= 12
    assert relative_response_error(model, system) < 0.02
    u = multisine(rng, 3)
    y = system.predict(u)
    err = model.predict(u)[PERIOD:] - y[PERIOD:]
    assert np.sqrt(np.mean(err ** 2)) < 0.02 * y.std()


def test_a_model_beyond_the_true_order_still_matches():
    rng = np.random.default_rng(4)
    system = random_system(rng, order=4)
    frf = estimate_bla(records(system, rng), PERIOD)
    model = fsid(frf.omega, frf.G, 10)
    assert model.spectral_radius < 1
    assert relative_response_error(model, system) < 1e-6


@settings(max_examples=30)
@given(arrays(float, (6, 6), elements=st.floats(-3, 3)))
def test_stabilized_puts_every_pole_inside_the_unit_circle(A):
    C = np.eye(2, 6)
    As, Cs = stabilized(A, C)
    assert np.max(np.abs(np.linalg.eigvals(As))) < 1
    lam = np.linalg.eigvals(A)
    if np.all(np.abs(lam) < 0.999):
        assert As is A and Cs is C
    else:
        # a reflected pole keeps its angle; the stable ones are kept
        mags = np.sort(np.minimum(np.abs(lam), 1 / np.maximum(np.abs(lam), 1e-300)))
        assert np.allclose(np.sort(np.abs(np.linalg.eigvals(As))),
                           np.minimum(mags, 1 - 1e-6), rtol=1e-5, atol=1e-6)


@settings(max_examples=20)
@given(st.integers(0, 2 ** 32 - 1), st.integers(1, 8))
def test_fsid_on_arbitrary_data_returns_a_stable_model(seed, order):
    rng = np.random.default_rng(seed)
    omega = np.linspace(0.05, 3.0, 40)
    G = rng.normal(size=(40, 2, 2)) + 1j * rng.normal(size=(40, 2, 2))
    model = fsid(omega, G, order)
    assert model.order == order and model.spectral_radius < 1


def test_state_space_round_trips_through_a_dict():
    rng = np.random.default_rng(5)
    s = random_system(rng)
    t = StateSpace.from_dict(s.to_dict())
    assert all(np.array_equal(getattr(s, k), getattr(t, k)) for k in "ABCD")


def _good():
    rng = np.random.default_rng(6)
    return records(random_system(rng), rng, n_records=4)


@pytest.mark.parametrize("call, message", [
    (lambda r: fit_state_space(r, 100, order=4), "not a whole number of periods"),
    (lambda r: fit_state_space(r, PERIOD + 0.5, order=4), "period must be an integer"),
    (lambda r: fit_state_space(r[:1], PERIOD, order=4), "needs at least 2 records"),
    (lambda r: fit_state_space(r, PERIOD, order=0), "order must be a positive integer"),
    (lambda r: fit_state_space(r[:2], PERIOD), "give order="),
    (lambda r: fit_state_space(r, PERIOD, validation=[7]), "validation indices"),
    (lambda r: fit_state_space([(r[0][0][:-1], r[0][1])] + r[1:], PERIOD, order=4),
     "with the same N"),
    (lambda r: fit_state_space([(np.full_like(r[0][0], np.nan), r[0][1])] + r[1:], PERIOD,
                               order=4), "NaN"),
    (lambda r: fit_state_space([(r[0][0], r[0][0])] * 4, PERIOD, order=4),
     "not independent"),
    (lambda r: fit_state_space([5] + r, PERIOD, order=4), "must be a pair"),
    (lambda r: StateSpace(np.eye(2), np.ones((3, 1)), np.ones((1, 2)), [[0.0]]),
     "shapes do not match"),
    (lambda r: fit_state_space(r, PERIOD, order=4).predict(r[0][0][:, :1]), "has 2 inputs"),
])
def test_bad_input_gives_a_one_line_error(call, message):
    with pytest.raises(InvalidArgumentError, match=message) as info:
        call(_good())
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("seed", [0, 1])
def test_refinement_recovers_the_system_from_a_perturbed_start(seed):
    from pihyst.dynamics._refine import refine
    rng = np.random.default_rng(seed)
    system = random_system(rng, order=6, m=2, p=3)
    frf = estimate_bla(records(system, rng, n_records=3), PERIOD)
    # a start 5 % off: the poles scaled and rotated, B, C, D perturbed
    lam, V = np.linalg.eig(system.A)
    A0 = np.real(V @ np.diag(lam * 0.97 * np.exp(0.05j * np.sign(lam.imag))) @
                 np.linalg.inv(V))
    start = StateSpace(A0, system.B * (1 + 0.05 * rng.normal(size=system.B.shape)),
                       system.C * (1 + 0.05 * rng.normal(size=system.C.shape)), system.D * 1.05)
    assert relative_response_error(start, system) > 0.05
    model = refine(start, frf.omega, frf.G, max_nfev=200)
    assert model.spectral_radius < 1 and model.order == 6
    assert relative_response_error(model, system) < 1e-6


def test_refinement_never_raises_the_error_and_keeps_the_poles_inside():
    from pihyst.dynamics._refine import refine
    rng = np.random.default_rng(7)
    system = random_system(rng, order=8, m=2, p=2)
    frf = estimate_bla(records(system, rng, n_records=4, noise=0.05), PERIOD)
    for order in (4, 8):
        start = fsid(frf.omega, frf.G, order)
        model = refine(start, frf.omega, frf.G)
        e0, e1 = (np.linalg.norm(m.response(frf.omega) - frf.G) for m in (start, model))
        assert e1 <= e0 and model.spectral_radius < 1
