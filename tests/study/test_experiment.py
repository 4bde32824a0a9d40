"""The paper's study (pihyst.study) on the simulated beam, and the report study."""

import json

import numpy as np
import pytest

from pihyst import paper
from pihyst.model import ClassicalPI, MultislopePI
from pihyst.sim import make_plant
from pihyst.sim.signals import decaying_triangles, triangle
from pihyst.study import (
    CLASSICAL_THRESHOLDS,
    MULTISLOPE_THRESHOLDS,
    PAPER,
    Recording,
    fit_paper_models,
    loop_study,
    paper_study,
    signed_extremes,
)


@pytest.fixture(scope="module")
def study():
    return paper_study(dt=1.0, variants=False, progress=None)


def test_the_paper_models_are_fitted_with_the_papers_thresholds(study):
    classical = study.models["classical"].model
    multislope = study.models["multislope"].model
    assert isinstance(classical, ClassicalPI) and isinstance(multislope, MultislopePI)
    np.testing.assert_array_equal(classical.thresholds, [0, 10, 30])     # 150 never moves
    np.testing.assert_array_equal(multislope.thresholds, MULTISLOPE_THRESHOLDS)
    assert (multislope.a, multislope.b, multislope.h, multislope.U) == (0.8, 1.2, 0.5, 150)
    assert any("r = 150 V never moves" in n for n in study.models["classical"].notes)
    entry = study.metrics["models"]["classical"]
    assert entry["requested_thresholds"] == list(CLASSICAL_THRESHOLDS)
    # as the paper: zero initial state, no offset
    assert classical.offset == 0 and not classical.initial_state.any()


def test_the_papers_findings_hold_on_the_paper_beam(study):
    m = study.metrics
    fit = m["fit"]
    # multislope beats the conventional PI by a wide margin (paper: 78.6 % less)
    assert m["improvement_pct"] > 60
    assert fit["multislope"]["mean_abs"] < 0.35 < 0.7 < fit["classical"]["mean_abs"]
    # the conventional PI ends ~3 um above the beam at 0 V (paper: -3.09 um)
    assert -4.0 < fit["classical"]["extremes"]["low"] < -2.5
    # feedforward tracking with the multislope inverse: < 1 % of the range (paper 0.63 %)
    tr = m["tracking"]["triangle"]["errors"]
    assert tr["multislope"]["mean_abs_pct"] < 1.0
    assert tr["multislope"]["mean_abs"] < tr["none"]["mean_abs"] / 5
    assert tr["multislope"]["saturated_samples"] == 0


def test_the_automatic_best_is_judged_on_data_it_was_not_fitted_on(study):
    val = study.metrics["validation"]
    assert val["best"]["mean_abs"] < min(val["classical"]["mean_abs"],
                                         val["multislope"]["mean_abs"])
    assert study.records["validation"].u.size != study.records["identification"].u.size
    assert "held-back" in study.metrics["models"]["best"]["criterion"]


def test_metrics_sit_beside_the_papers_numbers_and_are_json(study):
    m = study.metrics
    assert m["paper"] == PAPER == paper.published()
    json.dumps(m, allow_nan=False)
    h = m["headline"]
    assert h["fit_mean_abs_multislope_um"] == m["fit"]["multislope"]["mean_abs"]


def test_predictions_and_records_are_consistent(study):
    loop = study.loop
    t, u = triangle(dt=1.0)
    np.testing.assert_array_equal(loop.u, u)
    np.testing.assert_allclose(loop.y, make_plant("paper-beam", seed=0).run(u, t))
    for key, fm in study.models.items():
        np.testing.assert_array_equal(study.predictions["loop"][key], fm.model.predict(u))
    tr = study.tracking["triangle"]
    assert np.all((tr["voltage"]["multislope"] >= 0) & (tr["voltage"]["multislope"] <= 150))
    assert tr["desired"].max() == pytest.approx(0.98 * loop.y[np.argmax(loop.u)])


def test_operator_curves_mark_the_multislope_landmarks(study):
    ops = study.operators["multislope"]
    assert ops["outputs"].shape == (ops["u"].size, 4)
    texts = [a[2] for a in ops["annotations"]]
    assert "rising kink 95 V" in texts and "falling kink 15 V" in texts
    assert "holds from 150 V to 130 V" in texts
    # the r = 40 operator's output at the marked rising kink is where the curve passes
    x, y, _ = ops["annotations"][0]
    up = ops["u"][:ops["u"].size // 2 + 1]
    assert np.interp(x, up, ops["outputs"][:up.size, 3]) == pytest.approx(y)


def test_variants_repeat_the_comparison():
    study = paper_study(dt=2.0, variants=True, progress=None)
    rows = {r["plant"]: r for r in study.variants}
    assert set(rows) >= {"paper-beam", "lens", "s-shaped", "remanent"}
    for r in rows.values():
        assert r["validation"]["best"] < r["validation"]["classical"]
    assert rows["paper-beam"]["improvement_pct"] > 60


def test_progress_lines_are_numbered():
    lines = []
    paper_study(dt=2.0, variants=False, progress=lines.append)
    assert lines[0].startswith("[1/7] recording the loop")
    assert lines[-1].startswith("[7/7]")


def test_signed_extremes_keep_the_sign():
    u = np.array([0.0, 10.0, 60.0, 70.0, 140.0, 150.0])
    e = np.array([-3.0, 1.0, 0.5, -2.0, 2.4, 1.0])
    assert signed_extremes(u, e) == {"low": -3.0, "middle": -2.0, "high": 2.4}


def test_loop_study_on_a_record_that_does_not_start_at_rest():
    t, u = decaying_triangles(u_min=-20, u_max=80, n_triangles=3, dt=1.0)
    u = np.concatenate([np.full(5, 30.0), np.linspace(30, -20, 26)[1:], u[1:]])
    t = np.arange(u.size, dtype=float)
    beam = make_plant("lens", noise=False)
    y = beam.run(np.clip(u + 20, 0, 150), t) - 100.0        # arbitrary sensor zero
    study = loop_study(t, u, y, source="test", progress=None)
    m = study.metrics
    assert m["threshold_scale"] == pytest.approx(100 / 150)
    assert m["loop"]["settle_samples"] > 0
    assert study.loop.u.size == u.size - m["loop"]["settle_samples"]
    assert all(m["fit"][k]["mean_abs"] < 2.0 for k in ("classical", "multislope", "best"))
    np.testing.assert_allclose(study.models["classical"].model.thresholds,
                               [0, 10 * 100 / 150, 30 * 100 / 150])


def test_fit_paper_models_scales_the_thresholds_and_leaves_out_those_never_moving():
    t, u = triangle(u_max=100.0, dt=1.0)
    y = make_plant(noise=False).run(u, t)
    models = fit_paper_models(Recording("loop", t, u, y), scale=100 / 150)
    np.testing.assert_allclose(models["classical"].model.thresholds, [0, 20 / 3, 20])
    assert "r = 100 V never moves" in models["classical"].notes[0]
    np.testing.assert_allclose(models["multislope"].model.thresholds,
                               [0, 40 / 3, 20, 80 / 3])
    assert models["multislope"].model.U == 100
