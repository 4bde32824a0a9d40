"""pihyst.fit: recovery of known models, constraints, initial state, input ranges,
families, the report and the errors."""

import json
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import pihyst
from pihyst import ClassicalPI, FitError, MultislopePI, fit
from pihyst.exceptions import IllConditionedWarning, InfeasibleConstraintsError
from pihyst.identify import cycled_state
from pihyst.identify._options import FitOptions
from pihyst.sim import signals


def ramps(levels, n=40):
    """Piecewise-linear signal through ``levels``, n samples per ramp."""
    levels = np.asarray(levels, dtype=float)
    return np.concatenate([np.linspace(a, b, n, endpoint=False) for a, b in
                           zip(levels[:-1], levels[1:])] + [levels[-1:]])


def rich_signal(lo=0.0, hi=150.0, seed=0, n_cycles=6):
    """Starts at rest at lo; full cycles alternate with reversals inside the range."""
    rng = np.random.default_rng(seed)
    levels = [lo]
    for _ in range(n_cycles):
        levels += [hi, lo]
        inner = np.sort(rng.uniform(lo, hi, 4))
        levels += [inner[3], inner[0], inner[2], lo]
    return ramps(levels)


def at_rest(model):
    """``model`` started at rest at the bottom of its range after a full cycle."""
    lo, hi = model.input_range
    return model.replace(initial_state=model.simulate(np.array([lo, hi, lo])).final_state)


GRID = np.arange(16) * 150.0 / 32           # fit's classical candidates on 0..150 V


# ---------------------------------------------------------------- recovery
def test_recovers_classical_weights_and_offset_exactly():
    true = at_rest(ClassicalPI([0, 15, 40], [0.3, 0.2, 0.15], offset=-4.0))
    u = rich_signal()
    res = fit(u, true.predict(u), family="classical", thresholds=[0, 15, 40])
    np.testing.assert_allclose(res.model.weights, true.weights, atol=1e-9)
    assert res.model.offset == pytest.approx(-4.0, abs=1e-8)
    np.testing.assert_allclose(res.model.initial_state, true.initial_state, atol=1e-12)
    assert res.report.family("classical")["errors"]["held_back"]["rms"] < 1e-8


def test_recovers_multislope_weights_exactly():
    true = MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    u = rich_signal()
    res = fit(u, true.predict(u), family="multislope", thresholds=[0, 20, 30, 40])
    assert isinstance(res.model, MultislopePI)
    np.testing.assert_allclose(res.model.weights, true.weights, atol=1e-9)
    assert abs(res.model.offset) < 1e-8


def test_threshold_selection_finds_the_generating_subset():
    r = GRID[[0, 3, 9]]
    true = at_rest(ClassicalPI(r, [0.25, 0.3, 0.1], offset=2.0))
    u = rich_signal(seed=1)
    res = fit(u, true.predict(u), family="classical", n_operators=3)
    np.testing.assert_allclose(res.model.thresholds, r)
    np.testing.assert_allclose(res.model.weights, true.weights, atol=1e-8)
    choice = res.report.family("classical")["threshold_choice"]
    assert choice["search"] == "exhaustive" and choice["judged_on"] == "held_back"
    assert choice["candidates"] == pytest.approx(list(GRID))
    assert [reason["threshold"] for reason in choice["reasons"]] == pytest.approx(list(r))
    for reason in choice["reasons"]:
        assert reason["increase_without"] > 0.01


def test_automatic_size_stops_at_the_generating_size():
    r = GRID[[0, 5, 11]]
    true = at_rest(ClassicalPI(r, [0.2, 0.3, 0.2]))
    u = rich_signal(seed=2)
    rng = np.random.default_rng(0)
    res = fit(u, true.predict(u) + rng.normal(0, 1e-3, u.size), family="classical")
    assert res.model.n_operators == 3
    np.testing.assert_allclose(res.model.thresholds, r)


@settings(max_examples=15, deadline=None)
@given(idx=st.lists(st.integers(0, 15), min_size=1, max_size=5, unique=True),
       w=st.lists(st.floats(0.01, 1.0), min_size=5, max_size=5),
       offset=st.floats(-50, 50), seed=st.integers(0, 1000))
@pytest.mark.filterwarnings("ignore::pihyst.exceptions.InsufficientDataWarning")  # idx=[0]: linear
def test_recovery_property(idx, w, offset, seed):
    r = GRID[sorted(idx)]
    true = at_rest(ClassicalPI(r, w[:len(r)], offset=offset))
    u = rich_signal(seed=seed, n_cycles=3)
    res = fit(u, true.predict(u), family="classical", thresholds=r)
    np.testing.assert_allclose(res.model.weights, true.weights, atol=1e-7)
    np.testing.assert_allclose(res.model.predict(u), true.predict(u), atol=1e-7)


