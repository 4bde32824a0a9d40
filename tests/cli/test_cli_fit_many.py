"""pihyst fit-many: one model file per record and a summary; a bad record is reported in
the summary (exit status 2) and the others are written; bad usage is a one-line error
with exit status 2 and nothing written."""

import csv
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import pihyst
from pihyst.cli import main
from pihyst.io import read_columns

from fleets import actuator_record, local_client, make_fleet_dir, write_record


@pytest.fixture(scope="module")
def dask_client():
    yield from local_client()


def _alone(path, **options):
    """The fit of one record as pihyst fit does it (its time column gives the creep's t)."""
    cols, _ = read_columns(path, ["voltage_V", "displacement_um"], optional=["time_s"])
    return pihyst.fit(cols["voltage_V"], cols["displacement_um"], t=cols.get("time_s"),
                      **options)


def _summary(folder):
    with open(folder / "summary.csv", encoding="utf-8") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    return {r["record"]: r for r in rows}, json.loads((folder / "summary.json").read_text())


def test_fits_every_record_and_writes_models_and_summary(tmp_path, capsys):
    records = make_fleet_dir(tmp_path)
    for bad in ("text.csv", "short.csv"):
        (records / bad).unlink()
    out = tmp_path / "models"
    assert main(["fit-many", str(records), "-o", str(out), "--model", "classical"]) == 0
    text = capsys.readouterr().out
    assert "fitted 3 of 3 records" in text and "FAILED" not in text
    rows, summary = _summary(out)
    assert sorted(rows) == ["act0.csv", "act1.csv", "act2.csv"]
    assert summary["fitted"] == 3 and summary["failed"] == 0
    for name, row in rows.items():
        path = records / name
        model = pihyst.load_model(out / row["model_file"])
        alone = _alone(path, family="classical")
        assert model == alone.model    # bit for bit: == compares every parameter exactly
        assert model.metadata["fit"] == \
            json.loads(json.dumps(alone.model.metadata["fit"]))
        assert model.metadata["source"]["data"] == str(path)
        assert row["status"] == "fitted" and row["family"] == "classical" and not row["error"]
        assert int(row["n_operators"]) == model.n_operators
        held = alone.report.family("classical")["errors"]["held_back"]["rms"]
        assert float(row["held_back_rms_um"]) == held
        assert float(row["fit_time_s"]) > 0


def test_a_bad_record_fails_alone_with_exit_status_2(tmp_path, capsys):
    records = make_fleet_dir(tmp_path)
    out = tmp_path / "models"
    assert main(["fit-many", str(records), "-o", str(out), "--model", "classical"]) == 2
    cap = capsys.readouterr()
    assert "fitted 3 of 5 records" in cap.out and "2 FAILED: short.csv, text.csv" in cap.out
    assert cap.err.count("\n") == 1 and cap.err.startswith("pihyst: error: 2 of 5 records")
    assert "Traceback" not in cap.err
    rows, summary = _summary(out)
    assert summary["failed"] == 2
    assert rows["text.csv"]["status"] == "failed"
    assert rows["text.csv"]["error"] == \
        f"{records / 'text.csv'}:3:2: column 'displacement_um': 'abc' is not a number"
    assert rows["short.csv"]["error"].startswith(str(records / "short.csv"))
    assert not rows["short.csv"]["model_file"]
    assert sorted(p.name for p in out.iterdir()) == [
        "act0.json", "act1.json", "act2.json", "summary.csv", "summary.json"]


