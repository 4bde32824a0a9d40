"""pihyst rig: one-line errors with exit status 2 and no output file; the newcomer's
three commands."""

import pytest
from rig_helpers import config_text

from pihyst.cli import main


@pytest.fixture
def cfg(tmp_path):
    path = tmp_path / "rig.toml"
    path.write_text(config_text())
    return path


def error_line(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


@pytest.mark.parametrize("text, expected", [
    ("[rig]\nrate_hz = \n", "rig.toml: Invalid value (at line 2, column 11)"),
    ("[rig]\nrate = 20.0\n", "rig.toml:2: [rig] rate: unknown key"),
    ("[supply]\nprotocol = 'can-bus'\n", "rig.toml:2: [supply] protocol: 'can-bus' is not one"),
    ("[supply]\nscale = -1\n", "rig.toml:2: [supply] scale: must be a positive number"),
    ("[rig]\nu_max = 'high'\n", "rig.toml:2: [rig] u_max: must be a number"),
    ("[sensor]\nsign = 2\n", "rig.toml:2: [sensor] sign: must be 1 or -1"),
    ("[supply]\nset_command = 'VOLT {v}'\n", "rig.toml:2: [supply] set_command: bad template"),
    ("[pump]\n", "rig.toml: [pump]: unknown section"),
    # limits the supply cannot take: refused before anything is sent, not mid-run
    ("[rig]\nu_min = -150.0\n", "rig.toml:2: [rig] u_min: must be 0, got -150: pihyst "
                                 "drives unipolar supplies"),
    ("[rig]\nu_max = 1000.0\n[supply]\nsetpoint_format = 'uint16'\nscale = 100.0\n",
     "rig.toml:2: [rig] u_max: 1000 V is 100000 register units at [supply] scale 100: more "
     "than a uint16 setpoint holds (65535)"),
    ("[rig]\nu_max = 150.0\n[supply]\nsetpoint_format = 'uint32'\nscale = 1e8\n",
     "rig.toml:2: [rig] u_max: 150 V is 1.5e+10 register units"),
    ("[supply]\naddress = 0\n", "rig.toml:2: [supply] address: must be a Modbus slave "
                                 "address 1..247, got 0"),
])
def test_bad_configuration(tmp_path, capsys, text, expected):
    path = tmp_path / "rig.toml"
    path.write_text(text)
    out = tmp_path / "loop.csv"
    assert main(["rig", "record", "--config", str(path), "-o", str(out)]) == 2
    line = error_line(capsys)
    assert line.startswith("pihyst: error: ") and expected in line, line
    assert not out.exists()


def test_bad_options_and_ports(tmp_path, capsys, cfg):
    out = tmp_path / "run.csv"
    assert main(["rig", "record", "--config", str(cfg), "--max", "500", "-o", str(out)]) == 2
    assert "--min/--max" in error_line(capsys)
    assert main(["rig", "record", "--config", str(cfg), "--fault", "pump:stuck",
                 "-o", str(out)]) == 2
    assert "--fault pump:stuck" in error_line(capsys)
    real = tmp_path / "real.toml"
    real.write_text(config_text(supply={"port": str(tmp_path / "ttyNONE")}))
    assert main(["rig", "check", "--config", str(real)]) == 2
    assert "supply: cannot open port" in error_line(capsys)
    desired = tmp_path / "desired.csv"
    desired.write_text("time_s,displacement_um\n0,0\n1,oops\n")
    model = tmp_path / "m.json"
    model.write_text('{"family": "classical", "thresholds": [0, 10], "weights": [0.1, 0.2]}')
    assert main(["rig", "track", str(model), str(desired), "--config", str(cfg),
                 "-o", str(out)]) == 2
    assert "desired.csv:3:2" in error_line(capsys)
    assert not out.exists()


@pytest.mark.parametrize("command, column", [("record", "voltage_V"),
                                             ("track", "displacement_um")])
def test_a_file_spanning_too_long_a_time_is_refused(tmp_path, capsys, cfg, command, column):
    # two rows, 1e9 s apart: 2e10 ticks at 20 Hz, refused before any array is made
    data = tmp_path / "data.csv"
    data.write_text(f"time_s,{column}\n0,0\n1e9,10\n")
    model = tmp_path / "m.json"
    model.write_text('{"family": "classical", "thresholds": [0, 10], "weights": [0.1, 0.2]}')
    out = tmp_path / "run.csv"
    args = (["record", "--voltages", str(data)] if command == "record" else
            ["track", str(model), str(data)])
    assert main(["rig", *args, "--config", str(cfg), "-o", str(out)]) == 2
    assert f"{data}: time_s spans 1e+09 s, 20,000,000,001 ticks at 20 Hz: more than the " \
           "2,000,000 ticks of a run" in error_line(capsys)
    assert not out.exists()


def test_track_says_which_ticks_the_model_cannot_reach(tmp_path, capsys):
    # a model reaching 2 .. 28 um within the rig's 0 .. 100 V, asked for 0 .. 40 um: the
    # ticks outside saturate; the command says so before the run (and in the log), not
    # only as tracking errors
    cfg = tmp_path / "rig.toml"
    cfg.write_text(config_text(rig={"u_max": 100.0}))
    model = tmp_path / "m.json"
    model.write_text('{"family": "classical", "thresholds": [0, 10], "weights": [0.1, 0.2]}')
    desired = tmp_path / "desired.csv"
    out = tmp_path / "run.csv"
    desired.write_text("time_s,displacement_um\n0,0\n2,40\n4,0\n")
    # 31 % of the ticks out of reach: refused before the supply is touched ...
    assert main(["rig", "track", str(model), str(desired), "--config", str(cfg),
                 "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "25 of 81 samples (30.9 %) of the desired displacement are out of the model's " \
           "reach, more than 10 %" in err and "--saturate" in err and not out.exists()
    # ... unless --saturate says that is intended
    assert main(["rig", "track", str(model), str(desired), "--config", str(cfg),
                 "-o", str(out), "--saturate"]) == 0
    text = capsys.readouterr().out
    assert "frame: absolute" in text
    # the first 0 um is reached (from the initial state), the last two are not (2 um is
    # left at 0 V after the way up), nor the 23 above 28 um
    assert "note: 25 of 81 ticks of the desired displacement (span [0, 40] µm) are out of " \
           "the model's reach with the voltage in [0, 100] V (at most [2, 28] µm): their " \
           "voltage saturates" in text, text
    assert "note: 25 of 81 ticks" in _log_notes(out)
    desired.write_text("time_s,displacement_um\n0,5\n2,20\n4,5\n")
    assert main(["rig", "track", str(model), str(desired), "--config", str(cfg),
                 "-o", str(out)]) == 0
    assert "note:" not in capsys.readouterr().out
    # below the 2 um left at 0 V after a full sweep, yet in reach after a small one: no
    # note (the reach depends on the way there)
    desired.write_text("time_s,displacement_um\n0,0\n2,1\n4,0\n")
    assert main(["rig", "track", str(model), str(desired), "--config", str(cfg),
                 "-o", str(out)]) == 0
    assert "note:" not in capsys.readouterr().out


def test_track_runs_a_models_creep_at_the_tick_period(tmp_path, capsys, cfg):
    # a model fitted on a 200 Hz record (creep.dt 5 ms) on the 20 Hz rig: its creep lags
    # must move 50 ms per tick, not 5 ms (the held 20 um then needed 7 V too much)
    import numpy as np

    import pihyst
    from pihyst.model import Creep
    model = pihyst.ClassicalPI([0, 10, 30, 60], [0.2, 0.05, 0.03, 0.01],
                               creep=Creep([1.0, 10.0], [0.1, 0.1], dt=0.005))
    path, desired, out = tmp_path / "m.json", tmp_path / "hold.csv", tmp_path / "run.csv"
    model.save(path)
    desired.write_text("time_s,displacement_um\n0,0\n1,20\n20,20\n")
    assert main(["rig", "track", str(path), str(desired), "--config", str(cfg),
                 "-o", str(out)]) == 0
    text_rows = [line.split(",") for line in out.read_text().splitlines()
                 if ",run," in line and not line.startswith("#")]
    assert text_rows
    sent = np.array([float(r[4]) for r in text_rows])        # command_V
    ref = np.array([float(r[3]) for r in text_rows])
    expected = pihyst.compensate(model, ref, t=0.05 * np.arange(ref.size), u_min=0.0,
                                 u_max=150.0, slew_rate=10.0, sample_period=1.0,
                                 initial_voltage=sent[0])
    np.testing.assert_allclose(sent, expected.voltage, rtol=0, atol=1e-6)


@pytest.mark.parametrize("options, expected", [
    # checked as the option is parsed (it named the API's period_s before)
    (["--period", "0"], "argument --period: must be a positive number, got '0'"),
    (["--cycles", "0"], "argument --cycles: must be at least 1, got 0"),
    (["--max", "nan"], "argument --max: must be a finite number, got 'nan'"),
    (["--signal", "decaying-triangles", "--period", "0.01"],
     "--signal decaying-triangles --period 0.01 at 20 Hz ({cfg} [rig] rate_hz): dt = 0.05 s "
     "is more than half the period"),
])
def test_a_bad_signal_names_the_rigs_options(tmp_path, capsys, cfg, options, expected):
    # not pihyst simulate's: rig record has no --dt (the tick period is the rig's)
    out = tmp_path / "loop.csv"
    assert main(["rig", "record", "--config", str(cfg), *options, "-o", str(out)]) == 2
    line = error_line(capsys)
    assert expected.format(cfg=cfg) in line and "--dt" not in line, line
    assert not out.exists()


def test_record_fit_track(tmp_path, capsys, cfg):
    loop, model, run = (tmp_path / n for n in ("loop.csv", "model.json", "run.csv"))
    assert main(["rig", "record", "--config", str(cfg), "--period", "30",
                 "-o", str(loop)]) == 0
    assert "stopped: end of the program; 0 V, output off" in capsys.readouterr().out
    assert main(["fit", str(loop), "--model", "multislope", "--thresholds", "0,20,30,40",
                 "-o", str(model)]) == 0
    desired = tmp_path / "desired.csv"
    desired.write_text("time_s,displacement_um\n0,0\n15,35\n30,0\n")
    capsys.readouterr()
    assert main(["rig", "track", str(model), str(desired), "--config", str(cfg),
                 "--feedback", "0.3,2", "-o", str(run)]) == 0
    out = capsys.readouterr().out
    assert "tracking error with feedback" in out and "% of the range 35 µm" in out
    assert main(["rig", "check", "--config", str(cfg)]) == 0
    assert "0 V sent, output off, readback 0.000 V" in capsys.readouterr().out


@pytest.mark.parametrize("start", ["nan", "inf", "-inf"])
def test_a_fault_starts_at_a_finite_time(tmp_path, capsys, cfg, start):
    # a NaN start acted from 0 s (t < nan is false)
    out = tmp_path / "x.csv"
    assert main(["rig", "record", "--config", str(cfg), "--fault",
                 f"sensor:over-range:{start}", "-o", str(out)]) == 2
    assert f"--fault sensor:over-range:{start}: the start must be a finite time in " \
           "seconds" in error_line(capsys)
    assert not out.exists()


def test_a_fault_stops_the_run_with_status_1(tmp_path, capsys, cfg):
    out = tmp_path / "loop.csv"
    with pytest.raises(SystemExit) as info:
        main(["rig", "record", "--config", str(cfg), "--period", "20",
              "--fault", "sensor:over-range:3", "-o", str(out)])
    assert info.value.code == 1
    assert "the run stopped early: 5 consecutive invalid sensor readings" in \
        error_line(capsys)
    assert "stopped: 5 consecutive invalid sensor readings" in _log_notes(out)


def test_a_supply_left_charged_after_the_program_is_status_1(tmp_path, capsys, cfg):
    # the program runs to its end, then the supply stops answering: 0 V cannot be sent
    volts = tmp_path / "volts.csv"
    volts.write_text("time_s,voltage_V\n0,0\n2,40\n")
    out = tmp_path / "loop.csv"
    with pytest.raises(SystemExit) as info:
        main(["rig", "record", "--config", str(cfg), "--voltages", str(volts),
              "--fault", "supply:no-reply:2.2", "-o", str(out)])
    assert info.value.code == 1
    assert "the supply could not be zeroed at the end" in error_line(capsys)
    assert "WARNING: could not send 0 V" in _log_notes(out)


def test_a_full_disk_stops_the_run_with_status_1(tmp_path, capsys, cfg, monkeypatch):
    import errno

    from pihyst.rig import _session
    from pihyst.rig._log import CsvRunLog

    class FullDisk(CsvRunLog):
        budget = 100

        def _flush(self):
            FullDisk.budget -= 1
            if FullDisk.budget < 0:
                raise OSError(errno.ENOSPC, "No space left on device")
            super()._flush()
    monkeypatch.setattr(_session, "CsvRunLog", FullDisk)
    with pytest.raises(SystemExit) as info:
        main(["rig", "record", "--config", str(cfg), "--period", "20",
              "-o", str(tmp_path / "loop.csv")])
    assert info.value.code == 1
    assert "the run stopped early: the log could not be written (OSError: [Errno 28] No " \
           "space left on device)" in error_line(capsys)


def test_record_a_csv_of_voltages(tmp_path, capsys, cfg):
    volts = tmp_path / "volts.csv"
    volts.write_text("# a ramp\ntime_s,voltage_V\n0,0\n2,40\n4,0\n")
    out = tmp_path / "loop.csv"
    assert main(["rig", "record", "--config", str(cfg), "--voltages", str(volts),
                 "-o", str(out)]) == 0
    from pihyst.rig import read_run_log
    columns, _ = read_run_log(out)
    run = columns["phase"] == "run"
    assert run.sum() == 81                      # 4 s at 20 Hz, both ends included
    assert columns["voltage_V"][run].max() == pytest.approx(40.0)
    volts.write_text("time_s,voltage_V\n0,0\n1,400\n")
    assert main(["rig", "record", "--config", str(cfg), "--voltages", str(volts),
                 "-o", str(tmp_path / "no.csv")]) == 2
    assert "outside the rig's limits" in error_line(capsys)
    assert not (tmp_path / "no.csv").exists()


def test_track_refuses_a_delay_that_is_no_whole_number_of_ticks(tmp_path, capsys, cfg):
    model = tmp_path / "m.json"
    model.write_text('{"family": "classical", "thresholds": [0, 10], "weights": [0.1, 0.2], '
                     '"delay_samples": 3, "sample_period_s": 0.0123}')
    desired = tmp_path / "desired.csv"
    desired.write_text("time_s,displacement_um\n0,0\n1,5\n2,0\n")
    out = tmp_path / "run.csv"
    assert main(["rig", "track", str(model), str(desired), "--config", str(cfg),
                 "-o", str(out)]) == 2
    line = error_line(capsys)
    assert "delay of 3 samples at 0.0123 s" in line and "not a whole number" in line
    assert line.startswith(f"pihyst: error: {cfg}: the model's delay")   # names the rate's file
    assert not out.exists()


def _log_notes(log):
    """The lines about a run (its metadata, why it stopped), in the sidecar LOG.json."""
    import json
    with open(f"{log}.json", encoding="utf-8") as f:
        side = json.load(f)
    return "\n".join(side["comments"] + side["notes"])


def test_the_log_has_every_tick_and_fit_skips_the_invalid_ones(tmp_path, capsys):
    """Every tick is a row (a default reader sees the failed ones too, with their
    status); pihyst's reader skips those without a valid reading and says how many."""
    import numpy as np

    from pihyst.io import read_record
    from pihyst.rig import CsvRunLog, TickRecord
    path = tmp_path / "run.csv"
    log = CsvRunLog(path, metadata=["pihyst test"])
    for k in range(6):
        bad = k in (2, 3)
        log.write(TickRecord(k, 0.1 * k, "run", 1.0, float(k), float(k), float(k),
                             float("nan") if bad else 0.5 * k,
                             "over-range+" if bad else "ok", "ok", 0, 0.0, 0.001))
    log.note("stopped: end of the program")
    log.close()
    lines = path.read_text().splitlines()
    assert len(lines) == 7 and not any(line.startswith("#") for line in lines)
    assert ",nan,over-range+," in lines[3]
    rec = read_record(path)
    np.testing.assert_array_equal(rec.voltage, [0, 1, 4, 5])
    assert rec.metadata["skipped_ticks"] == 2
    pandas = pytest.importorskip("pandas")
    assert len(pandas.read_csv(path)) == 6
    assert _log_notes(path).endswith("stopped: end of the program")
