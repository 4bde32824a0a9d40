"""A model with invalid parameters cannot be constructed; messages say what is wrong."""

import math

import numpy as np
import pytest

import pihyst
from pihyst import ClassicalPI, InvalidModelError, MultislopePI, PiecewiseLinearPI


@pytest.mark.parametrize("thresholds,match", [
    ([0, 20, 10], "strictly increasing: thresholds\\[1\\] = 20 is followed by 10"),
    ([0, 10, 10], "strictly increasing"),
    ([-1, 10, 20], ">= 0"),
    ([0, math.nan, 20], "thresholds\\[1\\] is nan"),
    ([0, math.inf, 20], "thresholds\\[1\\] is inf"),
])
def test_bad_thresholds(thresholds, match):
    with pytest.raises(InvalidModelError, match=match):
        ClassicalPI(thresholds, [1, 1, 1])
    with pytest.raises(InvalidModelError, match=match.replace("20", "40").replace("10", "20")):
        MultislopePI(np.array(thresholds) * 2, [1, 1, 1], a=0.5, h=0.0)  # limit 75 V


def test_bad_weights_and_sizes():
    with pytest.raises(InvalidModelError, match="weights\\[0\\] is nan"):
        ClassicalPI([0], [math.nan])
    with pytest.raises(InvalidModelError, match="2 thresholds but 3 weights"):
        ClassicalPI([0, 1], [1, 1, 1])
    with pytest.raises(InvalidModelError, match="at least one operator"):
        ClassicalPI([], [])
    with pytest.raises(InvalidModelError, match="offset"):
        ClassicalPI([0], [1], offset=math.nan)
    with pytest.raises(InvalidModelError, match="input_range"):
        ClassicalPI([0], [1], input_range=(10, 0))
    with pytest.raises(InvalidModelError, match="initial_state must have 2 values"):
        ClassicalPI([0, 1], [1, 1], initial_state=[0])


def test_multislope_shape_and_threshold_limit():
    with pytest.raises(InvalidModelError, match="0 < a < b"):
        MultislopePI([0], [1], a=1.3, b=1.2)
    with pytest.raises(InvalidModelError, match="h <= 1"):
        MultislopePI([0], [1], h=1.5)
    with pytest.raises(InvalidModelError, match="not a finite number"):
        MultislopePI([0], [1], U=math.nan)
    # (1 - a)U/(1 - a h) with a = 0.9, h = 0: 15 V
    MultislopePI([15.0], [1], a=0.9, h=0.0)
    with pytest.raises(InvalidModelError, match="above"):
        MultislopePI([15.1], [1], a=0.9, h=0.0)


def test_multislope_input_range_beyond_U_breaks_envelope_order():
    # above U the rising envelope (slope b) overtakes the falling one (slope a)
    with pytest.raises(InvalidModelError, match="rising envelope above falling"):
        MultislopePI([40.0], [1.0], input_range=(0.0, 400.0))


def test_pwl_validation():
    x = [0.0, 150.0]
    with pytest.raises(InvalidModelError, match="rising envelope above falling"):
        PiecewiseLinearPI([(x, [0, 100])], [(x, [10, 90])], [1.0])
    with pytest.raises(InvalidModelError, match="strictly increasing"):
        PiecewiseLinearPI([([0, 0], [0, 1])], [(x, [10, 160])], [1.0])
    with pytest.raises(InvalidModelError, match="non-decreasing"):
        PiecewiseLinearPI([(x, [1, 0])], [(x, [10, 160])], [1.0])
    with pytest.raises(InvalidModelError, match="one rising and one falling"):
        PiecewiseLinearPI([(x, [0, 1])], [(x, [10, 160])], [1.0, 2.0])


def test_predict_rejects_input_outside_range_and_nan():
    m = ClassicalPI([0, 10], [1, 1])
    with pytest.raises(pihyst.InputRangeError, match="sample 2: input 151"):
        m.predict([0, 10, 151])
    with pytest.raises(pihyst.InputRangeError, match="sample 1: input nan"):
        m.predict([0, math.nan])
    with pytest.raises(ValueError, match="one-dimensional"):
        m.predict(np.zeros((2, 2)))
    with pytest.raises(pihyst.InputRangeError):
        m.stepper().step(-1.0)


def test_models_are_immutable_value_objects():
    m = ClassicalPI([0, 10], [1, 1])
    with pytest.raises(ValueError):
        m.weights[0] = 5.0
    m2 = m.replace(weights=[2, 2])
    assert m2.weights.tolist() == [2, 2] and m.weights.tolist() == [1, 1]
    assert m2.thresholds.tolist() == [0, 10]


def test_predict_empty_signal():
    assert ClassicalPI([0], [1]).predict([]).shape == (0,)