@pytest.mark.parametrize("args, message", [
    (["{missing}"], "not a folder"),
    (["{empty}"], "no records"),
    (["{named_summary}"], "cannot be named 'summary'"),
    (["{records}", "--workers", "2"], "--workers applies to --scheduler local only"),
    (["{records}", "--thresholds", "0,x"], "--thresholds: 'x' is not a number"),
    (["{records}", "--holdout", "2"], "--holdout"),
    (["{records}", "--n-operators", "0"], "--n-operators"),
    (["{records}", "--scheduler", "local", "--workers", "0"], "--workers"),
])
def test_bad_usage_is_one_line_and_writes_nothing(tmp_path, capsys, args, message):
    records = make_fleet_dir(tmp_path)
    (tmp_path / "empty").mkdir()
    named = tmp_path / "named"
    named.mkdir()
    (named / "summary.csv").write_text((records / "act0.csv").read_text())
    folders = {"missing": tmp_path / "nope", "empty": tmp_path / "empty",
               "named_summary": named, "records": records}
    out = tmp_path / "models"
    argv = ["fit-many"] + [a.format(**folders) for a in args] + ["-o", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("pihyst: error: ") and message in err and err.count("\n") == 1
    assert not out.exists()


def test_scheduler_needs_dask(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)   # as if not installed
    records = make_fleet_dir(tmp_path)
    out = tmp_path / "models"
    assert main(["fit-many", str(records), "-o", str(out), "--scheduler", "local"]) == 2
    assert capsys.readouterr().err == \
        "pihyst: error: --scheduler needs Dask: pip install 'pihyst[dask]'\n"
    assert not out.exists()


def test_on_a_running_cluster_the_models_are_the_same(tmp_path, capsys, dask_client):
    records = make_fleet_dir(tmp_path)
    serial, on_dask = tmp_path / "serial", tmp_path / "dask"
    address = dask_client.scheduler.address
    assert address.startswith("tcp://127.0.0.1:")
    assert main(["fit-many", str(records), "-o", str(serial), "--model", "classical"]) == 2
    assert main(["fit-many", str(records), "-o", str(on_dask), "--model", "classical",
                 "--scheduler", address]) == 2
    assert f"on {address}" in capsys.readouterr().out
    rows_serial, _ = _summary(serial)
    rows_dask, summary = _summary(on_dask)
    assert "2 workers" in summary["scheduler"]
    for name in rows_serial:
        a, b = rows_serial[name], rows_dask[name]
        assert (a["status"], a["error"], a["family"], a["n_operators"], a["held_back_rms_um"]) \
            == (b["status"], b["error"], b["family"], b["n_operators"], b["held_back_rms_um"])
        if a["model_file"]:
            assert pihyst.load_model(serial / a["model_file"]) == \
                pihyst.load_model(on_dask / b["model_file"])


@pytest.mark.slow
def test_scheduler_local_from_the_command_line(tmp_path):
    """The installed command with --scheduler local: worker processes, one per core."""
    pytest.importorskip("distributed", reason="needs dask.distributed: "
                                              "pip install 'pihyst[dask]'")
    records = make_fleet_dir(tmp_path)
    out = tmp_path / "models"
    proc = subprocess.run([sys.executable, "-m", "pihyst", "fit-many", str(records), "-o",
                           str(out), "--model", "classical", "--scheduler", "local",
                           "--workers", "2"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2, proc.stderr
    assert "on a local cluster" in proc.stdout and "fitted 3 of 5 records" in proc.stdout
    assert proc.stderr.startswith("pihyst: error: 2 of 5 records") and \
        proc.stderr.count("\n") == 1, proc.stderr
    for k in range(3):
        alone = _alone(records / f"act{k}.csv", family="classical")
        model = pihyst.load_model(out / f"act{k}.json")
        assert model == alone.model
        np.testing.assert_array_equal(model.weights, alone.model.weights)


def _fit_alone(tmp_path, path, *options):
    model = tmp_path / "alone" / (path.stem + ".json")
    model.parent.mkdir(exist_ok=True)
    assert main(["fit", str(path), *options, "-o", str(model)]) == 0
    return pihyst.load_model(model)


def _raw(path, u, y, rate=None):
    """A record as an instrument writes it: tab columns, no header, a sensor 1 sample
    late (column 3), and an unrelated column."""
    rows = zip(np.arange(u.size) * 0.25, u, np.r_[y[:1], y[:-1]])
    path.write_text("".join(f"{k!r}\t{a!r}\t{c!r}\t7\n" for k, a, c in
                            ((float(k), float(a), float(c)) for k, a, c in rows)))
    return path


def test_record_options_apply_to_every_file_as_pihyst_fit(tmp_path, capsys):
    folder = tmp_path / "raw"
    folder.mkdir()
    for k in range(2):
        _raw(folder / f"act{k}.dat", *actuator_record(k))
    options = ["--voltage", "2", "--displacement", "3", "--time", "1", "--lag", "1",
               "--model", "classical"]
    out = tmp_path / "models"
    assert main(["fit-many", str(folder), "-o", str(out), *options]) == 0
    text = capsys.readouterr().out
    assert "fitted 2 of 2 records" in text and "displacement 1 sample(s) later" in text
    for k in range(2):
        alone = _fit_alone(tmp_path, folder / f"act{k}.dat", *options)
        many = pihyst.load_model(out / f"act{k}.json")
        assert many == alone and "creep" in many.metadata["fit"]
        assert (out / f"act{k}.json").read_text().count("\n") > 0


def test_manifest_gives_options_per_file(tmp_path, capsys):
    folder = tmp_path / "raw"
    folder.mkdir()
    u, y = actuator_record(0)
    _raw(folder / "a.dat", u, y)
    write_record(folder / "b.csv", *actuator_record(1))
    (folder / "notes.md").write_text("not a record")
    os.symlink(folder / "loop", folder / "loop")
    manifest = tmp_path / "m.json"
    manifest.write_text(json.dumps({"a.dat": {"voltage": 2, "displacement": 3, "time": "1",
                                              "lag": 1}}))
    out = tmp_path / "models"
    assert main(["fit-many", str(folder), "-o", str(out), "--model", "classical",
                 "--manifest", str(manifest)]) == 0
    text = capsys.readouterr().out
    assert "skipped loop: a symlink loop" in text and "skipped notes.md: not a record" in text
    assert "fitted 2 of 2 records" in text and "(2 other files skipped)" in text
    assert pihyst.load_model(out / "a.json") == _fit_alone(
        tmp_path, folder / "a.dat", "--voltage", "2", "--displacement", "3", "--time", "1",
        "--lag", "1", "--model", "classical")
    assert pihyst.load_model(out / "b.json") == _fit_alone(tmp_path, folder / "b.csv",
                                                           "--model", "classical")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["skipped"] == {"loop": "a symlink loop",
                                  "notes.md": "not a record format (give --pattern to fit it)"}
    manifest.write_text(json.dumps({"a.dat": {"lag": -1}}))
    assert main(["fit-many", str(folder), "-o", str(tmp_path / "m2"), "--manifest",
                 str(manifest)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"pihyst: error: --manifest {manifest}: a.dat: argument --lag")
    assert err.count("\n") == 1


def test_manifest_says_which_files_have_a_units_row(tmp_path, capsys):
    folder = tmp_path / "raw"
    folder.mkdir()
    for name, units in (("a.csv", "Volt,micron"), ("b.csv", None)):
        u, y = actuator_record(0 if units else 1)
        (folder / name).write_text("voltage_V,displacement_um\n"
                                   + (units + "\n" if units else "")
                                   + "".join(f"{a!r},{b!r}\n"
                                             for a, b in zip(u.tolist(), y.tolist())))
    manifest = tmp_path / "m.json"
    manifest.write_text(json.dumps({"a.csv": {"units_row": True},
                                    "b.csv": {"units_row": False}}))
    out = tmp_path / "models"
    assert main(["fit-many", str(folder), "-o", str(out), "--model", "classical",
                 "--manifest", str(manifest)]) == 0
    assert "fitted 2 of 2 records" in capsys.readouterr().out
    assert pihyst.load_model(out / "a.json") == _fit_alone(
        tmp_path, folder / "a.csv", "--units-row", "--model", "classical")
    assert pihyst.load_model(out / "b.json") == _fit_alone(
        tmp_path, folder / "b.csv", "--no-units-row", "--model", "classical")


def test_the_model_files_name_their_record_as_pihyst_fits_do(tmp_path, capsys):
    """fit-many's model file carries what pihyst fit's carries about its record (columns,
    units, samples, the reading options), not only the file's name."""
    records = make_fleet_dir(tmp_path)
    for bad in ("text.csv", "short.csv"):
        (records / bad).unlink()
    out = tmp_path / "models"
    assert main(["fit-many", str(records), "-o", str(out), "--model", "classical"]) == 0
    single = tmp_path / "one.json"
    assert main(["fit", str(records / "act1.csv"), "--model", "classical", "-o",
                 str(single)]) == 0
    capsys.readouterr()
    rows, _ = _summary(out)
    many = pihyst.load_model(out / rows["act1.csv"]["model_file"]).metadata["source"]
    alone = pihyst.load_model(single).metadata["source"]
    assert many["record"] == alone["record"] and many["record"]["columns"]
    assert many["data"] == alone["data"]
