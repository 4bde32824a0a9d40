"""The identification pipeline as a newcomer reads it: each step a function returning a
frozen decision, every deciding number in one module, the decision table of
docs/theory/identification.md true to the code, and no function in identify/ over 100
lines of code."""

import ast
import dataclasses
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import pihyst
from pihyst import ClassicalPI, FitError
from pihyst.exceptions import PihystWarning
from pihyst.identify import _constants, _delay, _record_fit
from pihyst.identify._decisions import Choice, Delay, FamiliesFitted, StartState
from pihyst.identify._family_fit import FamilyFitter
from pihyst.identify._options import FitOptions
from pihyst.identify._progress import Steps
from pihyst.identify._responses import Responses, digest

ROOT = Path(__file__).resolve().parents[2]
IDENTIFY = ROOT / "src" / "pihyst" / "identify"
TABLE = ROOT / "docs" / "theory" / "identification.md"
MAX_CODE_LINES = 100


def ramps(levels, n=40):
    levels = np.asarray(levels, dtype=float)
    return np.concatenate([np.linspace(a, b, n, endpoint=False) for a, b in
                           zip(levels[:-1], levels[1:])] + [levels[-1:]])


def record(delay=0, noise=0.0, seed=0):
    """A classical PI actuator at rest after a full cycle, on major and minor loops,
    its output ``delay`` samples late."""
    true = ClassicalPI([0, 20, 45], [0.3, 0.2, 0.1], offset=1.0)
    true = true.replace(initial_state=true.simulate(np.array([0.0, 150.0, 0.0])).final_state)
    rng = np.random.default_rng(seed)
    levels = [0.0]
    for _ in range(5):
        inner = np.sort(rng.uniform(10, 140, 4))
        levels += [150.0, 0.0, inner[3], inner[0], inner[2], 0.0]
    u = ramps(levels)
    y = true.predict(u) + noise * rng.standard_normal(u.size)
    y = np.r_[np.full(delay, y[0]), y[:u.size - delay]]
    return u, y


def test_each_step_returns_a_frozen_decision_the_report_is_built_from():
    u, y = record(delay=3)
    options = FitOptions.from_arguments(family=["classical", "modified-pi"])
    rec, start = _record_fit.decide_start_state(u, y, options)
    assert isinstance(start, StartState) and start.mode == "cycled"
    delay = _record_fit.decide_delay(rec, options)
    assert isinstance(delay, Delay) and delay.samples == 3 and delay.auto
    attempt = _record_fit.fit_at_delay(rec, delay, options, Steps(None), Responses())
    assert isinstance(attempt.fitted, FamiliesFitted) and isinstance(attempt.choice, Choice)
    assert {r.name for r in attempt.fitted.results} == {"classical", "modified-pi"}
    done = _record_fit.finish(attempt, start, delay, options, Steps(None), None)
    data = done.result.report.to_dict()
    assert data["data"]["delay"] == delay.to_report()
    assert data["chosen"] == done.choice.chosen.name
    assert data["data"]["initial_state"] == start.mode
    for decision in (start, delay, attempt.fitted, attempt.choice, done):
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(decision, dataclasses.fields(decision)[0].name, None)


def test_the_pipeline_gives_what_fit_gives():
    u, y = record(delay=2, noise=0.01)
    options = FitOptions.from_arguments()
    by_steps = _record_fit.fit_record(u, y, options, Steps(None)).result
    by_fit = pihyst.fit(u, y)
    assert by_steps.model == by_fit.model
    assert by_steps.report.to_dict() == by_fit.report.to_dict()


def test_the_decided_delay_is_not_made_again(monkeypatch):
    u, y = record(delay=3)
    options = FitOptions.from_arguments(family="classical")
    rec, _ = _record_fit.decide_start_state(u, y, options)
    decided = _record_fit.decide_delay(rec, options).given()
    assert decided.decided_before and decided.samples == 3
    scans = []                          # the delay scan must not run again
    monkeypatch.setattr(_delay, "scan", lambda *args: scans.append(args) or [])
    fitted = _record_fit.fit_record(u, y, options, Steps(None), delay=decided)
    assert fitted.delay is decided and fitted.result.model.delay == 3 and scans == []


