"""pihyst.fit_many: every record fitted exactly as pihyst.fit fits it alone, serially or
on a Dask cluster; a bad record is reported with its error and never stops the others."""

import numpy as np
import pytest

import pihyst
from pihyst.fleet import _fit_many
from pihyst.io import read_columns

from fleets import actuator_record, local_client, make_fleet_dir, write_record

FAST = {"family": "classical"}   # one family: quick fits; the default is tested once
SEVERAL = {"family": ["classical", "multislope"], "n_candidates": 8}   # and a choice


@pytest.fixture(scope="module")
def dask_client():
    yield from local_client()


def _alone(path, **options):
    cols, _ = read_columns(path, ["voltage_V", "displacement_um"])
    return pihyst.fit(cols["voltage_V"], cols["displacement_um"], **options)


def assert_same_fit(outcome, alone):
    """Bit for bit: every parameter, the metadata, the report and every family's model."""
    assert outcome.status == "fitted", outcome.error
    got = outcome.result
    assert got.model == alone.model
    np.testing.assert_array_equal(got.model.weights, alone.model.weights)
    assert got.model.to_dict() == alone.model.to_dict()
    assert got.report.to_dict() == alone.report.to_dict()
    assert {k: m.to_dict() for k, m in got.models.items()} == \
        {k: m.to_dict() for k, m in alone.models.items()}


def test_serial_fleet_equals_fitting_each_record_alone(tmp_path):
    folder = make_fleet_dir(tmp_path)
    paths = sorted(folder.glob("act*.csv"))
    result = pihyst.fit_many(paths, **FAST)
    assert result.ok and result.scheduler == "serial"
    assert [o.record for o in result] == [p.name for p in paths]
    for path in paths:
        assert_same_fit(result[path.name], _alone(path, **FAST))
    assert set(result.models) == {p.name for p in paths}


def test_several_families_and_the_choice_are_identical():
    u, y = actuator_record(4)
    result = pihyst.fit_many({"a4": (u, y)}, **SEVERAL)
    assert_same_fit(result["a4"], pihyst.fit(u, y, **SEVERAL))
    assert len(result["a4"].result.models) == 2


@pytest.mark.slow
def test_default_options_fit_every_family_identically():
    u, y = actuator_record(4)
    result = pihyst.fit_many({"a4": (u, y)})
    assert_same_fit(result["a4"], pihyst.fit(u, y))
    assert len(result["a4"].result.models) > 2


def test_a_bad_record_is_reported_and_the_others_are_fitted(tmp_path):
    folder = make_fleet_dir(tmp_path)
    missing = folder / "gone.csv"
    records = sorted(folder.glob("*.csv")) + [missing]
    seen = []
    result = pihyst.fit_many(records, progress=seen.append, **FAST)
    assert not result.ok
    assert sorted(o.record for o in seen) == sorted(o.record for o in result)
    assert [o.record for o in result.fitted] == ["act0.csv", "act1.csv", "act2.csv"]
    errors = {o.record: o.error for o in result.failed}
    assert errors["text.csv"] == f"{folder / 'text.csv'}:3:2: column 'displacement_um': " \
                                 "'abc' is not a number"
    assert errors["gone.csv"].startswith(f"{missing}: cannot read file")
    assert errors["short.csv"].startswith(f"{folder / 'short.csv'}")
    assert "sample" in errors["short.csv"] or "samples" in errors["short.csv"]
    for o in result.failed:
        assert o.result is None and o.model is None and o.traceback is None
        assert "\n" not in o.error
    row = {r["record"]: r for r in result.summary()}["text.csv"]
    assert row["status"] == "failed" and row["family"] is None


def test_a_fit_error_names_the_file_line_and_column(tmp_path):
    """A FitError at a sample becomes FILE:LINE:COLUMN, as pihyst fit reports it."""
    u, y = actuator_record(0)
    u = u.copy()
    u[:] = 20.0   # constant input: cannot be fitted
    path = write_record(tmp_path / "flat.csv", u, y)
    out = pihyst.fit_many([path], **FAST)["flat.csv"]
    assert out.status == "failed"
    assert out.error.startswith(f"{path}:") and "constant" in out.error.lower()


