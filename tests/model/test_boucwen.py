"""The Bouc-Wen model: a value like the PI models, accurate against the closed form."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pihyst import load_model
from pihyst.exceptions import InputRangeError, InvalidModelError
from pihyst.model import BoucWenModel, PIModel
from pihyst.sim._boucwen import BoucWen

U = 150.0


def model_of_sim(bw):
    """The sim's Bouc-Wen (n = 1, physical units) in the model's normalized form:
    x = u / U, z = h / (alpha d U), beta' = beta U, gamma' = gamma U."""
    return BoucWenModel(beta=bw.beta * U, gamma=bw.gamma * U, hysteretic=-bw.alpha * bw.d * U,
                        linear=bw.d * U, quadratic=bw.c2, input_range=(0.0, U))


def wander(seed, n=1500, step=4.0):
    rng = np.random.default_rng(seed)
    v = np.abs(np.cumsum(rng.normal(0, step, n))) % (2 * U)
    return np.where(v > U, 2 * U - v, v)


@pytest.mark.parametrize("beta,gamma", [(0.035, 0.008), (0.035, -0.02), (0.01, 0.002),
                                        (0.12, 0.1)])
def test_matches_the_closed_form_for_n_1(beta, gamma):
    alpha = min(0.42, 0.99 * (beta + gamma) / (2 * beta))
    bw = BoucWen(U, d=0.28, alpha=alpha, beta=beta, gamma=gamma, c2=4.0)
    m = model_of_sim(bw)
    scale = abs(m.hysteretic) * m.z_max
    assert m.initial_state[1] * m.hysteretic == pytest.approx(-bw.state[1], abs=1e-8 * scale)
    u = wander(3)
    err = np.max(np.abs(m.predict(u) - bw.run(u)))
    assert err < 1e-8 * scale


@settings(max_examples=15)
@given(beta=st.floats(0.3, 80), ratio=st.floats(-0.95, 0.95), n=st.floats(1, 4),
       seed=st.integers(0, 2**16))
def test_state_stays_bounded_and_the_stepper_matches_the_batch(beta, ratio, n, seed):
    m = BoucWenModel(beta=beta, gamma=ratio * beta, n=n, hysteretic=-1.0, linear=3.0)
    u = wander(seed, n=200, step=10.0)
    res = m.simulate(u)
    z = (res.output - m.output(u, 0.0)) / m.hysteretic
    assert np.all(np.abs(z) <= m.z_max * (1 + 1e-9))
    s = m.stepper()
    assert np.array_equal([s.step(v) for v in u], res.output)
    # a following chunk continues exactly from the final state
    more = wander(seed + 1, n=50)
    assert np.array_equal(m.predict(more, initial_state=res.final_state),
                          m.predict(np.r_[u, more])[u.size:])


@settings(max_examples=15)
@given(beta=st.floats(0.3, 80), ratio=st.floats(-0.95, 0.95), n=st.floats(1, 4),
       seed=st.integers(0, 2**16))
def test_monotone_by_the_bound(beta, ratio, n, seed):
    # with the bound min_slope >= 0 at equality (the steepest admissible hysteresis),
    # the output never runs against the input
    d = 2 * beta / (beta + ratio * beta)
    m = BoucWenModel(beta=beta, gamma=ratio * beta, n=n, hysteretic=-1.0, linear=d)
    assert m.min_slope == pytest.approx(0.0, abs=1e-12)
    u = wander(seed, n=300, step=6.0)
    y = m.predict(u)
    du, dy = np.diff(u), np.diff(y)
    assert np.all(dy * np.sign(du) >= -1e-9)


def test_value_semantics_and_json_round_trip(tmp_path):
    m = BoucWenModel(beta=5.0, gamma=1.0, n=1.5, hysteretic=-8.0, linear=40.0, quadratic=2.0,
                     offset=0.5, input_range=(-10.0, 100.0), metadata={"fit": {"x": 1}})
    assert m == m.replace(metadata={})
    assert hash(m) == hash(m.replace(metadata={}))
    assert m.replace(beta=6.0) != m and m.replace(beta=6.0).beta == 6.0
    with pytest.raises(AttributeError):
        m.beta = 3.0
    d = json.loads(json.dumps(m.to_dict()))
    assert BoucWenModel.from_dict(d) == m
    assert PIModel.from_dict(d) == m
    m.save(tmp_path / "bw.json")
    assert load_model(tmp_path / "bw.json") == m
    with pytest.raises(InvalidModelError, match="unknown key 'weights'"):
        BoucWenModel.from_dict({**d, "weights": [1.0]})
    with pytest.raises(InvalidModelError, match="missing required key 'beta'"):
        BoucWenModel.from_dict({k: v for k, v in d.items() if k != "beta"})
    assert "BoucWenModel(beta=5" in repr(m)


@pytest.mark.parametrize("kwargs,match", [
    ({"beta": 1.0, "gamma": 1.0}, "beta > |gamma|"),
    ({"beta": 1.0, "gamma": 0.0, "n": 0.5}, "exponent"),
    ({"beta": float("nan"), "gamma": 0.0}, "not a finite"),
    ({"beta": 1.0, "gamma": 0.0, "input_range": (1, 1)}, "min < max"),
    ({"beta": 1.0, "gamma": 0.0, "initial_state": (0.0, 5.0)}, "z_max"),
])
def test_invalid_models_cannot_exist(kwargs, match):
    with pytest.raises(InvalidModelError, match=match):
        BoucWenModel(hysteretic=1.0, linear=1.0, **kwargs)


def test_input_outside_the_range_is_refused():
    m = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
    with pytest.raises(InputRangeError):
        m.predict([0.0, 151.0])
    with pytest.raises(InputRangeError):
        m.stepper().step(-1.0)
