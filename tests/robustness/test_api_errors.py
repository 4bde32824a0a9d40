"""The Python API raises pihyst's own exceptions (docs/errors.md) for invalid arguments:
never a bare TypeError, ZeroDivisionError, OverflowError or a NumPy error."""

import warnings

import numpy as np
import pytest

import pihyst
from pihyst.exceptions import InvalidArgumentError, ResourceLimitError
from pihyst.model import Creep
from pihyst.sim import make_plant, signals

CLASSICAL = {"thresholds": [0, 10], "weights": [0.5, 0.2]}


@pytest.mark.parametrize("changes", [
    {"weights": ["0.5", "0.2"]}, {"weights": [True, 0.2]}, {"weights": [10 ** 400, 1]},
    {"weights": [[0.5], [0.2]]}, {"weights": None}, {"weights": "05"}, {"weights": {}},
    {"weights": [0.5, float("nan")]}, {"weights": [1e306, 1e306]},
    {"thresholds": [0, "10"]}, {"thresholds": [10, 0]}, {"thresholds": [-1, 10]},
    {"offset": "1"}, {"offset": True}, {"offset": [1]}, {"offset": float("inf")},
    {"offset": 10 ** 400},
    {"input_range": "12"}, {"input_range": [0]}, {"input_range": [1, 0]},
    {"input_range": {"a": 0, "b": 1}}, {"input_range": [-1.7e308, 1.7e308]},
    {"initial_state": [0]}, {"initial_state": ["0", "0"]},
    {"units": ["V"]}, {"metadata": [1]},
])
def test_classical_constructor(changes):
    with pytest.raises(pihyst.InvalidModelError):
        pihyst.ClassicalPI(**{**CLASSICAL, **changes})


@pytest.mark.parametrize("shape", [
    {"a": 1.0, "b": 1.2, "h": 1.0}, {"a": 0.0}, {"a": 1.3}, {"h": -0.1}, {"h": 1.5},
    {"U": 0}, {"U": -1}, {"U": "150"}, {"U": 1.6e308}, {"b": float("nan")}, {"a": None},
])
def test_multislope_shape(shape):
    with pytest.raises(pihyst.InvalidModelError):
        pihyst.MultislopePI([0, 20], [0.1, 0.2], **shape)


@pytest.mark.parametrize("d", [
    {"family": "pwl", "weights": [1], "rising": "x", "falling": []},
    {"family": "pwl", "weights": [1], "rising": [[1, 2, 3]], "falling": [[1]]},
    {"family": "pwl", "weights": [1], "rising": [{"x": [0, 1], "y": ["a", 1]}],
     "falling": [{"x": [0, 1], "y": [0, 1]}]},
    {"family": "pwl", "weights": [1], "thresholds": [0],
     "rising": [{"x": [0, 150], "y": [0, 150]}], "falling": [{"x": [0, 150], "y": [0, 150]}]},
    {"family": ["classical"], "thresholds": [0], "weights": [1]},
    {"family": "classical", "thresholds": [0], "weights": [1], "schema_version": True},
    [], "classical", None,
])
def test_from_dict(d):
    with pytest.raises(pihyst.InvalidModelError):
        pihyst.load_model(d) if isinstance(d, dict) else pihyst.PIModel.from_dict(d)


@pytest.mark.parametrize("call", [
    lambda: signals.triangle(n_cycles=10 ** 8, dt=0.001),
    lambda: signals.triangle(period_s=1e300),
    lambda: signals.sine(dt=1e-300),
    lambda: signals.decaying_triangles(n_triangles=10 ** 9),
    lambda: signals.random_ramps(n_ramps=10 ** 9),
    lambda: signals.random_ramps(rate=1e-300),
    lambda: signals.staircase(n_steps=10 ** 9),
    lambda: signals.staircase(step_s=1e300),
])
def test_signals_too_long_are_refused_before_allocating(call):
    with pytest.raises(ResourceLimitError, match="samples"):
        call()


@pytest.mark.parametrize("call", [
    lambda: signals.triangle(n_cycles=0), lambda: signals.triangle(n_cycles=1.5),
    lambda: signals.triangle(n_cycles="3"), lambda: signals.triangle(dt=float("nan")),
    lambda: signals.triangle(dt=400.0), lambda: signals.triangle(u_min=True),
    lambda: signals.decaying_triangles(ratio=1.0),
    lambda: signals.random_ramps(seed=-1), lambda: signals.random_ramps(seed=1.5),
    lambda: signals.staircase(step_s=0),
    lambda: make_plant("paper-beam", seed=-1), lambda: make_plant("granite"),
    lambda: make_plant(["paper-beam"]),
    lambda: make_plant(noise=False).run([0.0, 200.0], [0.0, 1.0]),
    lambda: make_plant(noise=False).run([0.0, 1.0], [1.0, 0.0]),
])
def test_simulation_arguments(call):
    with pytest.raises(InvalidArgumentError):
        call()


