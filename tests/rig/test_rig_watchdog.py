"""The supply safe when pihyst itself is killed (issue 24, items 7 and 8): the
configuration names the supply's communication watchdog, pihyst arms it at the start of
a run and feeds it with every request, the emulated supply implements it, and a
`pihyst rig record` killed with SIGKILL leaves the emulated output at 0 V within the
configured time. A stop names its first cause."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from rig_helpers import config_text, make_config

from pihyst.rig import Fault, Rig, VoltageProgram, parse_config, read_run_log
from pihyst.rig._config import ConfigError
from pihyst.rig._pty import PtyEmulators

MODBUS_WATCHDOG = {"watchdog_s": 1.0, "watchdog_register": 13}
ASCII = {"protocol": "ascii", "set_command": "VOLT {volts:.2f}",
         "query_command": "MEAS:VOLT?", "output_on_command": "OUTP ON",
         "output_off_command": "OUTP OFF", "watchdog_s": 1.0,
         "watchdog_command": "SYST:WDOG {seconds:.2f}", "address": None,
         "setpoint_register": None, "setpoint_format": None, "word_order": None,
         "scale": None, "output_register": None, "readback_register": None}


@pytest.mark.parametrize("supply, says", [
    ({"watchdog_s": 1.0}, "[supply] watchdog_s: is set but watchdog_register"),
    ({"watchdog_register": 13}, "[supply] watchdog_register: names the supply's watchdog"),
    ({"watchdog_s": 0.1, "watchdog_register": 13}, "would trip between two ticks"),
    ({"watchdog_s": 100.0, "watchdog_register": 13}, "a uint16 register holds"),
    ({"watchdog_s": -1.0, "watchdog_register": 13}, "must be a positive number"),
    ({**ASCII, "watchdog_command": "WDOG {secs}"}, "[supply] watchdog_command: bad template"),
])
def test_watchdog_configuration_errors(supply, says):
    with pytest.raises(ConfigError) as err:
        parse_config(config_text(supply=supply), source="rig.toml")
    assert says in str(err.value) and str(err.value).startswith("rig.toml:")


@pytest.mark.parametrize("supply", [MODBUS_WATCHDOG, ASCII])
def test_a_run_arms_feeds_and_disarms_the_watchdog(tmp_path, supply):
    config = make_config(supply=supply)
    with Rig(config) as rig:
        st = rig.emulators.supply_state
        result = rig.run(VoltageProgram(np.linspace(0.0, 30.0, 40)), tmp_path / "run.csv",
                         handle_signals=False)
    assert result.completed and result.zeroed, result.reason
    assert not st.watchdog_tripped                 # fed on every tick
    assert st.watchdog_s == 0.0                    # disarmed after output off
    notes = read_run_log(tmp_path / "run.csv")[1]
    assert any("supply watchdog armed: output off after 1 s" in n for n in notes)


def test_the_emulated_watchdog_switches_off_a_silent_controller():
    config = make_config(supply=MODBUS_WATCHDOG)
    with Rig(config) as rig:
        rig.supply.set_voltage(20.0)
        rig.supply.arm_watchdog()
        rig.supply.output_on()
        st = rig.emulators.supply_state
        t = st.last_request
        assert st.output_V == pytest.approx(20.0) and st.watchdog_s == 1.0
        rig.emulators.beam.poll(t + 0.9)
        assert st.output_V == pytest.approx(20.0)
        rig.emulators.beam.poll(t + 1.01)
        assert st.output_V == 0.0 and st.watchdog_tripped


def test_a_dead_sensor_is_the_stop_reason_not_the_zeroed_readback(tmp_path):
    # the sensor stops answering: each tick costs its timeout, the supply's watchdog
    # (fixed in this emulated supply) trips between two requests, and the readback is 0 V
    config = make_config(rig={"rate_hz": 20.0}, sensor={"timeout_s": 0.3},
                         emulator={"supply_watchdog_s": 0.2})
    with Rig(config, faults=[Fault("no-reply", "sensor", start_s=2.0)]) as rig:
        u = np.r_[np.linspace(0, 60, 200), np.linspace(60, 0, 200)]
        result = rig.run(VoltageProgram(u), tmp_path / "run.csv", handle_signals=False)
    assert not result.completed
    # the first cause first; what it led to after
    assert result.reason.startswith("sensor: no reply within 0.3 s (from tick "), result.reason
    assert "; then readback 0.000 V differs from the command" in result.reason
    notes = read_run_log(tmp_path / "run.csv")[1]
    assert any(n.startswith("stopped: sensor: no reply") for n in notes)


_RECORD_CONFIG = """
[rig]
rate_hz = 20.0
u_min = 0.0
u_max = 150.0
slew_V_per_s = 200.0
[supply]
port = "{supply}"
baudrate = 115200
protocol = "modbus-rtu"
address = 1
setpoint_register = 10
setpoint_format = "float32"
output_register = 9
readback_register = 12
watchdog_register = 13
watchdog_s = {watchdog_s}
[sensor]
port = "{sensor}"
baudrate = 115200
protocol = "keyence-lk-g5000"
"""


@pytest.mark.slow       # about 3 s of wall clock: make test-slow and CI run it
@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs pseudo-terminals")
def test_rig_record_killed_with_sigkill_leaves_the_supply_at_0_V(tmp_path):
    watchdog_s = 0.6
    emu_config = make_config(supply={**MODBUS_WATCHDOG, "baudrate": 115200})
    with PtyEmulators(emu_config) as emu:
        st = emu.emulators.supply_state
        cfg = tmp_path / "rig.toml"
        cfg.write_text(_RECORD_CONFIG.format(supply=emu.paths["supply"],
                                             sensor=emu.paths["sensor"],
                                             watchdog_s=watchdog_s))
        child = subprocess.Popen([sys.executable, "-m", "pihyst", "rig", "record",
                                  "--config", str(cfg), "--max", "60", "--period", "20",
                                  "-o", str(tmp_path / "log.csv")],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        try:
            deadline = time.monotonic() + 30
            while st.output_V < 10.0:               # the run is well under way
                assert child.poll() is None, child.stderr.read()
                assert time.monotonic() < deadline, "the run did not start"
                time.sleep(0.02)
            assert st.watchdog_s == watchdog_s      # armed by pihyst
            child.send_signal(signal.SIGKILL)
            child.wait()
            killed = time.monotonic()
            while st.output_V != 0.0 and time.monotonic() < killed + 5 * watchdog_s:
                time.sleep(0.01)
            off_after = time.monotonic() - killed
        finally:
            if child.poll() is None:
                child.kill()
                child.wait()
            child.stderr.close()
    assert st.output_V == 0.0 and st.watchdog_tripped
    # within the watchdog's time (plus the emulator's 20 ms poll and scheduling slack)
    assert off_after <= watchdog_s + 0.3, off_after
