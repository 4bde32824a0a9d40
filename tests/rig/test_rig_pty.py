"""The emulated instruments over pseudo-terminals, in real time, and 'pihyst rig emulate'."""

import os
import subprocess
import sys

import numpy as np
import pytest
from rig_helpers import make_config

from pihyst.rig import Rig, VoltageProgram, open_sensor, open_supply
from pihyst.rig._pty import PtyEmulators

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs pseudo-terminals")


def test_record_over_pseudo_terminals(tmp_path):
    config = make_config(supply={"baudrate": 115200})
    with PtyEmulators(config) as emu:
        real = make_config(supply={"port": emu.paths["supply"], "baudrate": 115200},
                           sensor={"port": emu.paths["sensor"]}, rig={"rate_hz": 25.0})
        with Rig(real) as rig:
            assert not rig.emulate
            result = rig.run(VoltageProgram(np.linspace(0.0, 30.0, 20)), tmp_path / "run.csv",
                             handle_signals=False)
        st = emu.emulators.supply_state
        assert result.completed, result.reason
        assert st.last_setpoint_V == 0.0 and not st.output_on
        sent = [u for _, u in st.commands]
        assert max(sent) == pytest.approx(30.0)
        y = result.column("displacement_um", "run")
        assert np.all(np.isfinite(y)) and y[-1] > y[0] + 3


def test_vanishing_pseudo_terminal(tmp_path):
    import time

    from pihyst.rig import Fault
    config = make_config()
    with PtyEmulators(config, faults=[Fault("vanish", "sensor", start_s=0.3)]) as emu:
        cfg = make_config(sensor={"port": emu.paths["sensor"]}).sensor
        sensor = open_sensor(cfg)
        assert sensor.read().valid
        time.sleep(0.4)
        with pytest.raises(OSError):          # what the loop counts as a communication error
            for _ in range(3):
                sensor.read()


def test_emulate_command_prints_paths_and_serves(tmp_path):
    cfg = tmp_path / "rig.toml"
    from rig_helpers import config_text
    cfg.write_text(config_text())
    proc = subprocess.Popen([sys.executable, "-m", "pihyst", "rig", "emulate", "--config",
                             str(cfg), "--duration", "20"], stdout=subprocess.PIPE, text=True)
    try:
        paths = {}
        for _ in range(3):
            line = proc.stdout.readline()
            what, _, rest = line.partition(": ")
            if what in ("supply", "sensor"):
                paths[what] = rest.split()[0]
        config = make_config(supply={"port": paths["supply"]},
                             sensor={"port": paths["sensor"]})
        supply = open_supply(config.supply)
        supply.output_on()
        supply.set_voltage(12.5)
        assert supply.read_voltage() == pytest.approx(12.5)
        assert open_sensor(config.sensor).read().valid
        supply.set_voltage(0.0)
        supply.close()
        proc.terminate()
        out = proc.communicate(timeout=10)[0]
        assert "last setpoint 0 V" in out
        assert proc.returncode == 0
    finally:
        if proc.poll() is None:
            proc.kill()


def test_spy_url_logs_the_traffic(tmp_path):
    # docs/rig.md: 'spy://' shows every byte pihyst exchanges with a supply
    config = make_config(supply={"readback_register": None})
    trace = tmp_path / "trace.txt"
    with PtyEmulators(config) as emu:
        cfg = make_config(supply={"port": f"spy://{emu.paths['supply']}?file={trace}",
                                  "readback_register": None}).supply
        supply = open_supply(cfg)
        supply.set_voltage(10.0)
        supply.close()
        assert emu.emulators.supply_state.last_setpoint_V == 10.0
    lines = trace.read_text().upper().split("\n")
    tx = [" ".join(line.split()[3:16]) for line in lines if " TX " in line]
    assert tx == ["01 10 00 0A 00 02 04 41 20 00 00 66 26"]       # 10.0 V as float32 + CRC
