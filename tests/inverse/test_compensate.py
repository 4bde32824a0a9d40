"""pihyst.compensate and pihyst.Compensator: exact round trip on reachable trajectories
(Hypothesis, all three families), limits and slew limit under any input, step == run,
chunked == whole, hold on flat stretches, validation."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pihyst
from pihyst import Compensator, compensate
from pihyst.exceptions import InvalidArgumentError
from pihyst.inverse import FLAG_NAN, FLAG_SATURATED_HIGH, FLAG_SATURATED_LOW, FLAG_SLEW

from strategies import U, classical_models, multislope_models, pwl_models, random_walk

PAPER_CLASSICAL = pihyst.load_model("examples/paper_table1_classical.json")
PAPER_MULTISLOPE = pihyst.load_model("examples/paper_table1_multislope.json")

SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])


@st.composite
def voltage_walks(draw, lo=0.0, hi=U):
    """Voltages with many reversals of every size (minor loops), now and then at a limit."""
    n = draw(st.integers(1, 120))
    points = draw(st.lists(st.one_of(st.floats(lo, hi), st.sampled_from([lo, hi])),
                           min_size=n, max_size=n))
    return np.array(points)


def reachable(model, u, initial_voltage=0.0):
    """The model's output for u, from its initial state with initial_voltage applied first
    (as the compensator starts)."""
    return model.predict(np.r_[initial_voltage, u])[1:]


def steepness(model):
    """sum_k w_k max |slope of operator k's envelopes| (1 + ... for classical: slopes 1)."""
    if model.family != "pwl":
        return float(np.sum(model.weights) * max(getattr(model, "b", 1.0), 1.0))
    return float(sum(w * max(np.max(np.abs(np.diff(y) / np.diff(x)), initial=0.0)
                             for x, y in (r, f))
                     for w, r, f in zip(model.weights, model.rising, model.falling)))


def assert_round_trip(model, u):
    """predict(compensate(y_d)) == y_d to 1e-9 um. A model's own output is only defined
    to about (its steepest slope) x (a voltage's rounding): polylines with near-vertical
    segments (which the pwl strategy draws, e.g. 1e-5 V wide) get that much more."""
    y_d = reachable(model, u)
    result = compensate(model, y_d)
    conditioning = 64 * np.finfo(float).eps * steepness(model) * U
    np.testing.assert_allclose(result.displacement, y_d, rtol=0, atol=1e-9 + conditioning)
    # the displacement is the model's own prediction for the voltages
    np.testing.assert_array_equal(
        model.predict(result.voltage, initial_state=result.initial_state), result.displacement)
    lo, hi = model.input_range
    assert np.all((result.voltage >= lo) & (result.voltage <= hi))
    # a flag only where the voltage sits at a limit (rounding at the very top or bottom)
    assert np.all(np.isin(result.voltage[result.flags != 0], [lo, hi]))
    return result


@SETTINGS
@given(classical_models(), voltage_walks())
def test_round_trip_classical(model, u):
    assert_round_trip(model, u)


@SETTINGS
@given(multislope_models(), voltage_walks())
def test_round_trip_multislope(model, u):
    assert_round_trip(model, u)


@SETTINGS
@given(pwl_models(), voltage_walks())
def test_round_trip_pwl(model, u):
    assert_round_trip(model, u)


@SETTINGS
@given(st.one_of(classical_models(), multislope_models(), pwl_models()), voltage_walks(),
       st.data())
def test_round_trip_from_any_state(model, u, data):
    """From an arbitrary operator state (set, not reached from rest): its breakpoints
    arrive out of operator order, are sorted, and the inverse is exact all the same."""
    k = model.n_operators
    state = np.array(data.draw(st.lists(st.floats(-60, 220), min_size=k, max_size=k)))
    u0 = data.draw(st.floats(0.0, U))
    y_d = model.predict(np.r_[u0, u], initial_state=state)[1:]
    result = compensate(model, y_d, initial_state=state, initial_voltage=u0)
    conditioning = 64 * np.finfo(float).eps * steepness(model) * U
    np.testing.assert_allclose(result.displacement, y_d, rtol=0, atol=1e-9 + conditioning)
    assert np.all(np.isin(result.voltage[result.flags != 0], [0.0, U]))


@pytest.mark.parametrize("family", ["classical", "multislope"])
def test_noise_long_run(family):
    """A random voltage every sample (a reversal nearly every time), many operators."""
    rng = np.random.default_rng(5)
    k = 48
    w = rng.uniform(0.0, 0.05, k)
    if family == "classical":
        model = pihyst.ClassicalPI(np.sort(rng.uniform(0, U, k)), w)
    else:
        model = pihyst.MultislopePI(np.sort(rng.uniform(0, 50, k)), w)
    u = rng.uniform(0, U, 4000)
    assert_round_trip(model, u)