@pytest.mark.parametrize("kwargs, match", [
    ({"thresholds": [0, 10], "candidates": [0, 5]}, "not both"),
    ({"thresholds": [0, 10], "n_operators": 2}, "not both"),
    ({"n_operators": 0}, "positive integer"),
    ({"max_operators": 2.5}, "positive integer"),
    ({"max_latency": -1}, "positive number of seconds"),
    ({"delay": -1}, "number of samples"),
    ({"bounds": (0, 1, 2)}, "pair"),
    ({"creep": "yes"}, "creep must be"),
    ({"creep": [1.0, -2.0]}, "finite and > 0"),
    ({"creep": ["a"]}, "creep must be"),
    ({"thresholds": ["a", "b"]}, "list of numbers"),
    ({"family": ["classical", "classical"]}, "given once"),
    ({"family": "nonsense"}, "unknown model family"),
])
def test_options_are_checked_once_before_the_data(kwargs, match):
    with pytest.raises(FitError, match=match):
        FitOptions.from_arguments(**kwargs)
    u, y = record()
    with pytest.raises(FitError, match=match):
        pihyst.fit(u, y, **kwargs)


def test_options_are_a_frozen_value():
    options = FitOptions.from_arguments(family="kp", has_times=True)
    assert options.creep == "auto" and not options.chooses_thresholds
    with pytest.raises(dataclasses.FrozenInstanceError):
        options.delay = 0
    other = options.but(delay=0, families=["classical"])
    assert other.delay == 0 and options.delay == "auto"
    assert [f.name for f in other.families] == ["classical"]
    assert FitOptions.from_arguments(creep=True).creep == "always"
    assert FitOptions.from_arguments(creep="auto").creep == "off"   # no sample times


def test_responses_are_computed_once_per_input():
    responses, calls = Responses(), []

    def compute():
        calls.append(1)
        return 42

    a = np.arange(5.0)
    assert responses.get(digest(a), compute) == responses.get(digest(a.copy()), compute)
    assert len(calls) == 1 and digest(a) != digest(a + 1) and digest(a) != digest(a[:4])


def _deciding_constants():
    return {name for name, value in vars(_constants).items()
            if name.isupper() and isinstance(value, (int, float))}


def test_the_decision_table_is_true_to_the_code():
    text = TABLE.read_text(encoding="utf-8")
    table = text[text.index("## The procedure"):text.index("## Fitting families")]
    named = set(re.findall(r"`([A-Z][A-Z_0-9]+)`", table))
    # every constant the table names is a deciding constant, and every one is named
    assert named == _deciding_constants(), (named ^ _deciding_constants())
    # every step function and decision it names exists
    for name in re.findall(r"\(`([a-z_]+)` →", table):
        assert callable(getattr(_record_fit, name)), name
    for name in re.findall(r"→ `([A-Za-z]+)`\)", table):
        assert name in {"StartState", "Delay", "FamiliesFitted", "Choice"}, name
    modules = set(re.findall(r"`(_[a-z_]+)`", table))
    missing = [m for m in modules if not (IDENTIFY / f"{m}.py").exists()]
    assert not missing, missing


def test_deciding_numbers_live_in_one_module():
    """No module of identify/ defines a deciding constant of _constants again."""
    deciding = _deciding_constants()
    for path in IDENTIFY.glob("_*.py"):
        if path.stem == "_constants":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        defined = {t.id for node in tree.body if isinstance(node, ast.Assign)
                   for t in node.targets if isinstance(t, ast.Name)}
        assert not defined & deciding, (path.name, defined & deciding)