def test_multislope_shape_identification_recovers_the_shape():
    a, b, h = 0.7, 1.3, 0.3
    rmax = (1 - a) * 150 / (1 - a * h)
    true = MultislopePI(np.linspace(0, rmax, 16)[[0, 6, 12]], [0.2, 0.1, 0.15], a=a, b=b,
                        h=h)
    u = rich_signal(seed=3)
    y = true.predict(u)
    paper = fit(u, y, family="multislope", n_operators=3)
    res = fit(u, y, family="multislope-identified", n_operators=3)
    f = res.report.family("multislope-identified")
    assert f["shape"]["a"] == pytest.approx(a, abs=0.02)
    assert f["shape"]["b"] == pytest.approx(b, abs=0.05)
    assert f["shape"]["h"] == pytest.approx(h, abs=0.05)
    assert f["errors"]["held_back"]["rms"] < 0.05 * paper.report.family("multislope")[
        "errors"]["held_back"]["rms"]
    # the operators stay valid: thresholds within the shape's maximum, R <= F
    assert max(f["thresholds"]) <= (1 - f["shape"]["a"]) * 150 / (
        1 - f["shape"]["a"] * f["shape"]["h"]) * (1 + 1e-9)
    for v in np.linspace(0, 150, 31):
        R, F = res.model.envelopes(v)
        assert np.all(R <= F + 1e-9)


def test_modified_pi_recovers_its_own_structure():
    from pihyst.identify._families import ModifiedPI
    fam = ModifiedPI(4)
    r = np.arange(1, 17)[[1, 4, 9]] * 75 / 17          # on the family's candidate grid
    w = np.r_[[0.2, 0.15, 0.1], [0.3, 0.0, 0.2, 0.05]]     # plays, then input segments
    true = at_rest(fam.template(r, 150.0).replace(weights=w, offset=1.0))
    u = rich_signal(seed=4)
    res = fit(u, true.predict(u), family="modified-pi", n_operators=3)
    assert res.report.family("modified-pi")["thresholds"] == pytest.approx(list(r))
    np.testing.assert_allclose(res.model.weights, w, atol=1e-8)
    np.testing.assert_allclose(res.model.predict(u), true.predict(u), atol=1e-8)


def test_kp_fits_a_preisach_type_record_and_keeps_weights_nonnegative():
    from pihyst.identify._families import KrasnoselskiiPokrovskii
    fam = KrasnoselskiiPokrovskii(6)
    pairs = fam.pairs()
    w = np.random.default_rng(0).uniform(0, 2, len(pairs))
    true = at_rest(fam.template(pairs, 150.0).replace(weights=w))
    u = rich_signal(seed=5, n_cycles=8)
    y = true.predict(u)
    res = fit(u, y, family=pihyst.identify.KrasnoselskiiPokrovskii(grid=6))
    f = res.report.family("kp")
    assert f["errors"]["held_back"]["rms"] < 1e-3 * np.ptp(y)
    assert np.all(res.model.weights > 0)
    assert f["regularization"]["lambda"] == min(t["lambda"] for t in f["regularization"][
        "tried"] if t["rms"] == min(x["rms"] for x in f["regularization"]["tried"]))


# ---------------------------------------------------------------- constraints
def test_through_top_point_is_exact_and_bounds_hold():
    rng = np.random.default_rng(5)
    true = at_rest(ClassicalPI([0, 20, 50], [0.3, 0.2, 0.1]))
    u = rich_signal(seed=5)
    y = true.predict(u) + rng.normal(0, 0.3, u.size)
    res = fit(u, y, family="classical", thresholds=[0, 20, 50], through="top",
              bounds=(0.05, 0.25), refit=False)
    top = res.report.to_dict()["data"]["through"][0]
    assert u[top] == u.max()
    assert res.model.predict(u)[top] == pytest.approx(y[top], abs=1e-9)
    assert np.all(res.model.weights >= 0.05 - 1e-12) and np.all(res.model.weights <= 0.25 + 1e-12)


def test_negative_weights_only_when_allowed():
    true = at_rest(ClassicalPI([0, 20, 50], [0.3, -0.1, 0.2]))
    u = rich_signal(seed=6)
    y = true.predict(u)
    free = fit(u, y, family="classical", thresholds=[0, 20, 50], nonnegative=False)
    np.testing.assert_allclose(free.model.weights, true.weights, atol=1e-9)
    constrained = fit(u, y, family="classical", thresholds=[0, 20, 50])
    assert np.all(constrained.model.weights >= 0)


