"""Properties of the PyMeasure supplies, for any setpoint and register map: a setpoint
within 0 .. max_voltage goes out as one Modbus frame with a good CRC whose registers
decode (pihyst's codecs, as the emulated supply decodes them) to that voltage; any
other value writes nothing."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

pytest.importorskip("pymeasure")

from pymeasure.adapters import Adapter  # noqa: E402

from pihyst.rig._codecs import crc_ok, decode_registers, with_crc  # noqa: E402
from pihyst.rig.pymeasure import ModbusHVSupply  # noqa: E402


class ModbusEcho(Adapter):
    """Records every frame written and answers a write request as a server does (its
    first six bytes and a CRC)."""

    def __init__(self):
        super().__init__()
        self.frames, self._reply = [], b""

    def _write_bytes(self, content, **kwargs):
        self.frames.append(bytes(content))
        self._reply = with_crc(content[:6])

    def _read_bytes(self, count, break_on_termchar=False, **kwargs):
        out, self._reply = self._reply[:count], self._reply[count:]
        return out

    def flush_read_buffer(self):
        self._reply = b""


MAPS = st.fixed_dictionaries({
    "setpoint_format": st.sampled_from(["uint16", "uint32", "float32"]),
    "word_order": st.sampled_from(["big", "little"]),
    "scale": st.sampled_from([1.0, 10.0, 100.0, 1000.0]),
    "setpoint_register": st.integers(0, 0xFFF0),
    "address": st.integers(1, 247),
})


@settings(max_examples=60, deadline=None)
@given(MAPS, st.floats(0.0, 1.0))
def test_a_setpoint_within_the_limits_is_sent_exactly(regs, fraction):
    max_voltage = 60.0                          # 60 V x 1000 fits even a uint16 register
    volts = fraction * max_voltage
    adapter = ModbusEcho()
    supply = ModbusHVSupply(adapter, config=regs, max_voltage=max_voltage)
    supply.voltage_setpoint = volts
    (frame,) = adapter.frames
    assert crc_ok(frame) and frame[0] == regs["address"]
    assert int.from_bytes(frame[2:4], "big") == regs["setpoint_register"]
    if regs["setpoint_format"] == "uint16":
        assert frame[1] == 6
        words = [int.from_bytes(frame[4:6], "big")]
    else:
        assert frame[1] == 16 and frame[6] == 4
        words = [int.from_bytes(frame[7:9], "big"), int.from_bytes(frame[9:11], "big")]
    sent = decode_registers(words, regs["setpoint_format"], regs["word_order"]) / regs["scale"]
    step = 0.5 / regs["scale"] if regs["setpoint_format"] != "float32" else 1e-6 * volts
    assert abs(sent - volts) <= step + 1e-12
    assert 0.0 <= sent <= max_voltage


@settings(max_examples=60, deadline=None)
@given(MAPS, st.one_of(st.floats(allow_nan=True, allow_infinity=True)
                       .filter(lambda v: not 0.0 <= v <= 60.0),
                       st.just(math.nan)))
def test_no_other_value_is_sent(regs, volts):
    adapter = ModbusEcho()
    supply = ModbusHVSupply(adapter, config=regs, max_voltage=60.0)
    with pytest.raises(ValueError):
        supply.voltage_setpoint = volts
    assert adapter.frames == []