def _code_lines(source, node):
    body = node.body
    doc = set()
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
            and isinstance(body[0].value.value, str):
        doc = set(range(body[0].lineno, body[0].end_lineno + 1))
    lines = source.splitlines()[node.lineno - 1:node.end_lineno]
    return sum(1 for i, line in enumerate(lines, start=node.lineno)
               if line.strip() and not line.strip().startswith("#") and i not in doc)


def test_no_function_in_identify_is_over_100_lines_of_code():
    long = []
    for path in sorted(IDENTIFY.glob("*.py")):
        source = path.read_text(encoding="utf-8")
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                n = _code_lines(source, node)
                if n > MAX_CODE_LINES:
                    long.append(f"{path.name}:{node.name} ({n})")
    assert not long, long


@pytest.mark.parametrize("family", ["classical", "kp"])
def test_a_long_records_creep_rows_have_the_whole_records_operator_outputs(monkeypatch,
                                                                           family):
    """Creep's joint QP on a long record runs the operators on its (thinned) fitted rows
    and every input extremum only: the outputs there are exactly those of every sample."""
    from pihyst.identify import _creep

    rng = np.random.default_rng(3)
    levels = np.r_[0.0, 150.0, 0.0, rng.uniform(0, 150, 400)]
    u = np.concatenate([np.linspace(a, b, 200, endpoint=False)
                        for a, b in zip(levels[:-1], levels[1:])])
    model = (ClassicalPI(np.linspace(0, 70, 16), np.full(16, 0.1)) if family == "classical"
             else pihyst.fit(u[:4000], ClassicalPI([0, 30], [0.2, 0.1]).predict(u[:4000]),
                             family="kp").model)
    monkeypatch.setattr(_creep, "FIT_SAMPLES", 20_000)
    fitted = _creep._fitted_rows(u.size, 150, None)
    assert 0 < np.count_nonzero(fitted) <= 20_000 < u.size - 150
    basis = model.weights[:, None]
    for free in (True, False):
        long = _creep._operator_matrix(model, u, fitted, basis, free)
        monkeypatch.setattr(_creep, "FIT_SAMPLES", 10 ** 9)
        chunked = _creep._operator_matrix(model, u, fitted, basis, free)
        monkeypatch.setattr(_creep, "FIT_SAMPLES", 20_000)
        assert long.shape == (np.count_nonzero(fitted), basis.shape[1] if not free
                              else model.n_operators)
        np.testing.assert_array_equal(long, chunked) if free else \
            np.testing.assert_allclose(long, chunked, rtol=1e-13, atol=1e-13)


def test_a_record_of_much_travel_is_windowed_for_bouc_wen_and_the_shape_search(monkeypatch):
    """Bouc-Wen and the multislope shape search run on a long record's first cycles within
    FAMILY_TRAVEL ranges of input travel (their cost grows with the travel); a record
    that travels less is used whole."""
    from pihyst.identify._boucwen import FAMILY_TRAVEL, travel_window

    rng = np.random.default_rng(5)
    levels = np.r_[0.0, 150.0, 0.0, rng.uniform(0, 150, 1500)]
    u = np.concatenate([np.linspace(a, b, 20, endpoint=False)
                        for a, b in zip(levels[:-1], levels[1:])])
    y = ClassicalPI([0, 30], [0.2, 0.1]).predict(u)
    options = FitOptions.from_arguments()
    rec = options.frame(u, y, "cycled")
    stop = travel_window(rec, FAMILY_TRAVEL)
    assert stop is not None and stop < u.size
    path = np.cumsum(np.abs(np.diff(rec.v[:stop]))) / rec.S
    assert FAMILY_TRAVEL <= path[-1] < 1.5 * FAMILY_TRAVEL
    assert stop in {z for a, z, r in rec.layout.segments}          # at a cycle's end
    window = rec.shifted(0, stop)
    assert window.has_held_back and window.layout.count("fit") > 0
    short = options.frame(u[:4000], y[:4000], "cycled")
    assert travel_window(short, FAMILY_TRAVEL) is None
    windows = []                        # the stops of the fitters windowed
    real = FamilyFitter.windowed

    def spy(self, at, note):
        windows.append(at)
        return real(self, at, note)
    monkeypatch.setattr(FamilyFitter, "windowed", spy)
    pihyst.fit(u, y, family="bouc-wen")
    assert windows == [stop]


