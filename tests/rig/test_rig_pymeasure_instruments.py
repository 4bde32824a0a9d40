"""The PyMeasure Instrument classes (pihyst.rig.pymeasure) speak the bytes of pihyst's
drivers: checked with PyMeasure's expected_protocol against frames written out by hand
(Modbus RTU frames from the application protocol, KEYENCE and MDT693B dialogues from
docs/rig.md), and refuse setpoints beyond their limits before anything is sent."""

import math

import pytest

pytest.importorskip("pymeasure")

from pymeasure.test import expected_protocol  # noqa: E402

from pihyst.rig import KeyenceError, crc16_modbus  # noqa: E402
from pihyst.rig.pymeasure import (  # noqa: E402
    AsciiHVSupply,
    KeyenceLKG3000,
    KeyenceLKG5000,
    MDT693BLikeSupply,
    ModbusHVSupply,
)


def rtu(hex_frame):
    """A Modbus RTU frame from its hex digits, CRC appended (low byte first)."""
    frame = bytes.fromhex(hex_frame)
    return frame + crc16_modbus(frame).to_bytes(2, "little")


# ----------------------------------------------------------------------------- KEYENCE
def test_lk_g5000_reads_the_configured_output_with_scale_and_sign():
    with expected_protocol(KeyenceLKG5000, [(b"MS,02\r", b"MS,02,+0012.3456\r")],
                           config={"output": 2, "scale_um": 10.0, "sign": -1}) as sensor:
        assert sensor.displacement == pytest.approx(-123.456)


def test_lk_g3000_dialect():
    with expected_protocol(KeyenceLKG3000, [(b"M1\r", b"M1,-01.2345\r")]) as sensor:
        assert sensor.displacement == pytest.approx(-1.2345)


@pytest.mark.parametrize("marker, status", [("+FFFFFFF", "over-range+"),
                                            ("-FFFFFFF", "over-range-"),
                                            ("XXXXXXXX", "invalid")])
def test_no_value_is_never_a_number(marker, status):
    pairs = [(b"MS,01\r", f"MS,01,{marker}\r".encode())] * 2
    with expected_protocol(KeyenceLKG5000, pairs) as sensor:
        assert math.isnan(sensor.displacement)
        reading = sensor.reading
        assert reading.value is None and reading.status == status


def test_er_reply_raises_naming_the_code():
    with expected_protocol(KeyenceLKG5000, [(b"MS,01\r", b"ER,MS,62\r")]) as sensor:
        with pytest.raises(KeyenceError, match="ER,MS,62 .parameter range error"):
            _ = sensor.displacement


# ----------------------------------------------------------------------------- Modbus
def test_a_frame_quoted_in_modbus_tutorials():
    # read holding register 0, count 1, slave 1: 01 03 00 00 00 01 84 0A
    request = bytes.fromhex("01 03 0000 0001 840A")
    assert rtu("01 03 0000 0001") == request
    with expected_protocol(ModbusHVSupply, [(request, rtu("01 03 02 0064"))],
                           config={"setpoint_format": "uint16", "scale": 1.0,
                                   "readback_register": 0}) as supply:
        assert supply.voltage == 100.0


def test_float32_setpoint_output_and_readback():
    pairs = [(rtu("01 10 000A 0002 04 4120 0000"), rtu("01 10 000A 0002")),   # 10.0 V
             (rtu("01 06 0009 0001"), rtu("01 06 0009 0001")),                # output on
             (rtu("01 03 000C 0002"), rtu("01 03 04 411F 5C29")),             # 9.96 V back
             (rtu("01 10 000A 0002 04 0000 0000"), rtu("01 10 000A 0002")),   # shutdown: 0 V
             (rtu("01 06 0009 0000"), rtu("01 06 0009 0000"))]                # output off
    with expected_protocol(ModbusHVSupply, pairs,
                           config={"output_register": 9, "readback_register": 12}) as supply:
        supply.voltage_setpoint = 10.0
        supply.output_enabled = True
        assert supply.voltage == pytest.approx(9.96, abs=1e-5)
        assert supply.voltage_setpoint == 10.0 and supply.output_enabled
        supply.shutdown()
        assert supply.voltage_setpoint == 0.0 and supply.output_enabled is False


def test_uint32_counts_low_word_first_at_another_address():
    # 12.34 V at 100 counts per volt = 1234 = 0x000004D2, CDAB: 04D2 0000
    pairs = [(rtu("07 10 0020 0002 04 04D2 0000"), rtu("07 10 0020 0002"))]
    with expected_protocol(ModbusHVSupply, pairs,
                           config={"address": 7, "setpoint_register": 32,
                                   "setpoint_format": "uint32", "word_order": "little",
                                   "scale": 100.0}) as supply:
        supply.voltage_setpoint = 12.34


def test_uint16_setpoint_uses_function_06():
    pairs = [(rtu("01 06 000A 0BB8"), rtu("01 06 000A 0BB8"))]            # 30 V x 100
    with expected_protocol(ModbusHVSupply, pairs,
                           config={"setpoint_format": "uint16", "scale": 100.0}) as supply:
        supply.voltage_setpoint = 30.0


def test_modbus_exception_reply_is_an_oserror():
    pairs = [(rtu("01 10 000A 0002 04 4120 0000"), rtu("01 90 02"))]
    with expected_protocol(ModbusHVSupply, pairs) as supply:
        with pytest.raises(OSError):
            supply.voltage_setpoint = 10.0


def test_the_limits_of_a_rig_configuration_file(tmp_path):
    cfg = tmp_path / "rig.toml"
    cfg.write_text("[rig]\nu_max = 120.0\n[supply]\noutput_register = 9\n")
    with expected_protocol(ModbusHVSupply, [], config=str(cfg)) as supply:
        assert supply.max_voltage == 120.0
        with pytest.raises(ValueError):
            supply.voltage_setpoint = 120.5


