"""The emulated instruments, byte for byte, through their in-process pyserial ports."""

import pytest
from rig_helpers import make_config

from pihyst.rig import Emulators, Fault, VirtualClock, open_port
from pihyst.rig._codecs import with_crc
from pihyst.rig._serial_handlers import register, unregister


def h(text):
    return with_crc(bytes.fromhex(text))


@pytest.fixture
def bench():
    """Emulators of the default configuration on pihystsim://t-supply and t-sensor."""
    config = make_config()
    clock = VirtualClock()
    emu = Emulators(config, t0=0.0)
    register("t-supply", emu.supply, clock)
    register("t-sensor", emu.sensor, clock)
    supply = open_port("pihystsim://t-supply", 19200, 0.1, "supply")
    sensor = open_port("pihystsim://t-sensor", 115200, 0.1, "sensor")
    yield emu, clock, supply, sensor
    unregister("t-supply")
    unregister("t-sensor")


def test_modbus_write_read_and_timing(bench):
    emu, clock, supply, _ = bench
    request = h("0110000A00020442C80000")           # 100.0 V
    supply.write(request)
    reply = supply.read(8)
    assert reply == h("0110000A0002")
    # 13 bytes out + 5 ms processing + 8 bytes back, 10 bits each at 19 200 baud
    assert clock.now() == pytest.approx(21 * 10 / 19200 + 0.005)
    assert emu.supply_state.last_setpoint_V == 100.0
    assert emu.supply_state.output_V == 0.0             # output still off
    supply.write(h("010600090001"))
    assert supply.read(8) == h("010600090001")
    assert emu.beam.voltage == 100.0
    supply.write(h("0103000C0002"))
    assert supply.read(9) == h("01030442C80000")


def test_modbus_errors_and_silence(bench):
    emu, clock, supply, _ = bench
    supply.write(h("010300630001"))                     # register 99 does not exist
    assert supply.read(5) == h("018302")
    supply.write(h("0110000A00020444FA0000"))          # 2000 V: more than the supply gives
    assert supply.read(5) == h("019003")
    bad = bytearray(h("0110000A00020442C80000"))
    bad[-1] ^= 0xFF
    supply.write(bytes(bad))                            # bad CRC: ignored
    t = clock.now()
    assert supply.read(8) == b"" and clock.now() == pytest.approx(t + 0.1)
    supply.write(h("0210000A00020442C80000"))          # another slave: ignored
    assert supply.read(8) == b""
    assert emu.supply_state.commands == []


def test_keyence_replies(bench):
    emu, clock, _, sensor = bench
    sensor.write(b"MS,01\r")
    reply = sensor.read_until(b"\r")
    assert reply.startswith(b"MS,01,") and reply.endswith(b"\r")
    value = reply[6:-1].decode()
    assert value[0] in "+-" and len(value.split(".")[1]) == 4
    assert float(value) == pytest.approx(emu.beam.displacement, abs=1e-4)
    sensor.write(b"MS,05\r")
    assert sensor.read_until(b"\r") == b"ER,MS,62\r"
    sensor.write(b"MA\r")
    assert sensor.read_until(b"\r").endswith(b",XXXXXXXX\r")
    sensor.write(b"ZZ\r")
    assert sensor.read_until(b"\r") == b"ER,ZZ,50\r"


def test_keyence_g3000_and_faults():
    config = make_config(sensor={"protocol": "keyence-lk-g3000"})
    emu = Emulators(config, faults=[Fault("over-range", "sensor", count=1),
                                    Fault("error-code", "sensor", start_s=1.0, code=88,
                                          count=1)])
    clock = VirtualClock()
    register("t-g3000", emu.sensor, clock)
    try:
        port = open_port("pihystsim://t-g3000", 115200, 0.1, "sensor")
        port.write(b"M1\r")
        assert port.read_until(b"\r") == b"M1,+FFFFFFF\r"
        port.write(b"M0\r")
        reply = port.read_until(b"\r")
        # a sign and 7 characters: +dd.dddd
        assert reply.startswith(b"M0,") and reply.endswith(b",XXXXXXXX\r")
        assert len(reply.split(b",")[1]) == 8 and reply[5:6] in b"0123456789"
        port.write(b"M5\r")
        assert port.read_until(b"\r") == b"ER,M5,00\r"
        clock.sleep(1.0)
        port.write(b"M1\r")
        assert port.read_until(b"\r") == b"ER,M1,88\r"
    finally:
        unregister("t-g3000")


def test_baud_mismatch_gives_no_reply(bench):
    emu, clock, _, _ = bench
    port = open_port("pihystsim://t-sensor", 9600, 0.1, "sensor")
    port.write(b"MS,01\r")
    assert port.read_until(b"\r") == b""


def test_unknown_device_does_not_open():
    from pihyst.rig import RigError
    with pytest.raises(RigError, match="no emulated device 'nothing'"):
        open_port("pihystsim://nothing", 19200, 0.1, "supply")


@pytest.mark.parametrize("dialect", ["scpi", "mdt"])
def test_ascii_supply_round_trip(dialect):
    from pihyst.rig import open_supply
    supply_cfg = {"protocol": "ascii", "query_command": "MEAS:VOLT?",
                  "output_on_command": "OUTP ON", "output_off_command": "OUTP OFF"}
    emulator = {}
    if dialect == "mdt":
        supply_cfg = {"protocol": "ascii", "terminator": "\r", "echo": True, "prompt": "*",
                      "set_command": "xvoltage={volts:.2f}", "query_command": "xvoltage?",
                      "baudrate": 115200}
        emulator = {"supply_reply": "[{volts:6.2f}]"}
    config = make_config(supply=supply_cfg, emulator=emulator)
    emu = Emulators(config)
    clock = VirtualClock()
    register("t-ascii", emu.supply, clock)
    try:
        port = open_port("pihystsim://t-ascii", config.supply.baudrate, 0.1, "supply")
        supply = open_supply(config.supply, clock, port=port)
        supply.output_on()
        supply.set_voltage(24.68)
        assert supply.read_voltage() == pytest.approx(24.68)
        assert emu.beam.voltage == pytest.approx(24.68)
        supply.output_off()
        assert emu.supply_state.output_V == (0.0 if dialect == "scpi" else 24.68)
    finally:
        unregister("t-ascii")


def test_reads_time_out_on_the_emulators_clock_not_the_wall_clock(bench, monkeypatch):
    # a loaded machine: every wall-clock reading is a second later than the last one
    import itertools

    import serial.serialutil
    ticks = itertools.count()
    monkeypatch.setattr(serial.serialutil.Timeout, "TIME", lambda: float(next(ticks)))
    _, _, _, sensor = bench
    for _ in range(3):
        sensor.write(b"MS,01\r")
        reply = sensor.read_until(b"\r")
        assert reply.startswith(b"MS,01,") and reply.endswith(b"\r")


def test_parity_and_stop_bits():
    # Modbus RTU's default framing, 8E1: 11 bits per byte
    config = make_config(supply={"parity": "E"})
    emu = Emulators(config)
    clock = VirtualClock()
    register("t-8e1", emu.supply, clock)
    try:
        port = open_port("pihystsim://t-8e1", 19200, 0.1, "supply", parity="E")
        port.write(h("0110000A00020442C80000"))
        assert port.read(8) == h("0110000A0002")
        assert clock.now() == pytest.approx(21 * 11 / 19200 + 0.005)
        wrong = open_port("pihystsim://t-8e1", 19200, 0.1, "supply")     # 8N1
        wrong.write(h("0110000A00020442C80000"))
        assert wrong.read(8) == b""
    finally:
        unregister("t-8e1")