def test_fixed_offset_and_no_offset():
    true = at_rest(ClassicalPI([0, 30], [0.3, 0.2], offset=0.0))
    u = rich_signal(seed=7)
    y = true.predict(u) + 7.0
    res = fit(u, y, family="classical", thresholds=[0, 30], offset=7.0)
    assert res.model.offset == pytest.approx(7.0)
    np.testing.assert_allclose(res.model.weights, true.weights, atol=1e-9)
    res0 = fit(u, y - 7.0, family="classical", thresholds=[0, 30], offset=False)
    assert res0.model.offset == 0.0


def test_infeasible_constraints_raise():
    true = at_rest(ClassicalPI([0, 30], [0.3, 0.2]))
    u = rich_signal(seed=8)
    with pytest.raises(InfeasibleConstraintsError):
        fit(u, true.predict(u) + 100, family="classical", thresholds=[0, 30],
            through="top", bounds=(0, 0.01), offset=False)


# ---------------------------------------------------------------- state, offset, range
def test_record_starting_mid_cycle_is_settled_by_its_first_sweep():
    true = at_rest(ClassicalPI(GRID[[0, 4, 10]], [0.3, 0.2, 0.2], offset=-80.0))
    u = rich_signal(seed=9)
    y = true.predict(u)
    start = 100                                    # mid-ramp, operators not at rest
    assert 0 < u[start] < 150
    res = fit(u[start:], y[start:], family="classical", thresholds=GRID[[0, 4, 10]])
    d = res.report.to_dict()["data"]
    assert d["initial_state"] == "settle" and d["settle_samples"] > 0
    np.testing.assert_allclose(res.model.weights, true.weights, atol=1e-9)
    assert res.model.offset == pytest.approx(-80.0, abs=1e-7)
    # the saved initial state is the rest state after a full cycle
    np.testing.assert_allclose(res.model.initial_state, true.initial_state, atol=1e-9)


def test_zero_and_explicit_initial_state():
    true = ClassicalPI([0, 20, 60], [0.2, 0.2, 0.3])              # zero state
    u = rich_signal(seed=10)
    y = true.predict(u)
    res = fit(u, y, family="classical", thresholds=[0, 20, 60], initial_state="zero")
    np.testing.assert_allclose(res.model.weights, true.weights, atol=1e-9)
    assert np.all(res.model.initial_state == 0)
    state = [0.0, 5.0, 10.0]
    y2 = true.predict(u, initial_state=state)
    res2 = fit(u, y2, family="classical", thresholds=[0, 20, 60], initial_state=state)
    np.testing.assert_allclose(res2.model.initial_state, state)
    np.testing.assert_allclose(res2.model.predict(u), y2, atol=1e-8)


@pytest.mark.parametrize("lo, hi", [(0.0, 3.6), (-150.0, 150.0), (1000.0, 1010.0)])
def test_input_range_is_the_data_span_for_classical(lo, hi):
    S = hi - lo
    true = at_rest(ClassicalPI(np.array([0, 4, 10]) * S / 32, [0.3, 0.2, 0.2], offset=3.0,
                               input_range=(lo, hi)))
    u = rich_signal(lo, hi, seed=11)
    res = fit(u, true.predict(u), family="classical", thresholds=true.thresholds)
    assert res.model.input_range == (lo, hi)
    np.testing.assert_allclose(res.model.weights, true.weights, atol=1e-8)
    np.testing.assert_allclose(res.model.predict(u), true.predict(u), atol=1e-7 * S)


@pytest.mark.parametrize("lo, hi", [(0.0, 3.6), (-150.0, 150.0)])
def test_multislope_geometry_maps_to_the_data_range(lo, hi, tmp_path):
    # the paper's model on 0..150 V, driven through u = lo + (hi - lo) v / 150: the same
    # loop on the data's range, so the mapped family must fit it exactly
    true = MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    v = rich_signal(seed=12)
    u = lo + (hi - lo) * v / 150
    y = true.predict(v)
    scale = (hi - lo) / 150
    res = fit(u, y, family="multislope", thresholds=np.array([0, 20, 30, 40]) * scale)
    assert res.model.input_range == pytest.approx((lo, hi))
    np.testing.assert_allclose(res.model.predict(u), y, atol=1e-9)
    # weights per unit of the mapped input: w' = w / scale
    np.testing.assert_allclose(res.model.weights, true.weights / scale, rtol=1e-8)
    path = tmp_path / "m.json"
    res.model.save(path)
    again = pihyst.load_model(path)
    np.testing.assert_allclose(again.predict(u), y, atol=1e-9)
    meta = again.metadata["fit"]
    assert meta["family"] == "multislope" and meta["shape"]["U"] == pytest.approx(hi - lo)