@pytest.mark.parametrize("volts", [150.01, -0.01, math.nan, math.inf, 1e9])
def test_no_setpoint_beyond_the_limits_is_sent(volts):
    for cls in (ModbusHVSupply, MDT693BLikeSupply):
        with expected_protocol(cls, []) as supply:          # nothing may be written
            with pytest.raises(ValueError):
                supply.voltage_setpoint = volts
            assert supply.voltage_setpoint is None


def test_a_limit_the_register_cannot_hold_is_refused():
    from pihyst.exceptions import InvalidArgumentError
    with pytest.raises(InvalidArgumentError, match="more than a uint16"):
        with expected_protocol(ModbusHVSupply, [], max_voltage=1000.0,
                               config={"setpoint_format": "uint16", "scale": 100.0}):
            pass


# ----------------------------------------------------------------------------- ASCII
def test_scpi_like_ascii_supply():
    config = {"terminator": "\n", "set_command": "VOLT {volts:.2f}",
              "query_command": "MEAS:VOLT?", "output_on_command": "OUTP ON",
              "output_off_command": "OUTP OFF"}
    pairs = [(b"VOLT 12.50\n", None), (b"OUTP ON\n", None),
             (b"MEAS:VOLT?\n", b"12.498\n"),
             (b"VOLT 0.00\n", None), (b"OUTP OFF\n", None)]
    with expected_protocol(AsciiHVSupply, pairs, config=config) as supply:
        supply.voltage_setpoint = 12.5
        supply.output_enabled = True
        assert supply.voltage == pytest.approx(12.498)
        supply.shutdown()


def test_mdt693b_like_echo_and_prompt():
    pairs = [(b"xvoltage=24.80\r", b"xvoltage=24.80\r*"),
             (b"xvoltage?\r", b"xvoltage?\r*[  24.8]\r")]
    with expected_protocol(MDT693BLikeSupply, pairs) as supply:
        supply.voltage_setpoint = 24.8
        assert supply.voltage == pytest.approx(24.8)


def test_mdt693b_like_error_message_before_the_prompt_raises():
    pairs = [(b"xvoltage=24.80\r", b"xvoltage=24.80\rCMD_NOT_DEFINED*")]
    with expected_protocol(MDT693BLikeSupply, pairs) as supply:
        with pytest.raises(OSError, match="CMD_NOT_DEFINED"):
            supply.voltage_setpoint = 24.8


def test_shutdown_switches_the_output_off_even_when_0_V_is_not_answered():
    pairs = [(rtu("01 10 000A 0002 04 0000 0000"), rtu("01 90 04")),       # device failure
             (rtu("01 06 0009 0000"), rtu("01 06 0009 0000"))]              # output off
    with pytest.raises(OSError):
        with expected_protocol(ModbusHVSupply, pairs, config={"output_register": 9}) as s:
            s.shutdown()
    assert s.output_enabled is False and s.isShutdown


def test_leaving_with_brings_the_supply_to_0_V():
    pairs = [(b"xvoltage=30.00\r", b"xvoltage=30.00\r*"),
             (b"xvoltage=0.00\r", b"xvoltage=0.00\r*")]
    with expected_protocol(MDT693BLikeSupply, pairs) as supply:
        with supply:
            supply.voltage_setpoint = 30.0
        assert supply.voltage_setpoint == 0.0


def test_a_configuration_of_another_protocol_is_refused(tmp_path):
    from pihyst.rig import ConfigError
    cfg = tmp_path / "rig.toml"
    cfg.write_text('[supply]\nprotocol = "ascii"\n[sensor]\nprotocol = "keyence-lk-g3000"\n')
    with pytest.raises(ConfigError, match="protocol is 'ascii'; this instrument speaks "
                                          "'modbus-rtu'"):
        ModbusHVSupply(None, config=str(cfg))
    with pytest.raises(ConfigError, match="protocol is 'keyence-lk-g3000'"):
        KeyenceLKG5000(None, config=str(cfg))
    with pytest.raises(ConfigError, match=r"\[supply\] setpoint_format: unknown key|must be"):
        ModbusHVSupply(None, config={"setpoint_format": 16})
    with expected_protocol(KeyenceLKG3000, [], config=str(cfg)) as sensor:
        assert sensor.driver.command == "M1"


def test_visa_errors_are_oserrors_the_loop_counts():
    """A VISA connection that fails (a closed socket, a timeout) raises an OSError from
    the drivers, which the controller counts as a communication error."""
    import pyvisa
    from pymeasure.adapters import VISAAdapter

    from pihyst.rig.pymeasure import AdapterPort

    class Broken(VISAAdapter):
        def __init__(self, error):
            import logging
            self.error, self.log = error, logging.getLogger("test")

        def _write_bytes(self, content, **kwargs):
            pass

        def _read_bytes(self, count, break_on_termchar=False, **kwargs):
            raise pyvisa.errors.VisaIOError(self.error)

        def flush_read_buffer(self):
            if self.error != pyvisa.constants.StatusCode.error_timeout:
                raise pyvisa.errors.VisaIOError(self.error)

        def close(self):
            pass

    timeout = KeyenceLKG5000(Broken(pyvisa.constants.StatusCode.error_timeout))
    with pytest.raises(OSError, match="no reply within 0.1 s"):
        _ = timeout.reading
    closed = KeyenceLKG5000(Broken(pyvisa.constants.StatusCode.error_connection_lost))
    with pytest.raises(OSError):
        _ = closed.reading
    assert isinstance(timeout.port, AdapterPort) and timeout.port._bytewise
