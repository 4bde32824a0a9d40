"""The command line with a Bouc-Wen model that carries creep: compensate (its voltages
give the desired values back through the model with creep at the lags' fixed interval),
track on a simulated beam, and the rig's feedforward."""

import os
import sys

import numpy as np

from pihyst.cli import main
from pihyst.io import read_columns, write_columns
from pihyst.model import BoucWenModel, Creep

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "rig"))
from rig_helpers import config_text  # noqa: E402

MODEL = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0, offset=0.3,
                     creep=Creep([0.2, 2.0, 20.0], [0.02, 0.02, 0.03], dt=0.05))


def _desired(tmp_path):
    t = np.arange(400) * 0.05
    y = 15 + 10 * np.sign(np.sin(2 * np.pi * t / 8))       # a staircase with holds
    src = tmp_path / "desired.csv"
    write_columns(src, {"time_s": t, "displacement_um": y})
    model = tmp_path / "bwc.json"
    MODEL.save(model)
    return model, src, y


def test_compensate_meets_the_desired_values_through_the_lags(tmp_path, capsys):
    model, src, y = _desired(tmp_path)
    out = tmp_path / "comp.csv"
    assert main(["compensate", str(model), str(src), "-o", str(out)]) == 0
    cols, _ = read_columns(out, ["voltage_V", "displacement_um", "saturated"])
    np.testing.assert_allclose(cols["displacement_um"], y, atol=1e-9)
    np.testing.assert_allclose(MODEL.predict(cols["voltage_V"]), y, atol=1e-9)
    # in the holds the voltage moves to cancel the creep
    assert np.ptp(cols["voltage_V"][20:80]) > 0.1
    assert "saturated: 0 of 400 samples" in capsys.readouterr().out


def test_track_and_rig_track(tmp_path, capsys):
    model, src, y = _desired(tmp_path)
    out = tmp_path / "tracked.csv"
    assert main(["track", str(model), str(src), "--plant", "remanent", "--seed", "3",
                 "-o", str(out)]) == 0
    cols, _ = read_columns(out, ["predicted_um"])
    np.testing.assert_allclose(cols["predicted_um"], y, atol=1e-9)
    cfg = tmp_path / "rig.toml"
    cfg.write_text(config_text())
    assert main(["rig", "track", str(model), str(src), "--config", str(cfg),
                 "-o", str(tmp_path / "run.csv")]) == 0
    assert "tracking error open loop" in capsys.readouterr().out