# ---------------------------------------------------------------- families and report
def test_default_fit_compares_all_families_and_returns_the_best():
    from pihyst.sim import make_plant
    from pihyst.sim.signals import decaying_triangles
    t, u = decaying_triangles(n_triangles=4, dt=1.0)
    y = make_plant("paper-beam", seed=1).run(u, t)
    res = fit(u, y)
    rep = res.report.to_dict()
    names = [f["family"] for f in rep["families"]]
    assert set(names) == set(pihyst.identify.FAMILY_NAMES)
    held = {f["family"]: f["errors"]["held_back"]["rms"] for f in rep["families"]}
    assert rep["chosen"] == min(held, key=held.get) == res.report.chosen
    assert [f["chosen"] for f in rep["families"]].count(True) == 1
    assert rep["final"]["refit"] is True
    assert json.loads(res.report.to_json())["chosen"] == rep["chosen"]
    assert res.model.metadata["fit"]["family"] == rep["chosen"]
    for name, model in res.models.items():    # every model monotone, hence invertible
        if name == "bouc-wen":
            assert model.min_slope >= 0, name
        else:
            assert np.all(model.weights >= 0), name


def test_report_explains_threshold_choice():
    true = at_rest(ClassicalPI(GRID[[0, 6]], [0.3, 0.2]))
    u = rich_signal(seed=13)
    y = true.predict(u) + np.random.default_rng(1).normal(0, 0.05, u.size)
    res = fit(u, y, family="classical", n_operators=2)
    ch = res.report.family("classical")["threshold_choice"]
    assert len(ch["reasons"]) == 2 and len(ch["candidates"]) == 16
    assert ch["judged_on"] == "held_back"
    # a reason per threshold chosen: the held-back RMS without it is higher
    assert [r["threshold"] for r in ch["reasons"]] == ch["chosen"]
    chosen_rms = next(s["rms"] for s in ch["sizes"] if s["n_operators"] == 2)
    for r in ch["reasons"]:
        assert r["increase_without"] > 0
        assert r["rms_without"] == pytest.approx(chosen_rms + r["increase_without"])


def test_no_held_back_cycles_judges_on_fitted_data():
    true = at_rest(ClassicalPI([0, 30], [0.3, 0.2]))
    u = ramps([0, 150, 0], n=200)
    res = fit(u, true.predict(u))
    rep = res.report.to_dict()
    assert rep["data"]["held_back_samples"] == 0
    # judged on the fitted data, by the lowest BIC: n ln(RMS^2) + p ln n
    n = rep["data"]["fit_samples"]

    def bic(f):
        p = 7 if f["family"] == "bouc-wen" else np.count_nonzero(f["weights"]) + 1
        return 2 * n * np.log(f["judged_rms"]) + p * np.log(n)
    assert all(f["judged_rms"] == f["errors"]["fit"]["rms"] for f in rep["families"])
    assert rep["chosen"] == min(rep["families"], key=bic)["family"]
    # no kernels without held-back data to regularize them on (and no open minor loops)
    assert {s["family"] for s in rep["skipped"]} == {"kp", "multislope",
                                                     "multislope-identified"}
    assert rep["final"]["refit"] is False


def test_holdout_fraction_holds_back_the_end():
    true = at_rest(ClassicalPI([0, 30], [0.3, 0.2]))
    u = rich_signal(seed=14)
    res = fit(u, true.predict(u), family="classical", holdout=0.5)
    d = res.report.to_dict()["data"]
    layout = FitOptions.from_arguments(holdout=0.5).frame(u, true.predict(u)).layout
    assert layout.indices("held_back").min() > layout.indices("fit").max()   # the end
    assert d["held_back_samples"] == layout.count("held_back") > 0
    assert abs(d["fit_samples"] - d["held_back_samples"]) < 0.25 * u.size


