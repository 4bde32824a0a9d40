"""pihyst fit: fits a CSV, saves a model that loads and predicts, prints the report;
bad input is a one-line file:line:column error with exit status 2 and no output file."""

import json
import subprocess
import sys

import numpy as np
import pytest

import pihyst
from pihyst.cli import main
from pihyst.identify._report import FitReport
from pihyst.io import read_columns, write_columns


def ramps(levels, n=30):
    levels = np.asarray(levels, dtype=float)
    return np.concatenate([np.linspace(a, b, n, endpoint=False) for a, b in
                           zip(levels[:-1], levels[1:])] + [levels[-1:]])


def record(tmp_path, lo=0.0, hi=150.0, name="data.csv", noise=0.01):
    """A loop of a known multislope model on [lo, hi], as a docs/interfaces.md CSV."""
    v = ramps([0, 150, 0, 120, 30, 150, 0, 90, 10, 150, 0, 70, 0, 150, 0])
    model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    y = model.predict(v) + np.random.default_rng(0).normal(0, noise, v.size)
    u = lo + (hi - lo) * v / 150
    path = tmp_path / name
    write_columns(path, {"time_s": np.arange(v.size, dtype=float), "voltage_V": u,
                         "displacement_um": y})
    return path, u, y


def test_fit_saves_a_model_that_loads_and_predicts(tmp_path, capsys):
    data, u, y = record(tmp_path)
    out = tmp_path / "model.json"
    assert main(["fit", str(data), "-o", str(out)]) == 0
    model = pihyst.load_model(out)
    fitted = model.metadata["fit"]
    assert fitted["family"] in pihyst.identify.FAMILY_NAMES
    assert fitted["data"]["held_back_samples"] > 0 and fitted["final"]["refit"]
    assert fitted["creep"]["decision"]["kept"] == (model.creep is not None)
    pred = tmp_path / "pred.csv"
    assert main(["predict", str(out), str(data), "-o", str(pred)]) == 0
    cols, _ = read_columns(pred, ["displacement_um"])
    np.testing.assert_allclose(cols["displacement_um"], model.predict(u), rtol=1e-12)
    assert np.sqrt(np.mean((model.predict(u) - y) ** 2)) < 0.05


def test_fit_one_family_with_given_thresholds(tmp_path, capsys):
    data, *_ = record(tmp_path)
    out = tmp_path / "m.json"
    assert main(["fit", str(data), "--model", "classical", "--thresholds", "0,10,30",
                 "-o", str(out)]) == 0
    model = pihyst.load_model(out)
    assert model.family == "classical"
    np.testing.assert_array_equal(model.thresholds, [0, 10, 30])
    assert model.metadata["fit"]["threshold_choice"] is None      # given, not chosen