@pytest.mark.parametrize("model", [PAPER_CLASSICAL, PAPER_MULTISLOPE], ids=["classical",
                                                                             "multislope"])
def test_round_trip_paper_models_long_walk(model):
    u = random_walk(5000, seed=7, step=3.0)
    result = assert_round_trip(model, u)
    assert np.max(np.abs(result.displacement - reachable(model, u))) <= 1e-12 * 45
    if model.family == "classical":  # strictly increasing: the voltage itself comes back
        np.testing.assert_allclose(result.voltage, u, rtol=0, atol=1e-9)


DESIRED_ANY = st.lists(st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([np.nan, np.inf, -np.inf, 1e300, -1e300, 0.0, 20.0, 41.38]),
    st.floats(-10, 60)), min_size=1, max_size=150)


@SETTINGS
@given(DESIRED_ANY,
       st.floats(0, 140), st.floats(1, 150), st.one_of(st.none(), st.floats(1e-3, 200)),
       st.floats(0, 1), st.sampled_from([PAPER_CLASSICAL, PAPER_MULTISLOPE]))
def test_limits_and_slew_hold_for_any_input(desired, lo, width, slew, start, model):
    hi = min(lo + width, 150.0)
    u0 = lo + start * (hi - lo)
    y_d = np.array(desired)
    result = compensate(model, y_d, u_min=lo, u_max=hi, slew_rate=slew,
                        sample_period=1.0, initial_voltage=u0)
    u = result.voltage
    assert np.all((u >= lo) & (u <= hi))
    if slew is not None:
        assert np.all(np.abs(np.diff(np.r_[u0, u])) <= slew)
    previous = np.r_[u0, u[:-1]]
    nan = np.isnan(y_d)
    np.testing.assert_array_equal(result.nan_held, nan)
    np.testing.assert_array_equal(u[nan], previous[nan])
    slewed = result.slew_limited
    # out of reach: at the limit, or moving toward it when the slew limit cut it short
    high, low = result.saturated_high, result.saturated_low
    assert np.all(u[high & ~slewed] == hi) and np.all(u[low & ~slewed] == lo)
    assert np.all(u[high & slewed] > previous[high & slewed])
    assert np.all(u[low & slewed] < previous[low & slewed])
    assert not (high & low).any()
    assert np.all(y_d[high] > result.displacement[high])
    assert np.all(y_d[low] < result.displacement[low])
    if slew is None:
        assert not slewed.any()
    else:  # moved by the full slew limit, to the rounding of the voltages
        ulp = np.spacing(np.maximum(np.abs(u), np.abs(previous)))
        assert np.all(np.abs(u - previous)[slewed] >= (slew - 4 * ulp)[slewed])
    reached = result.reached
    np.testing.assert_allclose(result.displacement[reached], y_d[reached], rtol=0, atol=1e-9)
    assert np.count_nonzero(result.saturated | slewed | result.nan_held) == np.count_nonzero(
        result.flags)


@SETTINGS
@given(st.sampled_from([PAPER_CLASSICAL, PAPER_MULTISLOPE]), DESIRED_ANY,
       st.one_of(st.none(), st.floats(0.5, 20)), st.data())