@pytest.mark.parametrize("kwargs", [{"n_operators": 4}, {"thresholds": [0, 10, 30]},
                                    {"candidates": list(np.linspace(0, 60, 8))},
                                    # 42 s on a loaded machine; the way options reach
                                    # the fit with creep is the same for the others
                                    pytest.param({"offset": 0.0}, marks=pytest.mark.slow),
                                    {"initial_state": "zero"},
                                    {"bounds": (0, 1)}, {"nonnegative": False}])
def test_a_fit_with_sample_times_takes_every_option_the_fit_without_them_takes(kwargs):
    """With sample times the structure is chosen again on the record with its creep
    removed; there too a default family that cannot take an option (the kernel basis
    and Bouc-Wen have no thresholds; Bouc-Wen fits its own offset and state, has no
    bounds) is skipped rather than failing the fit, as it failed it before."""
    from pihyst.sim import make_plant, signals

    beam = make_plant("paper-beam", seed=1)
    t, u = signals.triangle(0, 150, 20.0, 4, 0.05)
    y = beam.run(u, t)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PihystWarning)   # e.g. a modified PI on given r
        result = pihyst.fit(u, y, t=t, **kwargs)
    data = result.report.to_dict()
    assert data["chosen"] != "bouc-wen"
    assert data["creep"]["kept"] in (True, False)        # the decision on creep is made
    if "thresholds" in kwargs and data["chosen"] == "classical":
        np.testing.assert_allclose(result.model.thresholds, kwargs["thresholds"])


def test_a_creep_estimate_of_nothing_does_not_refit_the_structure(monkeypatch):
    """Compute once: where the joint QP finds no creep (a record of a creep-free
    actuator), the record with the estimate removed is the record itself, and the
    structure is the first fit's, not fitted again (NO_CREEP). Here the model fits the
    record exactly, so the lags have nothing to explain."""
    from pihyst.identify import _creep

    u, y = record()
    t = np.arange(u.size) * 0.01
    calls = []
    real = _creep.fit_record
    monkeypatch.setattr(_creep, "fit_record",
                        lambda *a, **k: calls.append(k.get("delay")) or real(*a, **k))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PihystWarning)
        fitted = pihyst.fit(u, y, t=t, family="classical", thresholds=[0, 20, 45])
    decision = fitted.model.metadata["fit"]["creep"]["decision"]
    assert decision["kept"] is False
    assert calls == [None]          # the first fit only; the trial reused it
    assert decision["family_with"] == fitted.report.chosen


def test_a_real_creep_estimate_refits_the_structure(monkeypatch):
    from pihyst.identify import _creep

    u, y = record(noise=1e-3)
    t = np.arange(u.size) * 0.01
    y = y + 0.02 * np.log1p(t)                  # a creep-like drift, 2 % per decade
    calls = []
    real = _creep.fit_record
    monkeypatch.setattr(_creep, "fit_record",
                        lambda *a, **k: calls.append(k.get("delay")) or real(*a, **k))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PihystWarning)
        pihyst.fit(u, y, t=t, family=["classical", "modified-pi"])
    assert len(calls) == 2