def test_json_report_and_the_text_printed_are_the_same_report(tmp_path, capsys):
    """The command prints the fit's report (its wording: identify/test_report_text.py),
    then one line on the file written; --json prints the report's data instead."""
    data, *_ = record(tmp_path)
    out = tmp_path / "m.json"
    options = ["fit", str(data), "--model", "multislope", "--n-operators", "4", "--no-creep",
               "-o", str(out)]
    assert main(options + ["--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["chosen"] == "multislope"
    fam = rep["families"][0]
    assert fam["n_operators"] == 4 and len(fam["threshold_choice"]["reasons"]) == 4
    assert fam["errors"]["held_back"]["rms"] >= 0
    out.unlink()
    assert main(options) == 0
    text = capsys.readouterr().out
    assert f"\n{FitReport(rep)}\n\nwrote {out}: multislope model, 4 operators (pihyst " \
           f"predict {out} INPUT.csv -o OUT.csv)\n" in text
    assert text.count("\n") == str(FitReport(rep)).count("\n") + 4   # + read line, wrote


@pytest.mark.parametrize("lo, hi", [(0.0, 3.6), (-150.0, 150.0)])
def test_other_input_ranges_fit_and_predict(tmp_path, lo, hi):
    data, u, y = record(tmp_path, lo, hi)
    out = tmp_path / "m.json"
    assert main(["fit", str(data), "--model", "multislope", "--thresholds",
                 ",".join(str(r * (hi - lo) / 150) for r in (0, 20, 30, 40)),
                 "-o", str(out)]) == 0
    model = pihyst.load_model(out)
    assert model.input_range == pytest.approx((lo, hi))
    assert np.sqrt(np.mean((model.predict(u) - y) ** 2)) < 0.02
    pred = tmp_path / "pred.csv"
    assert main(["predict", str(out), str(data), "-o", str(pred)]) == 0


def _fails(capsys, argv, out):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("pihyst: error: ")
    assert not out.exists()
    return err


def test_errors_are_one_line_with_position(tmp_path, capsys):
    out = tmp_path / "m.json"
    bad = tmp_path / "nan.csv"
    bad.write_text("voltage_V,displacement_um\n0,0\n10,nan\n")
    err = _fails(capsys, ["fit", str(bad), "-o", str(out)], out)
    assert f"{bad}:3:2:" in err
    missing = tmp_path / "missing.csv"
    missing.write_text("voltage_V\n0\n1\n")
    assert "missing column 'displacement_um'" in _fails(
        capsys, ["fit", str(missing), "-o", str(out)], out)
    const = tmp_path / "const.csv"
    const.write_text("displacement_um,voltage_V\n" + "".join(f"{i},5\n" for i in range(40)))
    err = _fails(capsys, ["fit", str(const), "-o", str(out)], out)
    assert f"{const}:2:2:" in err and "constant" in err
    few = tmp_path / "few.csv"
    few.write_text("voltage_V,displacement_um\n0,0\n1,1\n2,2\n")
    assert "too few samples" in _fails(capsys, ["fit", str(few), "-o", str(out)], out)


def test_threshold_never_reached_and_bad_options(tmp_path, capsys):
    data, *_ = record(tmp_path)
    out = tmp_path / "m.json"
    err = _fails(capsys, ["fit", str(data), "--model", "classical", "--thresholds",
                          "0,10,150", "-o", str(out)], out)
    assert "never move the operator of threshold 150" in err and f"{data}:" in err
    assert "not a number" in _fails(capsys, ["fit", str(data), "--thresholds", "0,x",
                                             "-o", str(out)], out)
    assert "--holdout" in _fails(capsys, ["fit", str(data), "--holdout", "2", "-o",
                                          str(out)], out)
    assert "multislope" in _fails(capsys, ["fit", str(data), "--model", "multislope",
                                           "--thresholds", "0,80", "-o", str(out)], out)
    assert main(["fit", str(data), "--model", "nonsense", "-o", str(out)]) == 2
    assert "argument --model" in capsys.readouterr().err
    assert not out.exists()


def test_warning_is_printed_and_model_still_written(tmp_path, capsys):
    data, *_ = record(tmp_path)
    out = tmp_path / "m.json"
    assert main(["fit", str(data), "--model", "classical", "--thresholds",
                 "0,30,30.0000001", "-o", str(out)]) == 0
    assert "pihyst: warning: " in capsys.readouterr().err
    assert out.exists()


def test_entry_point(tmp_path):
    data, *_ = record(tmp_path)
    out = tmp_path / "m.json"
    proc = subprocess.run([sys.executable, "-m", "pihyst", "fit", str(data), "--model",
                           "classical", "--n-operators", "3", "--json", "-o", str(out)],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert pihyst.load_model(out).n_operators == 3
    report = json.loads(proc.stdout)                # the report of that fit
    assert report["chosen"] == "classical"
    assert len(report["families"][0]["threshold_choice"]["reasons"]) == 3


def test_creep_is_decided_with_a_time_column_and_skipped_with_a_broken_one(tmp_path, capsys):
    # with a time column creep is decided: test_fit_saves_a_model_that_loads_and_predicts
    data, u, y = record(tmp_path)
    out = tmp_path / "model.json"
    assert main(["fit", str(data), "--no-creep", "-o", str(out)]) == 0
    assert "creep" not in pihyst.load_model(out).metadata["fit"]           # not tried
    # time running backwards: fitted without creep, and a warning says where
    t = np.arange(u.size, dtype=float)
    t[40] = 1.0
    broken = tmp_path / "broken.csv"
    write_columns(broken, {"time_s": t, "voltage_V": u, "displacement_um": y})
    assert main(["fit", str(broken), "-o", str(out)]) == 0
    captured = capsys.readouterr()
    assert "creep" not in pihyst.load_model(out).metadata["fit"]
    warning = [line for line in captured.err.splitlines() if "time column is not used" in line]
    assert len(warning) == 1 and "broken.csv:" in warning[0] and "sample 40" in warning[0]
    # ... and when the fit then fails, its error is the only line (no warning first)
    out.unlink()
    assert main(["fit", str(broken), "--model", "classical", "--thresholds", "0,10,1e9",
                 "-o", str(out)]) == 2
    captured = capsys.readouterr()
    assert len(captured.err.strip().splitlines()) == 1, captured.err
    assert "time column" not in captured.err and not out.exists()


def test_fit_prints_each_step_with_its_time_when_asked(tmp_path, capsys, monkeypatch):
    """On a terminal (PIHYST_PROGRESS=1 here) each step of the fit is one stderr line
    with its time; PIHYST_PROGRESS=0 (and a pipe) prints none."""
    import re

    data, _, _ = record(tmp_path)
    monkeypatch.setenv("PIHYST_PROGRESS", "1")
    assert main(["fit", str(data), "--no-creep", "-o", str(tmp_path / "a.json")]) == 0
    lines = [x for x in capsys.readouterr().err.splitlines() if x.startswith("pihyst fit: ")]
    steps = [re.sub(r" \(\d+\.\d\d s\)$", "", x[len("pihyst fit: "):]) for x in lines]
    assert all(re.search(r" \(\d+\.\d\d s\)$", x) for x in lines)
    assert steps[0].startswith("start state:") and steps[1].startswith("delay:")
    assert any(s.startswith("classical fitted: judged RMS") for s in steps)
    monkeypatch.setenv("PIHYST_PROGRESS", "0")
    assert main(["fit", str(data), "--no-creep", "-o", str(tmp_path / "b.json")]) == 0
    assert "pihyst fit: " not in capsys.readouterr().err
