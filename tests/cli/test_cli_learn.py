"""pihyst learn: a short learning run on a simulated stage; bad input is one line, exit
status 2, no output file."""

import numpy as np
import pytest

from pihyst.cli import main
from pihyst.io import read_columns


def error_line(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_learn_on_a_stage_writes_every_trial(tmp_path, capsys):
    out = tmp_path / "run.csv"
    assert main(["learn", "--scan", "200", "--mode", "2000,0.05", "--trials", "4",
                 "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "trial   4 learn" in text and "best: trial" in text
    data, _ = read_columns(out, ["trial", "rms_um", "voltage_V"])
    assert set(data["trial"]) == {0, 1, 2, 3, 4} and data["trial"].size == 5 * 100
    assert np.all((data["voltage_V"] >= 0) & (data["voltage_V"] <= 150))
    rms = [data["rms_um"][data["trial"] == j][0] for j in range(5)]
    assert min(rms) < 0.5 * rms[0]           # from no model at all


@pytest.mark.parametrize("options, expected", [
    (["--scan", "500"], "--scan 500: the scan rate must be below half the first mode (400 Hz)"),
    (["--scan", "100", "--mode", "800,1.5"], "argument --mode: need HZ > 0 and 0 < DAMPING"),
    (["--scan", "100", "--mode", "12000"], "--mode: every mode must be below half the --clock"),
    (["--scan", "100", "--u-min", "100", "--u-max", "50"], "--u-min 100 and --u-max 50 must"),
    (["--scan", "100", "--noise", "-1"], "argument --noise: must be a number >= 0"),
    (["--scan", "100", "--trials", "0"], "argument --trials"),
    (["--desired", "missing.csv"], "missing.csv"),
])
def test_bad_input_is_one_line_and_status_2(tmp_path, capsys, monkeypatch, options, expected):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "run.csv"
    assert main(["learn", *options, "-o", str(out)]) == 2
    assert expected in error_line(capsys)
    assert not out.exists()
