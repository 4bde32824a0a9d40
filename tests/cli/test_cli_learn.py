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


def test_learn_a_desired_period_from_a_file_with_a_model(tmp_path, capsys):
    """A period given with its times is resampled at the clock; a model file starts it."""
    desired, model, out = (tmp_path / n for n in ("period.csv", "model.json", "run.csv"))
    t = np.arange(50) * 2e-4                               # 100 Hz, 50 points
    y = 22 - 15 * np.cos(2 * np.pi * 100 * t)
    desired.write_text("time_s,displacement_um\n"
                       + "".join(f"{a:.6g},{b:.6f}\n" for a, b in zip(t, y)))
    model.write_text('{"family": "classical", "thresholds": [0, 10, 30], '
                     '"weights": [0.22, 0.06, 0.03]}')
    assert main(["learn", "--model", str(model), "--desired", str(desired), "--trials", "3",
                 "-o", str(out)]) == 0
    data, _ = read_columns(out, ["trial", "time_s", "desired_um"])
    first = data["trial"] == 0
    assert first.sum() == 200                              # 10 ms at 20 kHz
    np.testing.assert_allclose(data["desired_um"][first][::4], y, atol=1e-6)
    assert "trial   3" in capsys.readouterr().out


def test_a_period_too_short_is_one_line(tmp_path, capsys):
    desired = tmp_path / "period.csv"
    desired.write_text("displacement_um\n1\n2\n")
    assert main(["learn", "--desired", str(desired), "-o", str(tmp_path / "o.csv")]) == 2
    assert "2 samples in the period; need 4" in error_line(capsys)


def hammerstein_file(path, hz=2000.0, damping=0.05, clock=20_000.0):
    """A Hammerstein model file: a classical PI model, then one mode (its discrete poles,
    unit static gain)."""
    from pihyst.dynamics import HammersteinModel
    from pihyst.model import ClassicalPI
    pole = np.exp((-damping + 1j * np.sqrt(1 - damping ** 2)) * 2 * np.pi * hz / clock)
    a = np.poly([pole, np.conj(pole)]).real
    model = HammersteinModel(hysteresis=(ClassicalPI([0, 10, 30], [0.22, 0.06, 0.03],
                                                     input_range=(0.0, 150.0)),),
                             a=(a,), b=(np.array([[0.0, a.sum()]]),))
    model.save(path)


def test_learn_starts_from_a_hammerstein_model_file(tmp_path, capsys):
    model, out = tmp_path / "ham.json", tmp_path / "run.csv"
    hammerstein_file(model)
    assert main(["learn", "--model", str(model), "--scan", "200", "--mode", "2000,0.05",
                 "--trials", "2", "-o", str(out)]) == 0
    data, _ = read_columns(out, ["trial", "voltage_V"])
    assert set(data["trial"]) == {0, 1, 2}
    assert np.all((data["voltage_V"] >= 0) & (data["voltage_V"] <= 150))


def test_a_broken_hammerstein_file_is_one_line_and_status_2(tmp_path, capsys):
    model, out = tmp_path / "ham.json", tmp_path / "run.csv"
    hammerstein_file(model)
    import json
    d = json.loads(model.read_text())
    d["a"][0][0] = 2.0
    model.write_text(json.dumps(d))
    assert main(["learn", "--model", str(model), "--scan", "200", "--mode", "2000,0.05",
                 "-o", str(out)]) == 2
    assert "a[0] must start with 1" in error_line(capsys)
    assert not out.exists()