def test_the_tied_lag_deficits_at_some_rows_are_the_full_deficits_there():
    """tied_deficits keeps only the rows a fit sums over, block by block: the same
    numbers as every deficit of every sample, selected and tied afterwards."""
    from pihyst.identify import _boucwen_creep
    from pihyst.identify._creep import log_t_basis

    rng = np.random.default_rng(8)
    n = 3 * _boucwen_creep.CHUNK + 17            # several blocks, the last one short
    s = np.cumsum(rng.normal(size=n))
    dt = rng.uniform(1e-4, 1e-2, n)
    tau = np.array([1e-3, 1e-2, 0.1, 1.0, 10.0])
    tie = log_t_basis(tau.size, 4)
    rows = rng.random(n) < 0.3
    rows[:_boucwen_creep.CHUNK] = False          # a block with no row at all
    full = _boucwen_creep.lag_deficits(s, s[0] - 2.0, dt, tau)[rows] @ tie
    np.testing.assert_allclose(_boucwen_creep.tied_deficits(s, s[0] - 2.0, dt, tau, tie,
                                                            rows), full, rtol=1e-12,
                               atol=1e-12)


@pytest.mark.parametrize("state_mode", ["cycled", "zero"])
def test_dropping_constant_kernels_restricts_the_grids_normal_equations_bit_for_bit(
        state_mode):
    """The kernels the input never moves are dropped from the grid's normal equations
    (identify/_family_fit.py): the rows and columns kept are the numbers a second pass
    over the kept kernels alone gives, bit for bit, for every role and state."""
    from pihyst.identify._families import KrasnoselskiiPokrovskii
    from pihyst.identify._family_fit import FramedRecord, _kept_columns

    u = np.r_[ramps([0.0, 150.0, 0.0, 90.0, 20.0, 150.0, 0.0]), 0.0]
    y = ClassicalPI([0, 30, 60], [0.3, 0.2, 0.1]).predict(u)
    rec = FramedRecord(u, y, input_range=None, initial_state=state_mode,
                       holdout="alternate", offset=True, through=[5])
    fitter = FamilyFitter(rec)
    fam = KrasnoselskiiPokrovskii(grid=5)
    pairs = fam.pairs()
    state0, parts, rows = fitter.grams(fam, fam.template(pairs, fitter.rec.S))
    kept = [k for k in range(len(pairs)) if k % 3]
    got = _kept_columns(kept, len(pairs), state0, parts, rows)
    want = fitter.grams(fam, fam.template([pairs[k] for k in kept], fitter.rec.S))
    np.testing.assert_array_equal(got[0], want[0])
    for role in ("fit", "held_back"):
        assert (got[1][role].dd, got[1][role].n) == (want[1][role].dd, want[1][role].n)
        np.testing.assert_array_equal(got[1][role].G, want[1][role].G)
        np.testing.assert_array_equal(got[1][role].b, want[1][role].b)
    assert got[2].keys() == want[2].keys() == {5}
    np.testing.assert_array_equal(got[2][5], want[2][5])


@pytest.mark.parametrize("long_record", [False, True])
def test_the_joint_qps_change_of_the_settled_output_is_exact_on_the_fitted_rows(
        monkeypatch, long_record):
    """Creep's joint QP stops when the operator columns times the change of their
    coefficients (and the offset's) is small: that is the change of the model's
    settled output at the fitted rows, without running the model over the record."""
    from pihyst.identify import _creep

    rng = np.random.default_rng(5)
    levels = np.r_[0.0, 150.0, 0.0, rng.uniform(0, 150, 120)]
    u = np.concatenate([np.linspace(a, b, 60, endpoint=False)
                        for a, b in zip(levels[:-1], levels[1:])])
    old = ClassicalPI(np.linspace(0, 70, 8), rng.uniform(0.05, 0.3, 8), offset=1.0)
    new = old.replace(weights=old.weights * rng.uniform(0.8, 1.2, 8), offset=1.3)
    if long_record:
        monkeypatch.setattr(_creep, "FIT_SAMPLES", 2_000)
    fitted = _creep._fitted_rows(u.size, 100, None)
    columns = _creep._operator_matrix(old, u, fitted, None, True, ones=True)
    change = columns @ (np.r_[new.weights, new.offset] - np.r_[old.weights, old.offset])
    np.testing.assert_allclose(change, (new.predict(u) - old.predict(u))[fitted],
                               rtol=1e-10, atol=1e-10)