def test_pairs_named_by_position_and_bad_pairs(tmp_path):
    u, y = actuator_record(1)
    result = pihyst.fit_many([(u, y), (u, y[:-5]), 3], **FAST)
    assert [o.record for o in result] == ["0", "1", "2"]
    assert result["0"].ok
    assert not result["1"].ok and "samples" in result["1"].error
    assert not result["2"].ok and "(u, y) pair" in result["2"].error


def test_unexpected_errors_keep_their_traceback(monkeypatch):
    def broken(u, y, **options):
        raise RuntimeError("a bug")

    monkeypatch.setattr(_fit_many, "fit", broken)
    u, y = actuator_record(0)
    out = pihyst.fit_many({"a": (u, y)})["a"]
    assert out.error == "RuntimeError: a bug"
    assert "Traceback" in out.traceback and "broken" in out.traceback


def test_options_and_records_are_checked_first():
    u, y = actuator_record(0)
    with pytest.raises(TypeError, match="n_opertors"):
        pihyst.fit_many({"a": (u, y)}, n_opertors=3)
    with pytest.raises(ValueError, match="two records are named 'x.csv'"):
        pihyst.fit_many(["a/x.csv", "b/x.csv"])
    with pytest.raises(TypeError, match="mapping"):
        pihyst.fit_many("records/")


def test_warnings_are_kept_with_the_record():
    """An ill-conditioned fit: its warning goes with the outcome, not to the caller."""
    u, y = actuator_record(0)
    thresholds = [0, 10, 10.000001]   # two nearly identical operators
    alone_warnings = []
    with pytest.warns(pihyst.IllConditionedWarning) as caught:
        alone = pihyst.fit(u, y, family="classical", thresholds=thresholds)
    alone_warnings = [str(w.message) for w in caught]
    out = pihyst.fit_many({"a": (u, y)}, family="classical", thresholds=thresholds)["a"]
    assert_same_fit(out, alone)
    assert list(out.warnings) == alone_warnings


# ------------------------------------------------------------------ on a Dask cluster
def test_dask_fleet_equals_serial_and_alone(tmp_path, dask_client):
    folder = make_fleet_dir(tmp_path)
    records = sorted(folder.glob("*.csv"))
    on_dask = pihyst.fit_many(records, client=dask_client, **FAST)
    serial = pihyst.fit_many(records, **FAST)
    assert "2 workers" in on_dask.scheduler
    assert [o.record for o in on_dask] == [o.record for o in serial]
    assert [o.status for o in on_dask] == [o.status for o in serial]
    assert [o.error for o in on_dask] == [o.error for o in serial]
    for path in sorted(folder.glob("act*.csv")):
        assert_same_fit(on_dask[path.name], _alone(path, **FAST))


def test_dask_progress_reports_every_record(dask_client):
    fleet = {f"a{k}": actuator_record(k) for k in range(4)}
    seen = []
    result = pihyst.fit_many(fleet, client=dask_client, progress=seen.append, **FAST)
    assert result.ok and sorted(o.record for o in seen) == sorted(fleet)
    for name, (u, y) in fleet.items():
        assert_same_fit(result[name], pihyst.fit(u, y, **FAST))


@pytest.mark.slow
def test_worker_processes_give_the_same_bits(tmp_path):
    """Worker processes (as --scheduler local starts them, BLAS in one thread each)."""
    distributed = pytest.importorskip(
        "distributed", reason="needs dask.distributed: pip install 'pihyst[dask]'")
    fleet = {f"a{k}": actuator_record(k) for k in range(3)}
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        result = pihyst.fit_many(fleet, client=client, **SEVERAL)
    for name, (u, y) in fleet.items():
        assert_same_fit(result[name], pihyst.fit(u, y, **SEVERAL))