def test_step_equals_run_and_chunked_equals_whole(model, desired, slew, data):
    y_d = np.array(desired)
    comp = Compensator(model, slew_rate=slew, sample_period=1.0)
    whole = comp.run(y_d)
    comp.reset()
    stepped = []
    for v in y_d:
        stepped.append((comp.step(v), comp.displacement, comp.last_flags))
    u, y, flags = (np.array(c) for c in zip(*stepped))
    np.testing.assert_array_equal(u, whole.voltage)
    np.testing.assert_array_equal(y, whole.displacement)
    np.testing.assert_array_equal(flags, whole.flags)
    # chunks through one compensator: bit for bit
    k = data.draw(st.integers(0, y_d.size))
    comp.reset()
    first, second = comp.run(y_d[:k]), comp.run(y_d[k:])
    np.testing.assert_array_equal(np.r_[first.voltage, second.voltage], whole.voltage)
    np.testing.assert_array_equal(np.r_[first.flags, second.flags], whole.flags)
    np.testing.assert_array_equal(second.final_state, whole.final_state)
    # a new compensator from the explicit state (operator state, last voltage): the same
    # to rounding (the running one keeps its sorted breakpoints and slope sum)
    restarted = compensate(model, y_d[k:], slew_rate=slew,
                           sample_period=1.0, initial_state=first.final_state,
                           initial_voltage=first.final_voltage)
    np.testing.assert_allclose(restarted.voltage, whole.voltage[k:], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(restarted.flags, whole.flags[k:])


def test_flat_stretch_holds_after_a_maximum():
    """Multislope operators hold their output for h r volts after a maximum: a desired
    displacement that stays at its maximum holds the voltage at the top instead of
    jumping to the other end of the flat stretch (docs/theory/inverse.md)."""
    model = pihyst.MultislopePI([10, 20, 40], [0.2, 0.1, 0.05])
    u = np.r_[np.arange(0.0, 151.0), np.linspace(149.875, 145.125, 39)]
    y_d = model.predict(u)
    assert np.all(y_d[150:] == y_d[150])  # flat while the voltage falls to 145.125 V
    result = compensate(model, y_d)
    np.testing.assert_allclose(result.voltage[150], 150.0, atol=1e-9)
    assert np.all(result.voltage[150:] == result.voltage[150])
    # the first small decrease crosses the flat stretch to where the output falls (145 V)
    comp = Compensator(model, initial_state=result.final_state,
                       initial_voltage=result.final_voltage)
    assert 145.0 - 1e-3 < comp.step(y_d[150] - 1e-6) < 145.0


def test_flat_stretch_after_reversal_with_paper_model():
    """At a reversal every multislope operator is flat (even r = 0: its envelopes differ):
    an unchanged desired value keeps the voltage."""
    model = PAPER_MULTISLOPE
    u = np.r_[np.linspace(0, 100, 101), np.linspace(99, 60, 40)]
    y_d = model.predict(u)
    result = compensate(model, np.r_[y_d[:101], np.full(20, y_d[100])])
    assert np.all(result.voltage[100:] == result.voltage[100])
    np.testing.assert_allclose(result.voltage[100], 100.0, atol=1e-9)


def test_saturation_is_counted_and_flagged():
    result = compensate(PAPER_MULTISLOPE, [10.0, 100.0, np.inf, np.nan, -5.0, 1e300, -np.inf])
    np.testing.assert_array_equal(result.flags, [0, FLAG_SATURATED_HIGH, FLAG_SATURATED_HIGH,
                                                 FLAG_NAN, FLAG_SATURATED_LOW,
                                                 FLAG_SATURATED_HIGH, FLAG_SATURATED_LOW])
    np.testing.assert_array_equal(result.voltage[1:], [150, 150, 150, 0, 150, 0])
    assert result.n_saturated == 5 and result.n_nan == 1 and result.n_slew_limited == 0
    np.testing.assert_array_equal(result.saturated, [0, 1, 1, 0, 1, 1, 1])
    assert result.displacement[1] == pytest.approx(41.38, abs=1e-12)


def test_slew_limit_flags():
    result = compensate(PAPER_CLASSICAL, [30.0] * 20, slew_rate=10.0, sample_period=1.0)
    assert np.all(np.diff(np.r_[0.0, result.voltage]) <= 10.0)
    assert result.slew_limited[0] and not result.slew_limited[-1]
    assert result.flags[0] == FLAG_SLEW
    assert result.displacement[-1] == pytest.approx(30.0, abs=1e-12)


def test_reset_to_a_state_alone_continues_from_the_voltage_it_pins():
    # the zero threshold pins the voltage: the compensator reset to the state of one that
    # ran (slew-limited, so its last voltage is not the last target's) goes on with the
    # same voltages, NaN holds and slew steps included
    model = pihyst.ClassicalPI([0, 10, 30], [0.3, 0.2, 0.1])
    ran = Compensator(model, slew_rate=3.0, sample_period=1.0)
    ran.run(model.predict(np.r_[np.linspace(0, 100, 30), np.linspace(100, 60, 10)]))
    reset = Compensator(model, slew_rate=3.0, sample_period=1.0)
    reset.step(5.0)
    reset.reset(ran.state)
    assert reset.voltage == ran.voltage and reset.displacement == ran.displacement
    np.testing.assert_array_equal(reset.state, ran.state)
    targets = [10.0, 11.0, np.nan, 12.0, 9.0, 30.0, 30.0]
    assert [reset.step(y) for y in targets] == [ran.step(y) for y in targets]


def test_reset_to_a_state_at_rest_at_a_limit_only():
    # after a full cycle down to 0 V the paper's multislope state is at rest at 0 V alone
    # within the limits
    ran = Compensator(PAPER_MULTISLOPE)
    ran.run(PAPER_MULTISLOPE.predict(np.r_[np.linspace(0, 150, 50), np.linspace(150, 0, 50)]))
    reset = Compensator(PAPER_MULTISLOPE)
    reset.step(20.0)
    reset.reset(ran.state)
    assert reset.voltage == pytest.approx(ran.voltage, abs=1e-13)
    np.testing.assert_array_equal(reset.state, ran.state)
    assert reset.step(12.5) == pytest.approx(ran.step(12.5), abs=1e-12)


@pytest.mark.parametrize("state,says", [
    # a multislope state after a fall to 60 V: at rest up to 85 V (its zero-threshold
    # operator has a play band), so the last voltage is not known
    ("fallen", r"at rest at every voltage in \[60, 85\] V.*reset\(state, voltage\)"),
    ([140.0, 0.0, 0.0, 0.0], r"at rest at no voltage within the limits \[0, 150\] V"),
])
def test_reset_refuses_a_state_that_does_not_say_the_voltage(state, says):
    comp = Compensator(PAPER_MULTISLOPE)
    if state == "fallen":
        comp.run(PAPER_MULTISLOPE.predict(np.r_[np.linspace(0, 100, 30),
                                                np.linspace(100, 60, 10)]))
        state = comp.state
    before = comp.state, comp.voltage
    with pytest.raises(InvalidArgumentError, match=says):
        comp.reset(state)
    np.testing.assert_array_equal(comp.state, before[0])     # left as it was
    assert comp.voltage == before[1]
    comp.reset(state, 70.0)                                    # with the voltage: as asked
    assert comp.voltage == 70.0

def test_streaming_state_and_reset():
    comp = Compensator(PAPER_MULTISLOPE, initial_voltage=0.0)
    assert comp.voltage == 0.0 and comp.displacement == 0.0
    u1 = comp.step(20.0)
    state, v = comp.state, comp.voltage
    assert v == u1 and comp.displacement == pytest.approx(20.0, abs=1e-12)
    comp.step(5.0)
    comp.reset(state, v)
    np.testing.assert_array_equal(comp.state, state)
    assert comp.step(5.0) == pytest.approx(
        Compensator(PAPER_MULTISLOPE, initial_state=state, initial_voltage=v).step(5.0), abs=0)
    comp.reset()
    assert comp.voltage == 0.0 and np.all(comp.state == 0)
    with pytest.raises(ValueError, match="outside the limits"):
        comp.reset(voltage=200.0)
    assert "Compensator(MultislopePI" in repr(comp)


def test_default_initial_voltage_is_zero_or_nearest_limit():
    assert Compensator(PAPER_CLASSICAL).voltage == 0.0
    assert Compensator(PAPER_CLASSICAL, u_min=20.0).voltage == 20.0
    bipolar = pihyst.ClassicalPI([0, 10], [0.1, 0.1], input_range=(-150, 150))
    assert Compensator(bipolar).voltage == 0.0
    assert Compensator(bipolar, u_max=-10.0).voltage == -10.0


def test_inputs_not_modified():
    y_d = np.array([1.0, 10.0, np.nan, 30.0])
    state = np.zeros(4)
    copy_y, copy_s = y_d.copy(), state.copy()
    compensate(PAPER_MULTISLOPE, y_d, initial_state=state)
    np.testing.assert_array_equal(y_d, copy_y)
    np.testing.assert_array_equal(state, copy_s)


@pytest.mark.parametrize("kwargs,match", [
    ({"u_min": -1.0}, "inside the model's input range"),
    ({"u_max": 151.0}, "inside the model's input range"),
    ({"u_min": 50.0, "u_max": 50.0}, "u_min < u_max"),
    ({"u_min": float("nan")}, "finite"),
    ({"slew_rate": 0.0}, "slew_rate must be > 0"),
    ({"slew_rate": -1.0}, "slew_rate must be > 0"),
    ({"slew_rate": "fast"}, "must be a number"),
    ({"initial_voltage": 160.0}, "outside the voltage limits"),
    ({"initial_state": [0.0, 1.0]}, "initial_state must have 4 values"),
])
def test_bad_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Compensator(PAPER_MULTISLOPE, **kwargs)


def test_negative_weights_rejected_with_hint():
    inverse = PAPER_CLASSICAL.inverse()  # negative weights
    with pytest.raises(pihyst.InvalidModelError, match="non-negative weights.*inverse"):
        compensate(inverse, [1.0])
    with pytest.raises(TypeError, match="pihyst model"):
        compensate("model.json", [1.0])
    with pytest.raises(ValueError, match="one-dimensional"):
        compensate(PAPER_CLASSICAL, [[1.0, 2.0]])
    with pytest.raises(ValueError, match="sequence of numbers"):
        compensate(PAPER_CLASSICAL, ["a"])


def test_empty_and_zero_weight_models():
    result = compensate(PAPER_CLASSICAL, [])
    assert result.voltage.size == 0 and result.final_voltage == 0.0
    flat = pihyst.ClassicalPI([0.0], [0.0], offset=2.0)
    result = compensate(flat, [2.0, 3.0, 1.0])
    np.testing.assert_array_equal(result.voltage, [0.0, 150.0, 0.0])
    np.testing.assert_array_equal(result.flags, [0, FLAG_SATURATED_HIGH, FLAG_SATURATED_LOW])


@pytest.mark.parametrize("model", [PAPER_CLASSICAL, PAPER_MULTISLOPE,
                                   pihyst.BoucWenModel(beta=0.5, gamma=0.2, hysteretic=10.0,
                                                       linear=30.0)], ids=lambda m: m.family)
def test_out_of_reach_is_flagged_when_the_slew_limit_cuts_the_sample_short(model):
    lo_y, hi_y = (float(v) for v in model.simulate([0.0, 150.0]).output)  # from the start
    desired = [lo_y, hi_y + 5, 1e308, np.inf, (lo_y + hi_y) / 2, lo_y - 5, -1e308]
    result = compensate(model, desired, slew_rate=2.0, sample_period=1.0)
    assert np.all(np.abs(np.diff(np.r_[0.0, result.voltage])) <= 2.0)
    np.testing.assert_array_equal(result.slew_limited, [0, 1, 1, 1, 1, 1, 1])
    np.testing.assert_array_equal(result.saturated_high, [0, 1, 1, 1, 0, 0, 0])
    np.testing.assert_array_equal(result.saturated_low, [0, 0, 0, 0, 0, 1, 1])
    assert result.n_saturated == 5 and result.flags[1] == FLAG_SATURATED_HIGH | FLAG_SLEW
    comp = Compensator(model, slew_rate=2.0, sample_period=1.0) if model.family != "bouc-wen" else \
        pihyst.BoucWenCompensator(model, slew_rate=2.0, sample_period=1.0)
    assert comp.step(hi_y + 5) == 2.0 and comp.last_flags == FLAG_SATURATED_HIGH | FLAG_SLEW
    assert comp.step(lo_y - 1) == 0.0 and comp.last_flags == FLAG_SATURATED_LOW



@pytest.mark.parametrize("model", [PAPER_CLASSICAL, PAPER_MULTISLOPE,
                                   pihyst.BoucWenModel(beta=0.5, gamma=0.2, hysteretic=10.0,
                                                       linear=30.0)], ids=lambda m: m.family)
def test_a_state_at_rest_at_the_top_starts_there(model):
    top = model.simulate([0.0, 150.0, 0.0, 150.0]).final_state
    comp = pihyst.inverse.compensator_for(model, initial_state=top, slew_rate=5.0,
                                          sample_period=1.0)
    assert comp.voltage == 150.0
    np.testing.assert_array_equal(comp.state, top)
    y_top = float(model.simulate([150.0], initial_state=top).output[0])
    assert comp.displacement == pytest.approx(y_top, abs=1e-12)
    mid = float(model.simulate([75.0], initial_state=top).output[-1])
    result = compensate(model, [mid] * 40, initial_state=top, slew_rate=5.0, sample_period=1.0)
    assert result.initial_voltage == 150.0 and result.voltage[0] == 145.0
    assert result.voltage[-1] == pytest.approx(75.0, abs=1e-9)    # the falling branch
    free = compensate(model, [mid], initial_state=top, initial_voltage=0.0)
    assert free.initial_voltage == 0.0                             # as asked: applied


def test_the_rest_voltage_of_a_state_is_nearest_the_default_and_inside_the_limits():
    from pihyst.inverse._compensator import rest_voltage
    m = pihyst.ClassicalPI([10.0, 30.0], [0.5, 0.5], input_range=(0.0, 150.0))
    top = m.simulate([0.0, 150.0]).final_state                     # [140, 120]: rests on [130, 150]
    assert rest_voltage(m, top, 0.0, 0.0, 150.0) == 130.0
    assert rest_voltage(m, top, 0.0, 0.0, 100.0) == 0.0            # not at rest within the limits
    assert rest_voltage(m, np.zeros(2), 0.0, 0.0, 150.0) == 0.0
    assert rest_voltage(m, np.array([140.0, 0.0]), 0.0, 0.0, 150.0) == 0.0   # rests nowhere
    assert Compensator(m, initial_state=top, u_max=140.0).voltage == 130.0
