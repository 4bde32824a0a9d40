"""Setpoints a supply may not be sent and bad program arguments are pihyst exceptions
naming what is wrong (never a bare ValueError): the drivers refuse them before sending,
a rig whose limits include one is refused before anything is sent or logged (the command
line: one line, exit status 2, no log), and the programs, faults and log reader say what
was wrong."""

import dataclasses

import numpy as np
import pytest
from rig_helpers import ScriptedPort, config_text, make_config

import pihyst
from pihyst.cli import main
from pihyst.exceptions import CSVError, InvalidArgumentError, RecordError
from pihyst.rig import (
    AsciiSupply,
    Fault,
    FeedbackProgram,
    FeedforwardProgram,
    ModbusRtuSupply,
    Rig,
    VirtualClock,
    VoltageProgram,
    read_run_log,
)
from pihyst.rig._codecs import encode_registers

MODEL = pihyst.ClassicalPI([0, 20], [0.2, 0.1])


@pytest.mark.parametrize("volts, says", [
    (float("nan"), r"refusing to send a non-finite setpoint \(nan\)"),
    (-1e-3, r"refusing to send a negative setpoint \(-0.001 V\) to a unipolar supply"),
    ("12 V", "refusing to send '12 V', which is not a number of volts"),
])
@pytest.mark.parametrize("kind", ["modbus", "ascii"])
def test_a_driver_refuses_a_setpoint_before_sending(kind, volts, says):
    port = ScriptedPort([])          # nothing may be written
    if kind == "modbus":
        supply = ModbusRtuSupply(port, make_config().supply, VirtualClock())
    else:
        supply = AsciiSupply(port, make_config(supply={"protocol": "ascii"}).supply)
    with pytest.raises(InvalidArgumentError, match="supply setpoint: " + says):
        supply.set_voltage(volts)


def test_a_setpoint_beyond_the_register_is_refused_before_sending():
    cfg = make_config(supply={"setpoint_format": "uint16", "scale": 1000.0},
                      rig={"u_max": 65.0}).supply
    supply = ModbusRtuSupply(ScriptedPort([]), cfg, VirtualClock())
    with pytest.raises(InvalidArgumentError, match=r"70 V is 70000 register units at \[supply\] "
                       r"scale 1000: more than a uint16 setpoint register holds \(65535\)"):
        supply.set_voltage(70.0)
    assert supply.check_setpoint(65.0) == 65000.0


BAD_LIMITS = [
    ({"rig": {"u_min": -10.0}}, "supply setpoint: refusing to send a negative setpoint "
                                "(-10 V) to a unipolar supply", "[rig] limits -10 .. 150 V"),
    ({"supply": {"setpoint_format": "uint16", "scale": 1000.0}},
     "supply setpoint: 150 V is 150000 register units at [supply] scale 1000: more than a "
     "uint16 setpoint register holds (65535)", "[rig] limits 0 .. 150 V"),
]
# the same limits in a configuration file (refused when it is read, rig/_config.py)
BAD_CONFIG = [
    ({"rig": {"u_min": -10.0}}, ":3: [rig] u_min: must be 0, got -10: pihyst drives "
                                "unipolar supplies (0 V to u_max)"),
    ({"supply": {"setpoint_format": "uint16", "scale": 1000.0}},
     ":4: [rig] u_max: 150 V is 150000 register units at [supply] scale 1000: more than a "
     "uint16 setpoint holds (65535)"),
]


@pytest.mark.parametrize("sections, says, where", BAD_LIMITS)
def test_a_rig_whose_limits_the_supply_refuses_runs_nothing(tmp_path, sections, says, where):
    # limits set past the configuration file's checks (settings built in Python): the run
    # refuses them before anything is sent or logged
    config = make_config()
    config = dataclasses.replace(
        config, rig=dataclasses.replace(config.rig, **sections.get("rig", {})),
        supply=dataclasses.replace(config.supply, **sections.get("supply", {})))
    log = tmp_path / "run.csv"
    with Rig(config) as rig:
        with pytest.raises(InvalidArgumentError) as err:
            rig.run(VoltageProgram([0.0, 5.0, 0.0]), log)
        assert str(err.value) == f"{where}: {says}"
        assert rig.emulators.supply.requests == 0     # nothing was sent
    assert not log.exists()