def test_invalid_argument_error_is_both_value_and_type_error():
    assert issubclass(InvalidArgumentError, ValueError)
    assert issubclass(InvalidArgumentError, TypeError)
    assert issubclass(ResourceLimitError, InvalidArgumentError)


LOOPS = np.tile(np.r_[np.linspace(0, 150, 151), np.linspace(149, 1, 149)], 4)


@pytest.mark.parametrize("u, y, says", [
    (LOOPS, np.random.default_rng(3).normal(0, 1, LOOPS.size), "does not follow the voltage"),
    (LOOPS * 1e200, LOOPS * 1e200, "too large to fit"),
    (LOOPS * 1e-200, LOOPS * 1e-200, "too little for floating point"),
    (LOOPS * 1e-3 + 1e9, LOOPS, "too little for floating point"),
    (np.linspace(0, 150, 300), np.linspace(0, 45, 300) ** 1.1, "never reverses"),
    (np.tile([0.0, 150.0], 50), np.tile([0.0, 45.0], 50), "distinct values"),
])
def test_fit_reports_what_the_data_cannot_support(u, y, says):
    with pytest.raises(pihyst.FitError, match=says):
        pihyst.fit(u, y, family="classical")


def test_fit_warns_when_the_record_has_no_hysteresis():
    with pytest.warns(pihyst.exceptions.InsufficientDataWarning, match="no hysteresis"):
        pihyst.fit(LOOPS, 0.3 * LOOPS, family="classical")


def test_fit_exact_record_from_the_top_without_holdout():
    """A noise-free record starting at the top, nothing held back: the BIC of a perfect
    fit (log of 0) was a 'math domain error'."""
    true = pihyst.ClassicalPI([0, 20, 50], [0.2, 0.1, 0.05])
    u = np.r_[np.linspace(150, 0, 151), np.linspace(0, 150, 151)[1:]]
    y = true.predict(u, initial_state=[150, 130, 100])
    res = pihyst.fit(u, y, holdout=None, family=["classical", "multislope"])
    assert res.report.family(res.report.chosen)["errors"]["fit"]["rms"] < 0.01 * np.ptp(y)


@pytest.mark.slow
def test_fit_a_million_repeated_samples():
    """A loop followed by a million copies of its last sample (a logger left running):
    fitted, no solver message."""
    true = pihyst.ClassicalPI([0, 20, 50], [0.2, 0.1, 0.05])
    u = np.tile(np.r_[np.linspace(0, 150, 151), np.linspace(149, 0, 150)], 3)
    y = true.predict(u) + np.random.default_rng(0).normal(0, 0.01, u.size)
    n = 10 ** 6
    res = pihyst.fit(np.r_[u, np.full(n, u[-1])], np.r_[y, np.full(n, y[-1])],
                     family="classical")
    assert res.report.family("classical")["errors"]["fit"]["rms"] < 0.05


@pytest.mark.parametrize("call", [
    lambda m: m.predict("abc"), lambda m: m.predict([[0.0, 1.0]]),
    lambda m: m.stepper().step("x"),
    lambda m: pihyst.Compensator("model.json"), lambda m: pihyst.Compensator(m, u_min="x"),
    lambda m: pihyst.Compensator(m, u_min=100, u_max=50),
    lambda m: pihyst.Compensator(m, slew_rate=float("nan")),
    lambda m: pihyst.Compensator(m, slew_rate=0), lambda m: pihyst.Compensator(m).step("x"),
    lambda m: pihyst.compensate(m, "abc"), lambda m: pihyst.compensate(m, [[1.0]]),
])
def test_running_models_with_bad_arguments(call):
    with pytest.raises(InvalidArgumentError):
        call(pihyst.ClassicalPI(**CLASSICAL))


def test_a_missing_input_sample_is_out_of_range():
    with pytest.raises(pihyst.InputRangeError, match="sample 1"):
        pihyst.ClassicalPI(**CLASSICAL).predict([0.0, None])


BOUC_WEN = {"beta": 0.01, "gamma": 0.005, "hysteretic": 1.0, "linear": 0.5, "n": 1}
LOOPS_Y = pihyst.ClassicalPI([0, 20, 50], [0.2, 0.1, 0.05]).predict(LOOPS)


