"""The paper's own numbers (docs/paper.md) as exact tests."""

import numpy as np
import pytest

import pihyst

CYCLE = np.r_[np.arange(0.0, 151.0), np.arange(149.0, -1.0, -1.0)]  # 0 -> 150 -> 0 V


def table1_classical():
    return pihyst.ClassicalPI([0, 10, 30, 150], [0.008, 0.252, 0.019, 0.582])


def table1_multislope():
    return pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])


def test_conventional_pi_of_table1():
    y = table1_classical().predict(CYCLE)
    assert y[150] == pytest.approx(38.76, abs=1e-12)
    # back at 0 V the model is 3.09 um above the beam, which returns to 0:
    # the paper's -3.09 um extreme low-voltage error
    assert y[-1] == pytest.approx(3.09, abs=1e-12)


def test_r150_operator_never_leaves_zero():
    phi = table1_classical().operators(CYCLE)
    assert np.all(phi[:, 3] == 0.0)


def test_multislope_pi_of_table1():
    y = table1_multislope().predict(CYCLE)
    assert y[150] == pytest.approx(41.38, abs=1e-12)
    assert abs(y[-1]) <= 1e-12


def test_multislope_r40_operator_kinks():
    op = pihyst.MultislopePI([40.0], [1.0])
    # rising envelope: slope 0.8, kink at 75 + r/2 = 95 V, then slope 1.2 up to U - r
    u_up = np.linspace(0, 150, 1501)
    y_up = op.predict(u_up)
    slopes = np.diff(y_up) / np.diff(u_up)
    assert np.allclose(slopes[(u_up[1:] > 40.5) & (u_up[1:] < 95)], 0.8)
    assert np.allclose(slopes[u_up[:-1] >= 95], 1.2)
    assert y_up[-1] == pytest.approx(110.0)  # R(U) = U - r
    # falling from 150 V: holds at 110 down to U - h r = 130 V, then slope 0.8
    # until the falling kink at 75 - 1.5 r = 15 V, then slope 1.2 to the origin
    u_down = np.linspace(150, 0, 1501)
    y_down = op.predict(np.r_[u_up, u_down])[u_up.size:]
    hold = u_down >= 130
    assert np.all(y_down[hold] == pytest.approx(110.0))
    s = np.diff(y_down) / np.diff(u_down)
    assert np.allclose(s[(u_down[1:] < 129.9) & (u_down[:-1] > 15)], 0.8)
    assert np.allclose(s[u_down[:-1] <= 15], 1.2)
    assert abs(y_down[-1]) <= 1e-12  # every multislope operator returns to the origin


def test_multislope_r0_is_hysteretic_unlike_classical_r0():
    rise, fall = pihyst.MultislopePI([0.0], [1.0]).envelopes(75.0)
    assert (rise[0], fall[0]) == pytest.approx((60.0, 90.0))
    rise, fall = pihyst.ClassicalPI([0.0], [1.0]).envelopes(75.0)
    assert rise[0] == fall[0] == 75.0


def test_multislope_threshold_limit_is_50V_for_the_paper_shape():
    assert pihyst.MultislopePI([50.0], [1.0]).max_threshold == pytest.approx(50.0)
    with pytest.raises(pihyst.InvalidModelError, match="above .*= 50"):
        pihyst.MultislopePI([0.0, 50.5], [1.0, 1.0])