@pytest.mark.parametrize("sections, says", BAD_CONFIG)
@pytest.mark.parametrize("command", ["record", "track"])
def test_the_rig_commands_refuse_such_limits_in_one_line(tmp_path, capsys, sections, says,
                                                         command):
    cfg = tmp_path / "rig.toml"
    cfg.write_text(config_text(**sections))
    out = tmp_path / "run.csv"
    if command == "record":
        argv = ["rig", "record", "--config", cfg, "--period", "2", "--cycles", "1", "-o", out]
    else:
        model, desired = tmp_path / "m.json", tmp_path / "desired.csv"
        MODEL.save(model)
        pihyst.io.write_columns(desired, {"displacement_um": np.linspace(0, 5, 20)})
        argv = ["rig", "track", model, desired, "--config", cfg, "-o", out]
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err == f"pihyst: error: {cfg}{says}\n"
    assert not out.exists()


@pytest.mark.parametrize("make, says", [
    (lambda: VoltageProgram([]), r"voltage signal must be a non-empty sequence of volts, got "
                                 r"shape \(0,\)"),
    (lambda: VoltageProgram([[1.0, 2.0]]), "non-empty sequence of volts, got shape"),
    (lambda: VoltageProgram([0.0, float("inf"), 1.0]), "not a finite number at tick 1: inf"),
    (lambda: VoltageProgram(["a", "b"]), "the voltage signal must be a sequence of numbers"),
    (lambda: FeedforwardProgram(MODEL, [], 0.0, 150.0), "desired trajectory must be a non-empty"),
    (lambda: FeedforwardProgram(MODEL, [{}], 0.0, 150.0),
     "the desired trajectory must be a sequence of numbers"),
    (lambda: FeedforwardProgram(MODEL, [1.0], 200.0, 300.0),
     r"the model's input range \[0, 150\] V and the rig's limits \[200, 300\] V do not overlap"),
    (lambda: FeedbackProgram(MODEL, [1.0], 0.0, 150.0, 0.05, -1.0, 0.0),
     "KP must be a finite number >= 0, got -1.0"),
    (lambda: Fault("melt", "supply"), "unknown fault 'melt'"),
    (lambda: Fault("over-range", "supply"), "fault 'over-range' does not apply to the supply"),
    (lambda: Fault("stuck", "sensor", count=0), "count must be >= 1 or None, got 0"),
    (lambda: encode_registers(70000, "uint16"), "70000 does not fit a uint16 register"),
    (lambda: encode_registers(1.0, "int8"), "unknown register format 'int8'"),
])
def test_bad_program_and_fault_arguments_are_pihyst_errors(make, says):
    with pytest.raises(InvalidArgumentError, match=says):
        make()


def test_a_run_log_that_cannot_be_read_names_the_file_and_where(tmp_path):
    path = tmp_path / "run.csv"
    path.write_text("# notes only\n")
    with pytest.raises(RecordError, match=r"run.csv: no header row: not a pihyst run log"):
        read_run_log(path)
    path.write_text("tick,time_s,phase\n0,0.0,run\n1,oops,run\n")
    with pytest.raises(CSVError, match=r"run.csv:3:2: column 'time_s': 'oops' is not a number"):
        read_run_log(path)


def test_a_stepper_refuses_a_dt_that_is_not_a_number():
    model = MODEL.replace(creep=pihyst.model.Creep([1.0], [0.05], 0.01))
    stepper = model.stepper()
    with pytest.raises(InvalidArgumentError, match="dt must be a number of seconds, got 'x'"):
        stepper.step(1.0, dt="x")
    with pytest.raises(InvalidArgumentError, match=r"dt must be a number of seconds, got \[None\]"):
        stepper.step(1.0, dt=[None])


def test_a_setpoint_refused_during_a_run_stops_it_at_0_v(tmp_path):
    # a driver that refuses 40 V and more although the limits passed its check: the run
    # stops there (not an error escaping the loop), and ramps down to 0 V, output off
    log = tmp_path / "run.csv"
    with Rig(make_config(rig={"slew_V_per_s": 400.0})) as rig:
        send = rig.supply.set_voltage

        def refusing(volts):
            if volts >= 40.0:
                raise InvalidArgumentError(f"supply setpoint: {volts:g} V refused")
            send(volts)
        rig.supply.set_voltage = refusing
        result = rig.run(VoltageProgram(np.r_[np.linspace(0.0, 60.0, 61), 0.0]), log)
        assert not result.completed and result.zeroed
        assert result.reason == "supply setpoint: 40 V refused"
        state = rig.emulators.supply_state
        assert state.last_setpoint_V == 0.0 and not state.output_on
    notes = read_run_log(log)[1]
    assert any(n.startswith("stopped: supply setpoint: 40 V refused") for n in notes), notes
