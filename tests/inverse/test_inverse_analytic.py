"""Analytic inverse of the classical PI model (docs/theory/inverse.md, paper eqs. 21-25
correctly indexed) against the exact inverse of the compensator."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pihyst
from pihyst import ClassicalPI, InputRangeError, InvalidModelError, compensate
from pihyst.model import classical_inverse, reachable_output_range

from strategies import U, random_walk

PAPER = pihyst.load_model("examples/paper_table1_classical.json")


@st.composite
def invertible_classical(draw):
    """r_0 = 0 < r_1 < ... (whole volts), w_0 > 0, w >= 0, any offset, and an initial
    state reached by a voltage history (with the voltage it ended at)."""
    rest = draw(st.lists(st.integers(1, 149), max_size=7, unique=True))
    r = np.r_[0.0, np.sort(rest)]
    w = np.r_[draw(st.floats(0.05, 1.0)),
              draw(st.lists(st.floats(0.0, 1.0), min_size=r.size - 1, max_size=r.size - 1))]
    model = ClassicalPI(r, w, offset=draw(st.floats(-5, 5)))
    history = draw(st.lists(st.floats(0, U), max_size=20))
    if history:
        state = model.simulate(np.array(history)).final_state
        model = model.replace(initial_state=state)
        return model, history[-1]
    return model, 0.0


@st.composite
def voltage_walks(draw):
    """Voltages with many reversals of every size (minor loops)."""
    return np.array(draw(st.lists(st.one_of(st.floats(0, U), st.sampled_from([0.0, U])),
                                  min_size=1, max_size=150)))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(invertible_classical(), voltage_walks())
def test_analytic_inverse_agrees_with_exact_inverse(model_and_voltage, u):
    model, u_start = model_and_voltage
    y_d = model.predict(u)
    exact = compensate(model, y_d, initial_voltage=u_start)
    analytic = model.inverse().predict(y_d)
    np.testing.assert_allclose(analytic, exact.voltage, rtol=0, atol=1e-9)
    np.testing.assert_allclose(analytic, u, rtol=0, atol=1e-9)


def test_paper_model_inverse_numbers_and_minor_loops():
    inv = PAPER.inverse()
    # r'_i = sum_{j<=i} w_j (r_i - r_j);  w'_0 = 1/w_0,  w'_i = -w_i / (S_i S_{i-1})
    np.testing.assert_allclose(inv.thresholds, [0.0, 0.08, 5.28, 38.76], rtol=1e-12)
    s = np.cumsum(PAPER.weights)
    np.testing.assert_allclose(inv.weights, [1 / 0.008, -0.252 / (s[1] * s[0]),
                                             -0.019 / (s[2] * s[1]), -0.582 / (s[3] * s[2])])
    assert inv.units == {"input": "um", "output": "V"}
    u = random_walk(4000, seed=11, step=4.0)
    y_d = PAPER.predict(u)
    exact = compensate(PAPER, y_d)
    np.testing.assert_allclose(inv.predict(y_d), exact.voltage, rtol=0, atol=1e-9)
    np.testing.assert_allclose(inv.predict(y_d), u, rtol=0, atol=1e-9)


def test_inverse_of_inverse_is_the_model():
    model = ClassicalPI([0, 5, 20, 60], [0.3, 0.1, 0.2, 0.05], offset=1.5,
                        initial_state=[10.0, 8.0, 1.0, 0.0])
    back = model.inverse().inverse()
    np.testing.assert_allclose(back.thresholds, model.thresholds, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(back.weights, model.weights, rtol=1e-12)
    assert back.offset == pytest.approx(model.offset, rel=1e-12)
    np.testing.assert_allclose(back.initial_state, model.initial_state, atol=1e-12)


def test_input_range_is_the_reachable_output_range():
    inv = PAPER.inverse()
    lo, hi = reachable_output_range(PAPER)
    assert (lo, hi) == pytest.approx((0.0, 38.76), abs=1e-12)
    assert inv.input_range == pytest.approx((lo, hi), abs=1e-9)
    assert inv.input_range[0] <= lo and inv.input_range[1] >= hi
    with pytest.raises(InputRangeError):
        inv.predict([10.0, 40.0])
    # offset and a non-zero initial state move the range
    shifted = PAPER.replace(offset=2.0, initial_state=[0.0, 0.0, 0.0, 5.0])
    lo2, hi2 = reachable_output_range(shifted)
    assert lo2 == pytest.approx(2.0 + 0.582 * 5.0) and hi2 == pytest.approx(40.76 + 0.582 * 5)


def test_inverse_saves_and_loads(tmp_path):
    inv = PAPER.inverse()
    inv.save(tmp_path / "inverse.json")
    back = pihyst.load_model(tmp_path / "inverse.json")
    y = np.r_[np.linspace(0, 38.76, 50), np.linspace(38.76, 3.09, 50)]
    np.testing.assert_array_equal(back.predict(y), inv.predict(y))


@pytest.mark.parametrize("model,match", [
    (ClassicalPI([5, 10], [0.5, 0.5]), "first threshold of 0"),
    (ClassicalPI([0, 10], [0.0, 0.5]), "positive partial sums"),
    (ClassicalPI([0, 10], [0.5, -0.6]), "positive partial sums"),
    (pihyst.MultislopePI([0, 20], [0.5, 0.5]), "classical PI models"),
])
def test_not_invertible_analytically(model, match):
    with pytest.raises(InvalidModelError, match=match):
        classical_inverse(model)
