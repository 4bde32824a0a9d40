"""Fits to the simulated beams (pihyst.sim: Preisach and Bouc-Wen, with creep, sensor
noise and 10 mV supply steps - not PI models).

Issue 3, item 9: fitted on one full triangle followed by decaying triangles, judged on a
different signal with reversals inside the range (ramps between random levels).
"""

import numpy as np
import pytest

from pihyst import fit
from pihyst.metrics import mean_abs_error
from pihyst.sim import PLANT_NAMES, make_plant
from pihyst.sim.signals import decaying_triangles, random_ramps, triangle

pytestmark = pytest.mark.slow


def _record(name):
    t, u = decaying_triangles()              # full 0-150-0 V triangle, then 4 decaying ones
    y = make_plant(name, seed=1).run(u, t)
    return u, y


@pytest.mark.parametrize("name", PLANT_NAMES)
def test_default_fit_within_half_a_percent_on_random_ramps(name):
    # The error of one run of random ramps depends on the run: creep (1-2 % per decade)
    # builds up while the ramps dwell high, which no rate-independent model can follow
    # (without creep the default fit is within 0.03-0.3 %). The target applies to the
    # mean over runs; no single run may exceed it by more than a quarter.
    u, y = _record(name)
    res = fit(u, y)
    assert res.model.delay == 0, res.report.to_dict()["data"]["delay"]["rule"]  # no lag
    span = np.ptp(y)
    errors = []
    for seed in range(5):
        t2, u2 = random_ramps(seed=100 + seed)
        y2 = make_plant(name, seed=200 + seed).run(u2, t2)
        errors.append(100 * mean_abs_error(y2, res.model.predict(u2)) / span)
    msg = f"{name} ({res.report.chosen}): {np.round(errors, 3)} % of {span:.1f} um"
    assert np.mean(errors) <= 0.5, msg
    assert max(errors) <= 0.625, msg


def test_four_operator_multislope_beats_classical_on_the_paper_beam_major_loop():
    # the paper's comparison: four operators each, judged on the major loop (here a fresh
    # 0-150-0 V triangle run with new noise); the multislope shape identified from the data
    u, y = _record("paper-beam")
    t2, u2 = triangle()
    y2 = make_plant("paper-beam", seed=7).run(u2, t2)
    err = {}
    for family in ("classical", "multislope-identified"):
        model = fit(u, y, family=family, n_operators=4).model
        err[family] = mean_abs_error(y2, model.predict(u2))
    assert err["multislope-identified"] <= 0.5 * err["classical"], err


def test_a_dead_time_on_a_simulated_beam_is_found_to_the_sample():
    # 10 samples (1 % of a cycle) of dead time on the paper beam: the classical probe's
    # best is off by its shape error, the fitted structure's descent from it is exact
    t1, u1 = decaying_triangles(period_s=20.0, dt=0.02)
    u = np.tile(u1, 2)
    t = 0.02 * np.arange(u.size)
    y = make_plant("paper-beam", seed=1).run(u, t)
    d = 10
    y = np.r_[np.full(d, y[0]), y[:-d]]
    res = fit(u, y, t=t)
    rep = res.report.to_dict()["data"]["delay"]
    assert res.model.delay == d and rep["samples"] == d, rep["rule"]
    assert res.model.sample_period == pytest.approx(0.02)
    assert rep["confirmation"]["samples"] == d
