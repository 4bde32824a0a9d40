"""The C compensator's saturated-ramp search (KP models: every polyline flat, one rising
segment, flat) against the NumPy twin (pihyst._reference.Compensator, which lists every
breakpoint of each sample and interpolates: no search) and against the C generic path
on the same functions (each polyline given with a fifth point on a flat part, which the
core does not take for a ramp)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pihyst import _core, _reference

U = 150.0


def ramp(lo_x, width, lo_y, hi_y):
    """flat at lo_y up to lo_x, rising to hi_y at lo_x + width, flat beyond"""
    x = np.array([lo_x - 10.0, lo_x, lo_x + width, lo_x + width + 10.0])
    return x, np.array([lo_y, lo_y, hi_y, hi_y])


def with_fifth_point(x, y):
    """the same function with a point on the low flat part: the generic polyline path"""
    return np.r_[x[0], 0.5 * (x[0] + x[1]), x[1:]], np.r_[y[0], y]


def kp_params(k, seed, grid=None):
    """K random ramps R above F (F's switching voltage <= R's, same heights). With `grid`
    the switching voltages come from `grid` values (coincident breakpoints, as identify
    builds them); some weights are zero and some ramps flat (height 0)."""
    rng = np.random.default_rng(seed)
    rising, falling = [], []
    for i in range(k):
        width = rng.choice([0.5, 5.0, 20.0]) if grid is None else U / grid
        if grid is None:
            a, b = np.sort(rng.uniform(-20.0, U + 10.0, 2))
        else:
            a, b = np.sort(rng.integers(0, grid + 1, 2)) * U / grid - 0.5 * width
        lo_y = rng.choice([0.0, -0.5])
        hi_y = lo_y if i % 7 == 3 else lo_y + rng.uniform(0.1, 2.0)
        rising.append(ramp(b, width, lo_y, hi_y))
        falling.append(ramp(a, width, lo_y, hi_y))
    w = rng.uniform(0.0, 1.0, k)
    w[rng.random(k) < 0.15] = 0.0
    return dict(family="pwl", thresholds=None, weights=w, rising=rising, falling=falling,
                offset=0.3, u_min=0.0, u_max=U)


def generic(params):
    return dict(params, rising=[with_fifth_point(*p) for p in params["rising"]],
                falling=[with_fifth_point(*p) for p in params["falling"]])


def desired(y_lo, y_hi, n, seed):
    rng = np.random.default_rng(seed)
    span = y_hi - y_lo
    t = np.arange(n)
    walk = np.cumsum(rng.normal(0, 0.03 * span, n)) + y_lo + 0.4 * span
    garbage = rng.uniform(y_lo, y_hi, n)
    idx = rng.choice(n, n // 8, replace=False)
    garbage[idx] = rng.choice([np.nan, np.inf, -np.inf, 1e300, y_lo - 1, y_hi + 1], idx.size)
    return {
        "random_walk": walk,
        "ramps": y_lo + span * np.abs(((t * 0.013) % 2.0) - 1.0),
        "decaying_sine": y_lo + span * (0.5 + 0.45 * np.sin(0.15 * t) * np.exp(-t / 150)),
        "uniform_noise": rng.uniform(y_lo - 0.05 * span, y_hi + 0.05 * span, n),
        "garbage": garbage,
    }


LIMITS = {"full": (0.0, U, np.inf), "limits_and_slew": (10.0, 140.0, 15.0),
          "tight_slew": (0.0, U, 0.7)}
MODELS = [(k, seed, grid) for k, seed, grid in
          ((1, 1, None), (5, 2, None), (16, 3, None), (60, 4, 12), (132, 5, 15))]


def assert_same(u_a, y_a, fl_a, u_b, y_b, fl_b, y_d, tol, case):
    """Same voltages (1e-9), outputs and flags; except that on a flat stretch whose level
    is y_d to rounding either end is an exact answer (the model's output there meets y_d
    within the tolerance in both runs, and no operator moves across it)."""
    np.testing.assert_array_equal(fl_a, fl_b, err_msg=case)
    np.testing.assert_allclose(y_a, y_b, rtol=0, atol=1e-9, err_msg=case)
    differ = np.abs(u_a - u_b) > 1e-9
    assert np.all(np.abs(y_a[differ] - y_d[differ]) <= tol), case
    assert np.all(np.abs(y_b[differ] - y_d[differ]) <= tol), case


def assert_met(u, y, fl, y_d, u_min, u_max, step, case):
    """Unflagged samples meet y_d (to 1e-9: the output's rounding plus the voltage's, an
    ulp of u times a slope of up to a few per volt); voltages in the limits and slew."""
    ok = fl == 0
    assert np.all(np.abs(y[ok] - y_d[ok]) <= 1e-9), case
    assert np.all((u >= u_min) & (u <= u_max)), case
    assert np.all(np.abs(np.diff(np.r_[u_min, u])) <= step), case


def run_three(params, u_min, u_max, step, y_d, u0=None):
    """ramp search, C generic path, NumPy reference (K <= 24 only: O(K^2) per sample;
    for larger K the generic path, itself tested against the reference, stands in)"""
    u0 = u_min if u0 is None else u0
    out = []
    slow = (_reference, params) if len(params["weights"]) <= 24 else (_core, generic(params))
    for core, args in ((_core, params), (_core, generic(params)), slow):
        comp = core.Compensator(core.Bank(**args), u_min, u_max, step, u0)
        out.append((*comp.run(y_d), comp))
    return out


@pytest.mark.parametrize("limits", LIMITS, ids=str)
@pytest.mark.parametrize("k,seed,grid", MODELS, ids=[f"K{k}-{seed}" for k, seed, _ in MODELS])
def test_ramp_search_matches_reference_and_generic(k, seed, grid, limits):
    u_min, u_max, step = LIMITS[limits]
    params = kp_params(k, seed, grid)
    y_at = _core.Bank(**params).run(np.linspace(0, U, 301))
    for name, y_d in desired(y_at.min(), y_at.max(), 150, seed).items():
        (u_r, y_r, fl_r, fast), (u_g, y_g, fl_g, _), (u_s, y_s, fl_s, slow) = run_three(
            params, u_min, u_max, step, y_d)
        case = f"K={k} {limits} {name}"
        for u, y, fl, what in ((u_g, y_g, fl_g, "generic"), (u_s, y_s, fl_s, "reference")):
            assert_same(u_r, y_r, fl_r, u, y, fl, y_d, fast.tolerance, f"{case} vs {what}")
        np.testing.assert_allclose(fast.state, slow.state, rtol=0, atol=1e-9, err_msg=case)
        assert_met(u_r, y_r, fl_r, y_d, u_min, u_max, step, case)
        # the state is the model's own for those voltages, bit for bit, and the outputs
        # are the model's within half the equality band (the compensator steps only the
        # ramps between two voltages and keeps the output as a running sum)
        bank = _core.Bank(**params)
        bank.run(np.r_[u_min])
        np.testing.assert_allclose(bank.run(u_r), y_r, rtol=0, atol=0.5 * fast.tolerance,
                                   err_msg=case)
        np.testing.assert_array_equal(bank.state, fast.state, err_msg=case)


def test_ramp_search_from_a_set_state():
    """From a state set by reset (not reached by running the model) the search agrees
    with the reference too: crossings anywhere on the ramps, operators above both."""
    params = kp_params(16, 9, None)
    rng = np.random.default_rng(9)
    y_d = rng.uniform(-3.0, 8.0, 120)
    for trial in range(5):
        state = rng.uniform(-0.6, 2.2, 16)
        u0 = rng.uniform(0.0, U)
        comps = [core.Compensator(core.Bank(**args), 0.0, U, np.inf, 0.0)
                 for core, args in ((_core, params), (_reference, params))]
        for comp in comps:
            comp.reset(state, u0)
        (u_f, y_f, fl_f), (u_s, y_s, fl_s) = (c.run(y_d) for c in comps)
        assert_same(u_f, y_f, fl_f, u_s, y_s, fl_s, y_d, comps[0].tolerance, str(trial))


@settings(max_examples=40, deadline=None)
@given(k=st.integers(1, 40), seed=st.integers(0, 2**32 - 1),
       grid=st.sampled_from([None, 4, 15]),
       u_min=st.sampled_from([0.0, 20.0]), step=st.sampled_from([np.inf, 3.0, 40.0]),
       n=st.integers(1, 80))
def test_ramp_search_property(k, seed, grid, u_min, step, n):
    """Any KP model, limits and signal: the ramp search gives the reference's voltages,
    outputs and flags; unflagged samples meet y_d; voltages in limits and slew."""
    params = kp_params(k, seed, grid)
    rng = np.random.default_rng(seed)
    y_at = _core.Bank(**params).run(np.linspace(0, U, 101))
    y_d = rng.uniform(y_at.min() - 0.2, y_at.max() + 0.2, n)
    y_d[rng.random(n) < 0.1] = np.nan
    (u_r, y_r, fl_r, fast), _, (u_s, y_s, fl_s, _) = run_three(params, u_min, U, step, y_d,
                                                                 u0=u_min)
    assert_same(u_r, y_r, fl_r, u_s, y_s, fl_s, y_d, fast.tolerance, "property")
    assert_met(u_r, y_r, fl_r, y_d, u_min, U, step, "property")


@settings(max_examples=25, deadline=None)
@given(k=st.integers(1, 40), seed=st.integers(0, 2**32 - 1),
       grid=st.sampled_from([None, 4, 15]), step=st.sampled_from([np.inf, 2.0]),
       jumps=st.floats(0.0, 1.0), n=st.integers(1, 400))
def test_ramp_model_step_property(k, seed, grid, step, jumps, n):
    """The compensator's own model step on a KP model visits only the ramps between two
    voltages and keeps the output as a running sum: over long runs mixing tracking and
    jumps, its state is the NumPy model's for the same voltages (to rounding; the C
    model step's bit for bit) and its outputs the NumPy model's within the equality
    band."""
    params = kp_params(k, seed, grid)
    rng = np.random.default_rng(seed)
    y_at = _core.Bank(**params).run(np.linspace(0, U, 101))
    y_lo, y_hi = y_at.min(), y_at.max()
    walk = y_lo + np.abs(np.cumsum(rng.normal(0, 0.02 * (y_hi - y_lo), n)))
    y_d = np.where(rng.random(n) < jumps, rng.uniform(y_lo, y_hi, n), walk)
    comp = _core.Compensator(_core.Bank(**params), 0.0, U, step, 0.0)
    u, y, _ = comp.run(y_d)
    twin = _reference.Bank(**params)
    twin.run(np.r_[0.0])
    y_twin = twin.run(u)
    scale = 1.0 + np.abs(y_twin).max()
    np.testing.assert_allclose(y, y_twin, rtol=0, atol=comp.tolerance + 1e-12 * scale)
    np.testing.assert_allclose(comp.state, twin.state, rtol=0, atol=1e-12)
    bank = _core.Bank(**params)
    bank.run(np.r_[0.0])
    np.testing.assert_allclose(bank.run(u), y, rtol=0, atol=0.5 * comp.tolerance)
    np.testing.assert_array_equal(bank.state, comp.state)
