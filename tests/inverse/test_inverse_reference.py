"""The C compensator against its NumPy twin (pihyst._reference.Compensator), which solves
each sample independently: all breakpoints of y(u) listed and evaluated by the model
formula, then one linear interpolation (no segment walk, no event sort)."""

import numpy as np
import pytest

from pihyst import _core, _reference

from strategies import U

N = 250


def classical_params(k):
    r = np.linspace(0.0, U, k, endpoint=False)
    w = np.random.default_rng(k).uniform(0.0, 0.5, k)
    return {"family": "classical", "thresholds": r, "weights": w}


def multislope_params(k):
    r = np.linspace(0.0, 50.0, k) if k > 1 else np.array([20.0])
    w = np.random.default_rng(k + 100).uniform(0.0, 0.5, k)
    return {"family": "multislope", "thresholds": r, "weights": w, "shape": (U, 0.8, 1.2, 0.5)}


def pwl_params(k):
    """Random polylines with flat stretches, some shorter than the range (extensions)."""
    rng = np.random.default_rng(k + 200)
    rising, falling = [], []
    for _ in range(k):
        x = np.r_[rng.uniform(0, 20), np.sort(rng.uniform(21, U - 21, 3)), rng.uniform(U - 20, U)]
        r = np.cumsum(rng.choice([0.0, 1.0], x.size) * rng.uniform(0, 30, x.size)) - 10
        # F = R + gap, gap non-decreasing and equal on the end segments, so that the
        # extensions beyond the ends run parallel and R <= F everywhere
        gap = np.sort(rng.uniform(0, 25, x.size))
        gap[1], gap[-2] = gap[0], gap[-1]
        f = r + gap
        rising.append((x, r))
        falling.append((x, f))
    w = rng.uniform(0, 1, k)
    w[0] = 0.0 if k > 2 else w[0]  # a zero weight
    return {"family": "pwl", "thresholds": None, "weights": w, "rising": rising,
            "falling": falling}


PARAMS = ([("classical", k, classical_params(k)) for k in (1, 4, 16)]
          + [("multislope", k, multislope_params(k)) for k in (1, 4, 16)]
          + [("pwl", k, pwl_params(k)) for k in (1, 3, 8)])


def desired_signals(y_lo, y_hi, seed):
    rng = np.random.default_rng(seed)
    span = y_hi - y_lo
    t = np.arange(N)
    walk = np.cumsum(rng.normal(0, 0.04 * span, N)) + y_lo + 0.3 * span
    garbage = rng.uniform(y_lo, y_hi, N)
    idx = rng.choice(N, 30, replace=False)
    garbage[idx] = rng.choice([np.nan, np.inf, -np.inf, 1e300, -1e300, y_lo - 1, y_hi + 1], 30)
    return {
        "random_walk": walk,
        "decaying_sine": y_lo + span * (0.5 + 0.45 * np.sin(0.15 * t) * np.exp(-t / 150)),
        "uniform_noise": rng.uniform(y_lo - 0.05 * span, y_hi + 0.05 * span, N),
        "garbage": garbage,
    }


LIMITS = {"full": (0.0, U, np.inf), "limits_and_slew": (10.0, 140.0, 15.0)}


@pytest.mark.parametrize("limits", LIMITS, ids=str)
@pytest.mark.parametrize("family,k,params", PARAMS, ids=[f"{f}-K{k}" for f, k, _ in PARAMS])
def test_compensator_matches_reference(family, k, params, limits):
    u_min, u_max, step = LIMITS[limits]
    args = dict(params, offset=0.25, u_min=0.0, u_max=U)
    y_at = _core.Bank(**args).run(np.linspace(0, U, 301))
    for name, y_d in desired_signals(y_at.min(), y_at.max(), seed=k).items():
        fast = _core.Compensator(_core.Bank(**args), u_min, u_max, step, u_min)
        slow = _reference.Compensator(_reference.Bank(**args), u_min, u_max, step, u_min)
        assert fast.tolerance == pytest.approx(slow.tolerance, rel=1e-12)
        u_f, y_f, fl_f = fast.run(y_d)
        u_s, y_s, fl_s = slow.run(y_d)
        case = f"{family} K={k} {limits} {name}"
        np.testing.assert_allclose(u_f, u_s, rtol=0, atol=1e-9, err_msg=case)
        np.testing.assert_allclose(y_f, y_s, rtol=0, atol=1e-9, err_msg=case)
        np.testing.assert_array_equal(fl_f, fl_s, err_msg=case)
        np.testing.assert_allclose(fast.state, slow.state, rtol=0, atol=1e-9, err_msg=case)
        assert np.all((u_f >= u_min) & (u_f <= u_max))
        assert np.all(np.abs(np.diff(np.r_[u_min, u_f])) <= step)


def test_reference_step_reset_and_validation():
    args = dict(multislope_params(4), offset=0.0, u_min=0.0, u_max=U)
    fast = _core.Compensator(_core.Bank(**args), 0.0, U, np.inf, 30.0)
    slow = _reference.Compensator(_reference.Bank(**args), 0.0, U, np.inf, 30.0)
    for y in (5.0, 12.0, np.nan, 3.0, 1e9):
        assert fast.step(y) == pytest.approx(slow.step(y), abs=1e-9)
        assert fast.last_flags == slow.last_flags
    state = np.array([10.0, 5.0, 1.0, 0.0])
    fast.reset(state, 40.0)
    slow.reset(state, 40.0)
    np.testing.assert_allclose(fast.state, slow.state, atol=1e-12)
    assert fast.voltage == slow.voltage == 40.0
    assert fast.output == pytest.approx(slow.output, abs=1e-12)
    for c, err in ((fast, _core.CoreError), (slow, _reference.CoreError)):
        with pytest.raises(err):
            c.reset(None, 151.0)
        with pytest.raises(err):
            c.reset([np.nan, 0, 0, 0], 1.0)
    neg = dict(args, weights=[0.1, -0.1, 0.1, 0.1])
    with pytest.raises(_core.CoreError, match="non-negative"):
        _core.Compensator(_core.Bank(**neg), 0.0, U, np.inf, 0.0)
    with pytest.raises(_reference.CoreError, match="non-negative"):
        _reference.Compensator(_reference.Bank(**neg), 0.0, U, np.inf, 0.0)
    with pytest.raises(_core.CoreError, match="limits"):
        _core.Compensator(_core.Bank(**args), 0.0, 200.0, np.inf, 0.0)
    with pytest.raises(_core.CoreError, match="slew"):
        _core.Compensator(_core.Bank(**args), 0.0, U, 0.0, 0.0)
