"""The schema of a fit's report and of ``model.metadata["fit"]`` (report_schema.py),
checked on fits that between them give every part of it: every family, skipped and
excluded families, a start state chosen from the record, a settling sweep, an adopted
delay and its confirmation, a validation record, the threshold search, a shape, kernels
and their regularization, and the decision on creep. The other tests read the decisions
through these keys; only test_report_text.py reads the report's wording."""

import json
import warnings

import numpy as np
import pytest
from report_schema import MODEL_FIT, REPORT, problems

import pihyst
from pihyst import ClassicalPI
from pihyst.exceptions import PihystWarning
from pihyst.model import Creep
from pihyst.sim import signals


def ramps(levels, n=40):
    levels = np.asarray(levels, dtype=float)
    return np.concatenate([np.linspace(a, b, n, endpoint=False) for a, b in
                           zip(levels[:-1], levels[1:])] + [levels[-1:]])


TRUE = ClassicalPI([0, 20, 45], [0.3, 0.2, 0.1], offset=1.0)
TRUE = TRUE.replace(initial_state=TRUE.simulate(np.array([0.0, 150.0, 0.0])).final_state)
MAJOR = ramps([0, 150] * 6 + [0])
MINOR = ramps([0, 150, 0, 110, 30, 140, 0, 150, 0, 90, 20, 130, 0, 150, 0, 120, 40, 150, 0])


def _fits():
    noise = np.random.default_rng(0).normal(0, 0.01, MINOR.size)
    lagged = np.r_[np.full(3, TRUE.predict(MINOR)[0]), TRUE.predict(MINOR)[:-3]] + noise
    u2 = ramps([60, 150, 0, 120, 30, 140, 10, 90, 50, 150, 0])
    creepy = ClassicalPI([0.0, 10.0, 25.0, 45.0], [0.15, 0.06, 0.04, 0.03],
                         creep=Creep([0.3, 3.0, 30.0], [0.02, 0.035, 0.015], dt=0.1))
    t, uc = signals.decaying_triangles(period_s=60.0, dt=0.1)
    yc = creepy.predict(uc, t=t) + np.random.default_rng(1).normal(0, 0.002, uc.size)
    return {
        # every family; multislope skipped (only major loops); some excluded
        "default, bounded": lambda: pihyst.fit(MAJOR, TRUE.predict(MAJOR), max_operators=3),
        "delay adopted, validated": lambda: pihyst.fit(
            MINOR, lagged, family="classical", validate=(u2, TRUE.predict(u2))),
        "shape searched, settled": lambda: pihyst.fit(
            MINOR, TRUE.predict(MINOR) + noise, family=["multislope", "multislope-identified"],
            initial_state="settle"),
        "creep decided": lambda: pihyst.fit(uc, yc, t=t, family="classical"),
        "creep fitted": lambda: pihyst.fit(uc, yc, t=t, family="classical", creep=True),
    }


@pytest.fixture(scope="module")
def fits():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PihystWarning)
        return {name: make() for name, make in _fits().items()}


@pytest.mark.parametrize("name", list(_fits()))
def test_the_report_and_the_models_fit_summary_follow_the_schema(fits, name):
    result = fits[name]
    report = result.report.to_dict()
    assert problems(report, REPORT) == []
    assert json.loads(result.report.to_json()) == report          # JSON-ready as it is
    assert problems(result.model.metadata["fit"], MODEL_FIT) == []
    # as a model file holds it (JSON) and reads it back
    saved = type(result.model).from_dict(json.loads(json.dumps(result.model.to_dict())))
    assert problems(saved.metadata["fit"], MODEL_FIT) == []


def test_the_fits_give_every_optional_part_of_the_schema(fits):
    """The fits above are the schema's examples: each optional part is present in one."""
    reports = {name: r.report.to_dict() for name, r in fits.items()}
    families = [f for r in reports.values() for f in r["families"]]
    assert {f["family"] for f in families} == set(pihyst.identify.FAMILY_NAMES)
    assert any(f["excluded"] for f in families) and any(r["skipped"] for r in reports.values())
    assert any(f.get("regularization", {}).get("product_density") for f in families)
    assert any(f["threshold_choice"] and len(f["threshold_choice"]["sizes"]) > 1
               for f in families)
    data = [r["data"] for r in reports.values()]
    assert any(d["initial_state_choice"] for d in data)
    assert any(d["settle_samples"] for d in data) and any(d["validation"] for d in data)
    assert any(d["delay"]["samples"] and d["delay"]["confirmation"] for d in data)
    assert any(r["final"]["errors"] and "validation" in r["final"]["errors"]
               for r in reports.values())
    assert {r["creep"]["kept"] for r in reports.values() if "creep" in r} <= {True, False}
    metas = [r.model.metadata["fit"] for r in fits.values()]
    assert any("settled" in m for m in metas)
    assert any("decision" in m.get("creep", {}) for m in metas)
    assert any(m.get("creep") and "decision" not in m["creep"] for m in metas)


def test_the_schema_catches_a_changed_report(fits):
    """The checker itself: a key renamed, dropped or of another type is found."""
    report = fits["delay adopted, validated"].report.to_dict()
    renamed = json.loads(json.dumps(report))
    renamed["data"]["delay"]["adopted"] = renamed["data"]["delay"].pop("samples")
    assert problems(renamed, REPORT) == [
        "$['data']['delay']: unexpected key 'adopted'",
        "$['data']['delay']: missing key 'samples'"]
    retyped = json.loads(json.dumps(report))
    retyped["families"][0]["n_operators"] = 3.0
    assert problems(retyped, REPORT) == ["$['families'][0]['n_operators']: float, not int"]
    flag = json.loads(json.dumps(report))
    flag["families"][0]["chosen"] = 1
    assert problems(flag, REPORT) == ["$['families'][0]['chosen']: int, not bool"]