# ---------------------------------------------------------------- errors and warnings
def test_bad_input_errors():
    u = rich_signal()
    y = 0.3 * u
    with pytest.raises(FitError, match="too few samples"):
        fit(u[:5], y[:5])
    with pytest.raises(FitError, match="input is constant"):
        fit(np.ones(100), np.arange(100.0))
    bad = y.copy()
    bad[17] = np.nan
    with pytest.raises(FitError, match="output sample 17") as err:
        fit(u, bad)
    assert err.value.index == 17 and err.value.column == "output"
    with pytest.raises(FitError, match="never move the operator of threshold 100"):
        fit(u, y, family="classical", thresholds=[0, 10, 100])
    with pytest.raises(FitError, match="same length|samples but"):
        fit(u, y[:-1])
    with pytest.raises(FitError, match="unknown model family"):
        fit(u, y, family="preisach")
    with pytest.raises(FitError, match="not both"):
        fit(u, y, thresholds=[0, 10], n_operators=2)
    with pytest.raises(FitError, match="above"):
        fit(u, y, family="multislope", thresholds=[0, 60])
    with pytest.raises(FitError, match="explicit thresholds"):
        fit(u, y, initial_state=[0.0, 1.0])
    with pytest.raises(FitError, match="cannot choose"):
        fit(u, y, family="classical", n_operators=40)


def test_record_that_never_settles_is_an_error():
    u = ramps([70, 150, 0], n=30)                    # starts mid-range, one sweep only
    with pytest.raises(FitError, match="settles the operator states"):
        fit(u, 0.3 * u, initial_state="settle")
    # "auto" fits it whole from the start state the probe fits best (_start_state.py)
    true = ClassicalPI([0, 20], [0.3, 0.2])
    y = true.predict(u, initial_state=[70.0, 50.0])     # risen to 70 from the bottom
    res = fit(u, y, family="classical", thresholds=[0, 20])
    assert res.report.to_dict()["data"]["initial_state"] == "rise"
    np.testing.assert_allclose(res.model.weights, true.weights, atol=1e-9)


def test_ill_conditioned_fit_warns_and_still_fits():
    true = at_rest(ClassicalPI([0, 30], [0.3, 0.2]))
    u = rich_signal(seed=15)
    y = true.predict(u)
    with pytest.warns(IllConditionedWarning, match="r=30"):
        res = fit(u, y, family="classical", thresholds=[0, 30, 30 + 1e-7])
    np.testing.assert_allclose(res.model.predict(u), y, atol=1e-6)
    assert res.report.family("classical")["warnings"]


def test_no_warning_on_a_well_posed_fit():
    true = at_rest(ClassicalPI([0, 30], [0.3, 0.2]))
    u = rich_signal(seed=16)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit(u, true.predict(u), family="classical", thresholds=[0, 30])


@pytest.mark.filterwarnings("ignore::pihyst.exceptions.InsufficientDataWarning")  # no loop
def test_inputs_are_not_modified():
    u = rich_signal(seed=17)
    y = 0.3 * u + np.sin(u / 9)
    u0, y0 = u.copy(), y.copy()
    fit(u, y, family="classical", n_operators=2)
    assert np.array_equal(u, u0) and np.array_equal(y, y0)


def test_cycled_state_matches_a_long_run():
    m = MultislopePI([0, 10, 40], [1, 1, 1])
    v = np.r_[np.linspace(0, 150, 301), np.linspace(150, 0, 301)]
    np.testing.assert_allclose(cycled_state(m, 150.0), m.simulate(v).final_state)


def test_shape_identification_with_U_keeps_the_operators_valid():
    true = MultislopePI([0, 15, 30], [0.2, 0.1, 0.15], U=170.0, input_range=(0, 150))
    u = rich_signal(seed=18)
    res = fit(u, true.predict(u),
              family=pihyst.identify.MultislopeIdentified(identify="with-U"), n_operators=3)
    f = res.report.family("multislope-identified")
    assert f["shape"]["U"] == pytest.approx(170.0, abs=2.0)
    assert f["errors"]["held_back"]["rms"] < 0.01
    for v in np.linspace(0, 150, 31):
        R, F = res.model.envelopes(v)
        assert np.all(R <= F + 1e-9)


def test_threshold_bound_in_the_error_is_that_of_the_fitted_cycles():
    """After a settling sweep, with alternate cycles held back, the fitted cycles of
    decaying triangles (peaks 150, 105, 73.5, ...) reach 73.5 V only: a threshold of 45
    never moves, and the bound the error suggests is half the fitted span, not half the
    record's (it said "use thresholds below 75" of a threshold of 45)."""
    t, u = signals.decaying_triangles(period_s=60.0, dt=0.1)
    y = ClassicalPI([0.0, 10.0, 25.0, 45.0], [0.15, 0.06, 0.04, 0.03]).predict(u)
    with pytest.raises(FitError, match=r"threshold 45 \(their input spans 73.5 of the "
                                       r"range 150\).*below 36.75"):
        fit(u, y, family="classical", thresholds=[0.0, 10.0, 25.0, 45.0],
            initial_state="settle")
