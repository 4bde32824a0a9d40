"""pihyst rig learn on the emulated rig: trials through the controller, every one ending
at 0 V with the output off, also when a fault stops one."""

import numpy as np
import pytest
from rig_helpers import config_text

from pihyst.cli import main
from pihyst.io import read_columns


@pytest.fixture
def setup(tmp_path):
    cfg = tmp_path / "rig.toml"
    cfg.write_text(config_text())
    model = tmp_path / "model.json"
    model.write_text('{"family": "classical", "thresholds": [0, 10, 30], '
                     '"weights": [0.22, 0.06, 0.03]}')
    desired = tmp_path / "desired.csv"
    t = np.arange(40) / 20.0                                   # a 2 s period at 20 Hz
    y = 20 - 12 * np.cos(2 * np.pi * t / 2.0)
    desired.write_text("time_s,displacement_um\n"
                       + "".join(f"{a:g},{b:.6f}\n" for a, b in zip(t, y)))
    return cfg, model, desired


def test_rig_learn_runs_trials_that_each_end_at_zero(tmp_path, capsys, setup):
    cfg, model, desired = setup
    out = tmp_path / "run.csv"
    assert main(["rig", "learn", str(model), str(desired), "--config", str(cfg),
                 "--trials", "3", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "4 trials at 20 Hz" in text and "every trial ended at 0 V, output off" in text
    data, _ = read_columns(out, ["trial", "rms_um", "voltage_V"])
    assert data["trial"].size == 4 * 40
    for j in range(4):
        # the log's stop line is in its sidecar (docs/records.md: plain CSV out)
        log = (tmp_path / f"run.trial-{j:02d}.csv.json").read_text()
        assert "0 V sent and output off" in log
    rms = [data["rms_um"][data["trial"] == j][0] for j in range(4)]
    assert min(rms) < rms[0]


def test_a_fault_in_a_trial_stops_the_learning_at_zero(tmp_path, capsys, setup):
    cfg, model, desired = setup
    out = tmp_path / "run.csv"
    with pytest.raises(SystemExit) as info:
        main(["rig", "learn", str(model), str(desired), "--config", str(cfg), "--trials", "3",
              "--fault", "sensor:over-range:1", "-o", str(out)])
    assert info.value.code == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "learning trial 0 stopped: 5 consecutive invalid sensor" in err[0]
    assert "0 V, output off" in err[0]
    assert "0 V sent and output off" in (tmp_path / "run.trial-00.csv.json").read_text()
    assert not out.exists()
