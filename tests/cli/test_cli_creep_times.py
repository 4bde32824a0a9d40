"""A model with creep on the command line: predict, validate, compensate and track run
its lags at the record's sample times (a time column at another interval than the
model's ``creep.dt``, irregular), block by block with the lag state and the last time
carried across blocks; without a time column, every ``creep.dt``; a time that runs
backwards is a one-line error at its line, exit status 2, no output file."""

import numpy as np
import pytest

import pihyst
from pihyst.cli import main
from pihyst.io import _records, read_columns, write_columns
from pihyst.model import BoucWenModel, Creep

CREEP = Creep([0.05, 0.5, 5.0], [0.03, 0.04, 0.05], dt=0.01)
MODELS = {
    "classical": pihyst.ClassicalPI([0, 20, 45], [0.3, 0.2, 0.1], creep=CREEP),
    "bouc-wen": BoucWenModel(beta=5.0, gamma=1.0, hysteretic=20.0, linear=40.0,
                             input_range=(0.0, 150.0), creep=CREEP),
}


def _times(n):
    # 4 ms steps, one longer pause: nothing like the model's 10 ms
    dt = np.full(n, 0.004)
    dt[n // 3] = 0.7
    return np.cumsum(dt)


def _levels(n, lo, hi):
    k = np.arange(n)
    return lo + (hi - lo) * (0.5 + 0.45 * np.sin(2 * np.pi * k / 97) * np.cos(k / 211))


@pytest.fixture(params=sorted(MODELS))
def model_file(request, tmp_path):
    path = tmp_path / "m.json"
    MODELS[request.param].save(path)
    return MODELS[request.param], path


def test_predict_and_validate_use_the_time_column_across_blocks(tmp_path, monkeypatch,
                                                                model_file):
    model, path = model_file
    n = 600
    t, u = _times(n), _levels(n, 0.0, 150.0)
    y = model.predict(u, t=t)
    assert np.max(np.abs(y - model.predict(u))) > 1e-3     # the times matter
    data = tmp_path / "u.csv"
    write_columns(data, {"time_s": t, "voltage_V": u, "displacement_um": y})
    monkeypatch.setattr(_records, "BLOCK_ROWS", 37)
    out = tmp_path / "p.csv"
    assert main(["predict", str(path), str(data), "-o", str(out)]) == 0
    cols, _ = read_columns(out, ["displacement_um"])
    np.testing.assert_allclose(cols["displacement_um"], y, rtol=0, atol=1e-9)
    assert main(["validate", str(path), str(data), "--json"]) == 0
    # without a time column: every creep.dt
    write_columns(data, {"voltage_V": u})
    assert main(["predict", str(path), str(data), "-o", str(out)]) == 0
    cols, _ = read_columns(out, ["displacement_um"])
    np.testing.assert_allclose(cols["displacement_um"], model.predict(u), rtol=0, atol=1e-9)


def test_validate_judges_at_the_sample_times(tmp_path, capsys, model_file):
    import json

    model, path = model_file
    n = 600
    t, u = _times(n), _levels(n, 0.0, 150.0)
    data = tmp_path / "r.csv"
    write_columns(data, {"time_s": t, "voltage_V": u, "displacement_um": model.predict(u, t=t)})
    assert main(["validate", str(path), str(data), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["errors"]["rms_um"] < 1e-9


def test_compensate_and_track_use_the_time_column(tmp_path, monkeypatch, model_file):
    model, path = model_file
    n = 600
    t = _times(n)
    lo, hi = model.predict(np.array([0.0, 150.0]))
    yd = _levels(n, lo + 0.2 * (hi - lo), lo + 0.8 * (hi - lo))
    ref = pihyst.compensate(model, yd, t=t)
    data = tmp_path / "d.csv"
    write_columns(data, {"time_s": t, "displacement_um": yd})
    monkeypatch.setattr(_records, "BLOCK_ROWS", 37)
    out = tmp_path / "v.csv"
    assert main(["compensate", str(path), str(data), "-o", str(out)]) == 0
    cols, _ = read_columns(out, ["voltage_V"])
    np.testing.assert_allclose(cols["voltage_V"], ref.voltage, rtol=0, atol=1e-9)
    assert main(["track", str(path), str(data), "-o", str(out), "--no-noise"]) == 0
    cols, _ = read_columns(out, ["voltage_V"])
    np.testing.assert_allclose(cols["voltage_V"], ref.voltage, rtol=0, atol=1e-9)


@pytest.mark.parametrize("command", ["predict", "compensate", "validate"])
def test_time_running_backwards_is_a_one_line_error(tmp_path, capsys, model_file, command):
    _, path = model_file
    n = 200
    t = _times(n)
    t[150] = t[149] - 0.001
    u = _levels(n, 0.0, 150.0)
    data = tmp_path / "bad.csv"
    write_columns(data, {"time_s": t, "voltage_V": u, "displacement_um": u * 0.1})
    out = tmp_path / "o.csv"
    argv = [command, str(path), str(data)] + ([] if command == "validate" else ["-o", str(out)])
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "bad.csv:" in err and "runs backwards" in err, err
    assert not out.exists()


def test_a_warning_about_the_record_is_said_once(tmp_path, capsys):
    # with a time column the record is fitted with and without its creep estimate; a
    # record without hysteresis made both fits warn, and the command said it twice
    t = np.arange(4000) * 0.01
    u = 75 + 75 * np.sin(2 * np.pi * t / 10)
    y = 0.3 * u + np.random.default_rng(0).normal(0, 0.01, u.size)
    data = tmp_path / "straight.csv"
    write_columns(data, {"time_s": t, "voltage_V": u, "displacement_um": y})
    assert main(["fit", str(data), "--model", "classical", "-o",
                 str(tmp_path / "m.json")]) == 0
    warnings = [line for line in capsys.readouterr().err.splitlines()
                if "shows no hysteresis" in line]
    assert len(warnings) == 1, warnings
