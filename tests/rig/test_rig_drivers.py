"""Each driver against a scripted port that asserts every byte sent and received."""

import math

import minimalmodbus
import pytest
from rig_helpers import ScriptedPort, make_config

from pihyst.rig import (
    AsciiSupply,
    KeyenceError,
    KeyenceSensor,
    ModbusRtuSupply,
    NoReplyError,
    ReplyError,
    RigError,
    VirtualClock,
)
from pihyst.rig._codecs import with_crc


def h(text):
    return with_crc(bytes.fromhex(text))


def modbus(port_script, **supply):
    cfg = make_config(supply=supply).supply
    port = ScriptedPort(port_script)
    return ModbusRtuSupply(port, cfg, VirtualClock()), port


def test_modbus_float32_big():
    supply, port = modbus([
        (h("0110000A00020443160000"), h("0110000A0002")),     # 150.0 V -> 0x43160000
        (h("0103000C0002"), h("0103044316147B")),              # readback 150.08 V
        (h("010600090001"), h("010600090001")),                # output on
        (h("010600090000"), h("010600090000")),                # output off
    ])
    supply.set_voltage(150.0)
    assert supply.read_voltage() == pytest.approx(150.08, abs=1e-4)
    supply.output_on()
    supply.output_off()
    port.done()


def test_modbus_uint32_little_scaled():
    # 123.45 V at 100 counts per volt = 12345 = 0x00003039, low word first
    supply, port = modbus([(h("0710001400020430390000"), h("071000140002"))],
                          address=7, setpoint_register=20, setpoint_format="uint32",
                          word_order="little", scale=100.0, readback_register=None,
                          output_register=None)
    supply.set_voltage(123.45)
    assert supply.read_voltage() is None
    supply.output_on()          # no output register: nothing is sent
    port.done()


def test_modbus_uint16_uses_function_06():
    supply, port = modbus([(h("0206000503E8"), h("0206000503E8"))], address=2,
                          setpoint_register=5, setpoint_format="uint16", scale=10.0)
    supply.set_voltage(100.0)
    port.done()
    with pytest.raises(ValueError, match="more than a uint16"):
        supply.set_voltage(7000.0)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -1.0])
def test_setpoints_refused_before_sending(bad):
    supply, port = modbus([])
    with pytest.raises(ValueError, match="refusing"):
        supply.set_voltage(bad)
    port.done()


def test_modbus_errors():
    supply, port = modbus([(h("0103000C0002"), h("018302"))])
    with pytest.raises(minimalmodbus.IllegalRequestError):
        supply.read_voltage()
    supply, port = modbus([(h("0103000C0002"), h("0103044316147B")[:-1] + b"\x00")])
    with pytest.raises(minimalmodbus.InvalidResponseError):
        supply.read_voltage()
    supply, port = modbus([(h("0103000C0002"), b"")])
    with pytest.raises(minimalmodbus.NoResponseError):
        supply.read_voltage()
    assert isinstance(minimalmodbus.NoResponseError(), OSError)


def ascii_supply(script, **supply):
    cfg = make_config(supply={"protocol": "ascii", **supply}).supply
    port = ScriptedPort(script)
    return AsciiSupply(port, cfg), port


def test_ascii_scpi():
    supply, port = ascii_supply([(b"VOLT 12.35\r\n", b""), (b"MEAS:VOLT?\r\n", b"12.340\r\n"),
                                 (b"OUTP ON\r\n", b""), (b"OUTP OFF\r\n", b"")],
                                query_command="MEAS:VOLT?", output_on_command="OUTP ON",
                                output_off_command="OUTP OFF")
    supply.set_voltage(12.345)
    assert supply.read_voltage() == 12.34
    supply.output_on()
    supply.output_off()
    port.done()


