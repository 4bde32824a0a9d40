"""pihyst fit --validate OTHER.csv, --delay, --max-operators, --max-latency: the report
judges every family on the other record too; bounds narrow the choice; bad options and
bad validation files are one-line errors with exit status 2 and no output file."""

import json

import numpy as np
import pytest

import pihyst
from pihyst.cli import main
from pihyst.io import write_columns

MODEL = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])


def ramps(levels, n=30):
    levels = np.asarray(levels, dtype=float)
    return np.concatenate([np.linspace(a, b, n, endpoint=False) for a, b in
                           zip(levels[:-1], levels[1:])] + [levels[-1:]])


def write(tmp_path, name, levels, seed=0, zero=0.0):
    u = ramps(levels)
    y = MODEL.predict(u) + zero + np.random.default_rng(seed).normal(0, 0.01, u.size)
    path = tmp_path / name
    write_columns(path, {"voltage_V": u, "displacement_um": y})
    return path


@pytest.fixture
def data(tmp_path):
    return write(tmp_path, "data.csv", [0, 150, 0, 120, 30, 150, 0, 90, 10, 150, 0, 70, 0,
                                        150, 0])


def test_validate_record_is_judged_and_reported(tmp_path, data, capsys):
    other = write(tmp_path, "other.csv", [0, 150, 0, 100, 50, 130, 20, 150, 0], seed=1,
                  zero=3.0)
    out = tmp_path / "m.json"
    assert main(["fit", str(data), "--validate", str(other), "--max-operators", "6",
                 "-o", str(out)]) == 0
    model = pihyst.load_model(out)
    assert model.n_operators <= 6
    fitted = model.metadata["fit"]
    validation = fitted["data"]["validation"]              # the other file, judged
    assert validation["samples"] == ramps([0, 150, 0, 100, 50, 130, 20, 150, 0]).size
    assert set(fitted["held_back_by_kind"]) >= {"validation record"}
    assert fitted["final"]["errors"]["validation"]["rms"] > 0


def test_delay_option(tmp_path, data, capsys):
    out = tmp_path / "m.json"
    assert main(["fit", str(data), "--model", "classical", "--delay", "2", "--json",
                 "-o", str(out)]) == 0
    rep = json.loads(capsys.readouterr().out)
    assert rep["data"]["delay"]["samples"] == 2


def _fails(capsys, argv, out):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("pihyst: error: ")
    assert not out.exists()
    return err


def test_bad_options_and_validation_files(tmp_path, data, capsys):
    out = tmp_path / "m.json"
    assert "--delay" in _fails(capsys, ["fit", str(data), "--delay", "x", "-o", str(out)],
                               out)
    assert "--max-operators" in _fails(capsys, ["fit", str(data), "--max-operators", "0",
                                                "-o", str(out)], out)
    assert "--max-latency" in _fails(capsys, ["fit", str(data), "--max-latency", "-3",
                                              "-o", str(out)], out)
    # --max-latency in seconds, as pihyst.fit's max_latency (the report shows us)
    err = _fails(capsys, ["fit", str(data), "--model", "classical", "--max-latency",
                          "1e-12", "-o", str(out)], out)
    assert "more than max_latency = 1e-06 µs" in err
    err = _fails(capsys, ["fit", str(data), "--model", "kp", "--max-operators", "3", "-o",
                          str(out)], out)
    assert "no fitted family meets the bounds" in err
    outside = tmp_path / "outside.csv"
    outside.write_text("voltage_V,displacement_um\n0,0\n100,1\n200,2\n0,0\n")
    err = _fails(capsys, ["fit", str(data), "--validate", str(outside), "-o", str(out)],
                 out)
    assert f"{outside}:4:1:" in err and "outside the model's input range" in err
    missing = tmp_path / "missing.csv"
    assert "cannot read" in _fails(capsys, ["fit", str(data), "--validate", str(missing),
                                            "-o", str(out)], out)