@pytest.mark.parametrize("call, exception, says", [
    (lambda: pihyst.fit(LOOPS, LOOPS_Y, family="classical", holdout=5), pihyst.FitError,
     "^holdout must be 'alternate', a fraction in \\(0, 1\\) or None, got 5$"),
    (lambda: pihyst.fit(LOOPS, LOOPS_Y, family="classical", holdout="half"),
     pihyst.FitError, "^holdout must be"),
    (lambda: pihyst.fit(LOOPS, LOOPS_Y, family="classical", bounds="x"), pihyst.FitError,
     "^bounds must be a pair \\(lower, upper\\), got 'x'$"),
    (lambda: pihyst.fit(LOOPS, LOOPS_Y, family="classical", bounds=(0, "1")),
     pihyst.FitError, "^bounds: the upper bound must be a number"),
    (lambda: pihyst.fit(LOOPS, LOOPS_Y, family="classical", bounds=(0, 1, 2)),
     pihyst.FitError, "^bounds must be a pair"),
    (lambda: pihyst.ClassicalPI(**CLASSICAL).envelopes("x"), InvalidArgumentError,
     "^u must be one input value"),
    (lambda: pihyst.ClassicalPI(**CLASSICAL).envelopes(True), InvalidArgumentError,
     "^u must be one input value"),
    (lambda: pihyst.load_model(5), InvalidArgumentError,
     "^load_model needs a file path or a dict, got int$"),
    (lambda: pihyst.fit_many("notalist"), InvalidArgumentError, "^records must be"),
    (lambda: pihyst.compensate(pihyst.ClassicalPI(**CLASSICAL), [1, 2], u_max="100"),
     InvalidArgumentError, "^u_max must be a number, got '100'$"),
    (lambda: pihyst.BoucWenModel(**{**BOUC_WEN, "n": "1"}), pihyst.InvalidModelError,
     "^n must be a number, got '1'$"),
    (lambda: pihyst.compensate(pihyst.BoucWenModel(**BOUC_WEN), [1, 2], u_max="100"),
     InvalidArgumentError, "^u_max must be a number"),
    (lambda: pihyst.BoucWenCompensator(pihyst.BoucWenModel(**BOUC_WEN), u_min=100,
                                       u_max=50), InvalidArgumentError, "^voltage limits"),
    (lambda: pihyst.BoucWenCompensator(pihyst.ClassicalPI(**CLASSICAL)),
     InvalidArgumentError, "^model must be a BoucWenModel"),
    (lambda: pihyst.ClassicalPI(**CLASSICAL, creep=Creep([0.1], [0.01], 1e-3)).predict(
        [0, 1, 2], t=[0, 1]), InvalidArgumentError, "^t must be one sample time"),
])
def test_arguments_of_the_wrong_kind_raise_pihysts_own_exceptions(call, exception, says):
    with pytest.raises(exception, match=says) as err:
        call()
    assert type(err.value).__module__ == "pihyst.exceptions"
    assert "\n" not in str(err.value)


NOT_REAL = {
    "complex": np.array([1 + 0j, 2 + 1j]),
    "complex-list": [1.0, 2 + 1j],
    "datetime64": np.array(["2020-01-01", "2020-01-02"], dtype="datetime64[D]"),
    "timedelta64": np.array([1, 2], dtype="timedelta64[s]"),
    "object": np.array([1.0, 2.0], dtype=object),
}
BOUC = pihyst.BoucWenModel(**BOUC_WEN)


@pytest.mark.parametrize("kind", sorted(NOT_REAL))
@pytest.mark.parametrize("call", [
    lambda x: pihyst.ClassicalPI(**CLASSICAL).predict(x),
    lambda x: pihyst.ClassicalPI(**CLASSICAL).simulate(x),
    lambda x: BOUC.predict(x),
    lambda x: pihyst.compensate(pihyst.ClassicalPI(**CLASSICAL), x),
    lambda x: pihyst.Compensator(pihyst.ClassicalPI(**CLASSICAL)).run(x),
    lambda x: pihyst.compensate(BOUC, x),
    lambda x: pihyst.fit(x, LOOPS_Y[:2]),
    lambda x: pihyst.fit(LOOPS[:2], x),
], ids=["predict", "simulate", "bouc-wen", "compensate", "Compensator", "compensate-bw",
        "fit-u", "fit-y"])
def test_non_real_arrays_are_refused(call, kind):
    """complex (NumPy would drop the imaginary part with a mere warning), dates and
    durations (counts of an unstated unit), objects: an InvalidArgumentError."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # no ComplexWarning on the way either
        with pytest.raises(InvalidArgumentError, match="must be real numbers, got "):
            call(NOT_REAL[kind])


@pytest.mark.parametrize("kwargs, says", [
    ({"n_candidates": 10 ** 6}, "^n_candidates: must be at most 128, got 1000000$"),
    ({"n_operators": 10 ** 6}, "^n_operators: must be at most 128"),
    ({"thresholds": np.linspace(0, 100, 10 ** 6)}, "^thresholds: 1,000,000 values, at most"),
    ({"candidates": np.linspace(0, 100, 10 ** 6)}, "^candidates: 1,000,000 values, at most"),
])
def test_fit_sizes_beyond_the_limit_are_refused_before_allocating(kwargs, says):
    import tracemalloc
    tracemalloc.start()
    try:
        with pytest.raises(ResourceLimitError, match=says):
            pihyst.fit(LOOPS, LOOPS_Y, **kwargs)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 64 << 20          # nothing of the size asked for was allocated