def test_ascii_mdt693b_echo_and_prompt():
    # the dialogue of a captured MDT693B session (public driver code): the command is
    # echoed, '*' acknowledges, a query's reply follows the prompt
    supply, port = ascii_supply(
        [(b"xvoltage=24.68\r", b"xvoltage=24.68\r*"),
         (b"xvoltage?\r", b"xvoltage?\r*[  24.8]\r"),
         (b"xvoltage=200.00\r", b"xvoltage=200.00\rCMD_NOT_DEFINED\r*")],
        terminator="\r", set_command="xvoltage={volts:.2f}", query_command="xvoltage?",
        echo=True, prompt="*")
    supply.set_voltage(24.68)
    assert supply.read_voltage() == 24.8
    with pytest.raises(RigError, match="CMD_NOT_DEFINED"):
        supply.set_voltage(200.0)
    port.done()


def test_ascii_prompt_after_a_query_reply_arrives_before_the_next_echo():
    # the prompt that follows a query's reply ('*[ 100]\r*' in a captured MDT693B
    # session) was still on its way when the next command went out: it comes before the
    # echo, which is otherwise right
    supply, port = ascii_supply(
        [(b"xvoltage?\r", b"xvoltage?\r*[  24.8]\r"),
         (b"xvoltage=0.00\r", b"*xvoltage=0.00\r*"),
         (b"xvoltage=1.00\r", b"*xvoltage=1.50\r")],
        terminator="\r", set_command="xvoltage={volts:.2f}", query_command="xvoltage?",
        echo=True, prompt="*")
    assert supply.read_voltage() == 24.8
    supply.set_voltage(0.0)
    with pytest.raises(RigError, match="expected the echo"):   # a wrong echo still is one
        supply.set_voltage(1.0)
    port.done()


def test_ascii_errors():
    supply, _ = ascii_supply([(b"xvoltage=1.00\r", b"xvolt")], terminator="\r",
                             set_command="xvoltage={volts:.2f}", echo=True)
    with pytest.raises(RigError, match="cut short"):
        supply.set_voltage(1.0)
    supply, _ = ascii_supply([(b"VOLT 1.00\r\n", b"")], query_command="MEAS:VOLT?")
    supply.set_voltage(1.0)
    supply.port.script.append((b"MEAS:VOLT?\r\n", b""))
    with pytest.raises(NoReplyError):
        supply.read_voltage()
    supply, _ = ascii_supply([(b"MEAS:VOLT?\r\n", b"ERROR\r\n")], query_command="MEAS:VOLT?")
    with pytest.raises(RigError, match="ERROR"):
        supply.read_voltage()


def sensor(script, **cfg):
    port = ScriptedPort(script)
    return KeyenceSensor(port, make_config(sensor=cfg).sensor), port


def test_keyence_g5000_scale_and_sign():
    s, port = sensor([(b"MS,03\r", b"MS,03,+0012.3456\r")], output=3, scale_um=1000.0,
                     sign=-1)
    r = s.read()
    assert r.valid and r.value == pytest.approx(-12345.6)
    port.done()


def test_keyence_g3000():
    s, port = sensor([(b"M2\r", b"M2,-01.2345\r")], protocol="keyence-lk-g3000", output=2)
    assert s.read().value == pytest.approx(-1.2345)
    port.done()


@pytest.mark.parametrize("reply, status", [(b"MS,01,+FFFFFFF\r", "over-range+"),
                                           (b"MS,01,-FFFFFFF\r", "over-range-"),
                                           (b"MS,01,XXXXXXXX\r", "invalid")])
def test_keyence_invalid_readings(reply, status):
    s, _ = sensor([(b"MS,01\r", reply)])
    r = s.read()
    assert r.status == status and r.value is None


def test_keyence_failures():
    s, _ = sensor([(b"MS,01\r", b"ER,MS,62\r")])
    with pytest.raises(KeyenceError, match="62 .parameter range"):
        s.read()
    s, _ = sensor([(b"M1\r", b"ER,M1,22\r")], protocol="keyence-lk-g3000")
    with pytest.raises(KeyenceError, match="22 .invalid parameter"):
        s.read()
    s, _ = sensor([(b"MS,01\r", b"MS,01,+00")])
    with pytest.raises(RigError, match="cut short"):
        s.read()
    s, _ = sensor([(b"MS,01\r", b"")])
    with pytest.raises(NoReplyError):
        s.read()
    s, _ = sensor([(b"MS,01\r", b"MS,01,+0\xf2.3456\r")])
    with pytest.raises(ReplyError):
        s.read()
