"""The emulated instruments on TCP ports of 127.0.0.1 (pihyst.rig._tcp, 'pihyst rig
emulate --tcp'): reached by pyserial's socket:// (pihyst's own drivers and a whole rig
run), by PyVISA with pyvisa-py over TCPIP::...::SOCKET (plain queries and the PyMeasure
Instrument classes), one client after another, in real time."""

import re
import subprocess
import sys

import numpy as np
import pytest
from rig_helpers import config_text, make_config

from pihyst.rig import Fault, Rig, VoltageProgram, open_sensor, open_supply
from pihyst.rig._tcp import TcpEmulators


def test_record_through_socket_urls(tmp_path):
    config = make_config(supply={"baudrate": 115200})
    with TcpEmulators(config) as emu:
        assert all(url.startswith("socket://127.0.0.1:") for url in emu.paths.values())
        real = make_config(supply={"port": emu.paths["supply"], "baudrate": 115200},
                           sensor={"port": emu.paths["sensor"]}, rig={"rate_hz": 25.0})
        with Rig(real) as rig:
            assert not rig.emulate
            result = rig.run(VoltageProgram(np.linspace(0.0, 30.0, 20)), tmp_path / "run.csv",
                             handle_signals=False)
        st = emu.emulators.supply_state
        assert result.completed and result.zeroed, result.reason
        assert st.last_setpoint_V == 0.0 and not st.output_on
        assert max(u for _, u in st.commands) == pytest.approx(30.0)
        y = result.column("displacement_um", "run")
        assert np.all(np.isfinite(y)) and y[-1] > y[0] + 3


def test_clients_one_after_another_and_fixed_ports():
    config = make_config()
    with TcpEmulators(config) as probe:          # find two free neighbouring ports
        base = probe.addresses["supply"][1]
    for attempt in range(20):
        try:
            emu = TcpEmulators(config, port=base + 2 * attempt)
            break
        except OSError:
            continue
    with emu:
        port = emu.addresses["supply"][1]
        assert emu.addresses["sensor"][1] == port + 1
        assert emu.visa["supply"] == f"TCPIP::127.0.0.1::{port}::SOCKET"
        cfg = make_config(sensor={"port": emu.paths["sensor"]}).sensor
        for _ in range(3):                        # each client hangs up, the next is served
            sensor = open_sensor(cfg)
            assert sensor.read().valid
            sensor.close()


def test_vanish_closes_the_connection():
    import time
    config = make_config()
    with TcpEmulators(config, faults=[Fault("vanish", "sensor", start_s=1.5)]) as emu:
        sensor = open_sensor(make_config(sensor={"port": emu.paths["sensor"]}).sensor)
        assert sensor.read().valid
        time.sleep(1.6)
        with pytest.raises(OSError):
            for _ in range(3):
                sensor.read()
        sensor.close()


def test_pyvisa_tcpip_socket():
    pyvisa = pytest.importorskip("pyvisa")
    pytest.importorskip("pyvisa_py")
    config = make_config(sensor={"protocol": "keyence-lk-g3000", "output": 2})
    rm = pyvisa.ResourceManager("@py")
    with TcpEmulators(config) as emu:
        lk = rm.open_resource(emu.visa["sensor"], read_termination="\r",
                              write_termination="\r", timeout=2000)
        try:
            reply = lk.query("M2")
            assert re.fullmatch(r"M2,[+-]\d\d\.\d{4}", reply)          # M2,+01.2345
            assert lk.query("M1") == "M1,XXXXXXXX"                   # output 1: no head
            assert lk.query("MS,01") == "ER,MS,00"                   # not an LK-G3000 command
        finally:
            lk.close()
            rm.close()


def test_pymeasure_instruments_over_pyvisa_tcpip():
    pytest.importorskip("pymeasure")
    pytest.importorskip("pyvisa_py")
    from pihyst.rig.pymeasure import KeyenceLKG5000, ModbusHVSupply
    config = make_config(supply={"baudrate": 115200})
    with TcpEmulators(config) as emu:
        supply = ModbusHVSupply(emu.visa["supply"], config=config, visa_library="@py")
        sensor = KeyenceLKG5000(emu.visa["sensor"], config=config, visa_library="@py")
        try:
            rest = sensor.displacement
            supply.output_enabled = True
            supply.voltage_setpoint = 60.0
            assert supply.voltage == pytest.approx(60.0, abs=0.01)
            assert sensor.displacement > rest + 5
            supply.shutdown()
            st = emu.emulators.supply_state
            assert st.setpoint_V == 0.0 and not st.output_on
        finally:
            supply.adapter.close()
            sensor.adapter.close()


def test_emulate_command_on_tcp(tmp_path):
    cfg = tmp_path / "rig.toml"
    cfg.write_text(config_text())
    proc = subprocess.Popen([sys.executable, "-m", "pihyst", "rig", "emulate", "--config",
                             str(cfg), "--tcp", "0", "--duration", "20"],
                            stdout=subprocess.PIPE, text=True)
    try:
        urls, visa = {}, {}
        for _ in range(3):
            line = proc.stdout.readline()
            what, _, rest = line.partition(": ")
            if what in ("supply", "sensor"):
                urls[what] = rest.split()[0]
                visa[what] = rest.split()[1].strip("(;")
        assert urls["supply"].startswith("socket://127.0.0.1:")
        port = int(urls["supply"].rsplit(":", 1)[1])
        assert visa["supply"] == f"TCPIP::127.0.0.1::{port}::SOCKET"
        config = make_config(supply={"port": urls["supply"]}, sensor={"port": urls["sensor"]})
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


def test_emulate_tcp_port_in_use_is_one_line(tmp_path, capsys):
    import socket

    from pihyst.cli import main
    cfg = tmp_path / "rig.toml"
    cfg.write_text(config_text())
    with socket.create_server(("127.0.0.1", 0)) as busy:
        port = busy.getsockname()[1]
        assert main(["rig", "emulate", "--config", str(cfg), "--tcp", str(port),
                     "--duration", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"--tcp {port}: cannot listen on 127.0.0.1" in err[0]
    assert err[0].endswith("Address already in use")
