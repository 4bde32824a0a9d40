"""Fits to measured data sets (../shared/data or $PIHYST_DATA; skipped when absent).

Protocol (issue 3, item 8): the first cycle only settles the operator states, the model
is fitted on the first half of the rest and judged on the second half (held back).
"""

import numpy as np
import pytest

from pihyst import fit
from pihyst.identify._families import FAMILIES
from pihyst.identify._options import FitOptions
from pihyst.io import datasets

ROOT = datasets.data_root()
# the families whose minor loops their structure does not fix: not fitted on major loops
OPEN_LOOPS = {f.name for f in FAMILIES.values() if not f.minor_loops_fixed}
pytestmark = [
    pytest.mark.skipif(ROOT is None, reason="measured data not found: set PIHYST_DATA or put "
                       "the data sets in ../shared/data next to the repository"),
    pytest.mark.slow,
]


def _held_back_fit(u, y):
    res = fit(u, y, initial_state="settle", holdout=0.5, refit=False)
    rep = res.report.to_dict()
    assert rep["data"]["initial_state"] == "settle" and rep["data"]["settle_samples"] > 0
    rec = FitOptions.from_arguments(initial_state="settle", holdout=0.5).frame(u, y)
    layout = rec.shifted(rep["data"]["delay"]["samples"]).layout     # as it was fitted
    assert layout.indices("held_back").min() > layout.indices("fit").max()   # the end
    assert rep["data"]["held_back_samples"] == layout.count("held_back") > 0
    best = res.report.family(res.report.chosen)
    rms = best["errors"]["held_back"]["rms"]
    # refit=False: the returned model is the one judged; the held-back part is the tail
    n_held = rep["data"]["held_back_samples"]
    e = res.model.predict(u)[-n_held:] - y[-n_held:]
    assert np.sqrt(np.mean(e ** 2)) == pytest.approx(rms, rel=1e-9)
    return res, rms


def test_p885_stack_held_back_rms():
    u, y = datasets.p885(ROOT)
    assert u.size == 8026 and u.min() == 0.0 and u.max() == pytest.approx(3.6)
    res, rms = _held_back_fit(u, y)
    assert res.model.input_range == pytest.approx((0.0, 3.6))
    assert rms <= 0.35, res.report


def test_smarthysteresis_sine_held_back_rms():
    u, y = datasets.smarthysteresis(ROOT)
    assert u.min() == pytest.approx(-150) and u.max() == pytest.approx(150)
    res, rms = _held_back_fit(u, y)
    assert res.model.input_range == pytest.approx((-150.0, 150.0))
    # One sine amplitude: only major loops, so the minor loops are undetermined and the
    # multislope families (operators anchored at the top of the range) are not chosen.
    # The default adopts the record's 10 ms lag (delay="auto"; 0.055 um held back);
    # without it the chosen modified PI gives 0.081 um.
    # multislope-identified cannot be chosen (the minor loops are open): not fitted
    assert {x["family"] for x in res.report.to_dict()["skipped"]} == OPEN_LOOPS
    alone = fit(u, y, family="multislope-identified", initial_state="settle", holdout=0.5,
                refit=False)
    assert alone.report.family("multislope-identified")["errors"]["held_back"]["rms"] <= 0.08
    assert rms <= 0.08, res.report


def test_p885_pair_the_default_generalizes_to_the_test_record():
    # The accuracy issue's target: fit on Model_Vi_Do.dat, predict the uncompensated
    # stretch of Test_Vi_Do_Di.dat (mean removed) with the plain default fit. The
    # identification record is one periodic major loop: the minor loops are not
    # determined by it, and its output lags the input by more than the sensor's one
    # sample: the default delay rule adopts the lag, on the identification record alone,
    # and the model predicts with its own delay.
    u, y = datasets.p885(ROOT)
    ut, yt = datasets.p885_test(ROOT)
    res = fit(u, y)
    rep = res.report.to_dict()
    d = rep["data"]["delay"]["samples"]
    assert 1 <= d <= 5 and res.model.delay == d
    a, z = datasets.P885_TEST_UNCOMPENSATED
    e = yt[a:z] - res.model.predict(ut)[a:z]
    test_rms = np.sqrt(np.mean((e - e.mean()) ** 2))
    held = res.report.family(res.report.chosen)["errors"]["held_back"]["rms"]
    assert test_rms <= 0.35, (test_rms, res.report)
    assert held <= 0.30, res.report
    assert {x["family"] for x in rep["skipped"]} == OPEN_LOOPS   # minor loops undetermined
    # the same record as a validation record: judged and reported per family
    val = fit(u, y, validate=(ut, yt))
    assert val.model.delay == d
    for f in val.report.families:
        assert f["held_back_by_kind"]["validation record"]["rms"] > 0
    e = yt[a:z] - val.model.predict(ut)[a:z]
    assert np.sqrt(np.mean((e - e.mean()) ** 2)) <= 0.35, val.report
    # without the delay the same default misses the target (the starting point)
    plain = fit(u, y, delay=0)
    e = yt[a:z] - plain.model.predict(ut)[a:z]
    assert np.sqrt(np.mean((e - e.mean()) ** 2)) > 0.35
