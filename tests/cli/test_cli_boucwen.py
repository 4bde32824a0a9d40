"""The command line with a Bouc-Wen model wherever a PI model's compensator runs:
compensate (predict -> compensate gives the voltages back, limits, slew, initial states),
track (the simulated beam driven by the Bouc-Wen inverse), and the rig's track."""

import sys
from pathlib import Path

import numpy as np

from pihyst.cli import main
from pihyst.io import read_columns, write_columns
from pihyst.model import BoucWenModel

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "rig"))
from rig_helpers import config_text  # noqa: E402

MODEL = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0, offset=0.3)


def _model(tmp_path):
    path = tmp_path / "bw.json"
    MODEL.save(path)
    return path


def test_predict_then_compensate_gives_the_voltages_back(tmp_path, capsys):
    model = _model(tmp_path)
    predicted = tmp_path / "pred.csv"
    assert main(["predict", str(model), "examples/triangle_0_150V.csv", "-o",
                 str(predicted)]) == 0
    out = tmp_path / "comp.csv"
    assert main(["compensate", str(model), str(predicted), "-o", str(out)]) == 0
    cols, _ = read_columns(out, ["voltage_V", "displacement_um", "saturated"])
    given, _ = read_columns(predicted, ["voltage_V", "displacement_um"])
    # the triangle starts at 0 V, where the model's output is flat-free: voltages come back
    np.testing.assert_allclose(cols["voltage_V"], given["voltage_V"], atol=1e-9)
    np.testing.assert_allclose(cols["displacement_um"], given["displacement_um"], atol=1e-9)
    assert not cols["saturated"].any()
    assert "saturated: 0 of 301 samples" in capsys.readouterr().out


def test_compensate_limits_slew_and_initial_states(tmp_path, capsys):
    model = _model(tmp_path)
    src = tmp_path / "d.csv"
    t = np.arange(60) * 0.5
    y = 20 + 25 * np.sin(t)
    write_columns(src, {"time_s": t, "displacement_um": y})
    for mode in ("model", "zero", "bottom", "top"):
        out = tmp_path / f"out-{mode}.csv"
        assert main(["compensate", str(model), str(src), "-o", str(out), "--u-min", "5",
                     "--u-max", "120", "--slew-rate", "40", "--initial-state", mode,
                     "--saturate"]) == 0
        cols, _ = read_columns(out, ["voltage_V", "saturated", "slew_limited"])
        u = cols["voltage_V"]
        assert np.all((u >= 5) & (u <= 120))
        assert np.all(np.abs(np.diff(u)) <= 20.0)  # 40 V/s x 0.5 s
        assert cols["saturated"].any() and cols["slew_limited"].any()
    assert "at or toward 120 V" in capsys.readouterr().out


def test_compensate_refuses_a_non_monotone_model(tmp_path, capsys):
    path = tmp_path / "bad.json"
    MODEL.replace(linear=10.0).save(path)
    src = tmp_path / "d.csv"
    src.write_text("time_s,displacement_um\n0,1\n1,2\n")
    out = tmp_path / "out.csv"
    assert main(["compensate", str(path), str(src), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "monotone" in err[0]
    assert not out.exists()


def test_track_drives_the_beam_through_the_bouc_wen_inverse(tmp_path, capsys):
    model = _model(tmp_path)
    t = np.arange(200) * 0.05
    y = 20 + 10 * np.sin(2 * np.pi * t / 5)
    src = tmp_path / "desired.csv"
    write_columns(src, {"time_s": t, "displacement_um": y})
    out = tmp_path / "tracked.csv"
    assert main(["track", str(model), str(src), "--plant", "lens", "--seed", "3", "-o",
                 str(out)]) == 0
    cols, _ = read_columns(out, ["predicted_um", "voltage_V"])
    np.testing.assert_allclose(cols["predicted_um"], y, atol=1e-9)  # the model is inverted
    assert "tracking error" in capsys.readouterr().out


def test_rig_track_with_a_bouc_wen_model(tmp_path, capsys):
    cfg = tmp_path / "rig.toml"
    cfg.write_text(config_text())
    model = _model(tmp_path)
    desired = tmp_path / "desired.csv"
    desired.write_text("time_s,displacement_um\n0,2\n5,30\n10,2\n")
    run = tmp_path / "run.csv"
    assert main(["rig", "track", str(model), str(desired), "--config", str(cfg),
                 "-o", str(run)]) == 0
    assert "tracking error open loop" in capsys.readouterr().out
    assert "through the inverse of a bouc-wen model" in (tmp_path / "run.csv.json").read_text()
    assert main(["rig", "track", str(model), str(desired), "--config", str(cfg),
                 "--feedback", "0.3,2", "-o", str(tmp_path / "fb.csv")]) == 0
    assert "tracking error with feedback" in capsys.readouterr().out


def test_predict_runs_the_model_itself(tmp_path):
    """A Bouc-Wen model's input range is its normalization: predict clamps voltages within
    the tolerance instead of running a model with a wider range (another model)."""
    model = _model(tmp_path)
    out = tmp_path / "pred.csv"
    assert main(["predict", str(model), "examples/triangle_0_150V.csv", "-o", str(out)]) == 0
    cols, _ = read_columns(out, ["voltage_V", "displacement_um"])
    np.testing.assert_allclose(cols["displacement_um"], MODEL.predict(cols["voltage_V"]),
                               rtol=0, atol=1e-12)
