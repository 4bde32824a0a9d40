import pytest

from pihyst.rig._codecs import (
    KeyenceError,
    Reading,
    ReplyError,
    crc16_modbus,
    crc_ok,
    decode_registers,
    encode_registers,
    format_value,
    parse_reply,
    parse_value,
    request_length,
    with_crc,
)


def test_crc_catalogue_check_value():
    # CRC-16/MODBUS of "123456789" is 0x4B37 (the CRC catalogue's check value)
    assert crc16_modbus(b"123456789") == 0x4B37


def test_crc_of_known_frames():
    # read holding registers 0..9 of slave 1 and write register 1 = 3: frames quoted in
    # Modbus tutorials, CRC low byte first
    assert with_crc(bytes.fromhex("01030000000A")) == bytes.fromhex("01030000000AC5CD")
    assert with_crc(bytes.fromhex("010600010003")) == bytes.fromhex("010600010003980B")
    assert crc_ok(bytes.fromhex("010600010003980B"))
    assert not crc_ok(bytes.fromhex("010600010003980C"))


@pytest.mark.parametrize("fmt", ["uint16", "uint32", "float32"])
@pytest.mark.parametrize("order", ["big", "little"])
def test_registers_round_trip(fmt, order):
    for value in (0.0, 1.0, 150.0, 1000.0 if fmt != "uint16" else 65535.0):
        words = encode_registers(value, fmt, order)
        assert all(0 <= w <= 0xFFFF for w in words)
        assert decode_registers(words, fmt, order) == value


def test_register_word_order():
    assert encode_registers(100000, "uint32", "big") == [0x0001, 0x86A0]
    assert encode_registers(100000, "uint32", "little") == [0x86A0, 0x0001]
    assert encode_registers(1.0, "float32", "big") == [0x3F80, 0x0000]


def test_register_overflow():
    with pytest.raises(ValueError, match="uint16"):
        encode_registers(70000, "uint16")
    with pytest.raises(ValueError, match="uint32"):
        encode_registers(-1, "uint32")


def test_request_length():
    assert request_length(b"\x01") is None
    assert request_length(b"\x01\x03") == 8
    assert request_length(b"\x01\x10\x00\x0a\x00\x02") is None
    assert request_length(b"\x01\x10\x00\x0a\x00\x02\x04") == 13
    assert request_length(b"\x01\x2b") == -1


@pytest.mark.parametrize("text, value", [("+0012.3456", 12.3456), ("-01.2345", -1.2345),
                                         ("+12.3", 12.3), ("0.5", 0.5), ("- 3.25", -3.25),
                                         ("+123456", 123456.0)])
def test_keyence_values_of_any_width(text, value):
    assert parse_value(text) == Reading(value, "ok")


@pytest.mark.parametrize("text, status", [("+FFFFFFF", "over-range+"),
                                          ("-FFFFFFF", "over-range-"),
                                          ("XXXXXXXX", "invalid")])
def test_keyence_markers_are_never_numbers(text, status):
    r = parse_value(text)
    assert r.value is None and r.status == status and not r.valid


@pytest.mark.parametrize("code, meaning", [(50, "command error"), (51, "status error"),
                                           (60, "command length"), (61, "parameter count"),
                                           (62, "parameter range"), (88, "timeout"),
                                           (99, "other")])
def test_keyence_error_codes(code, meaning):
    with pytest.raises(KeyenceError, match=f"ER,MS,{code}.*{meaning}") as info:
        parse_reply(f"ER,MS,{code}", "MS,01")
    assert info.value.code == code


@pytest.mark.parametrize("code, meaning", [(0, "command error"), (1, "status error"),
                                           (20, "command length"), (21, "parameter count"),
                                           (22, "invalid parameter"), (88, "timeout")])
def test_keyence_g3000_error_codes(code, meaning):
    with pytest.raises(KeyenceError, match=f"ER,M1,{code:02d}.*{meaning}"):
        parse_reply(f"ER,M1,{code:02d}", "M1", "keyence-lk-g3000")


def test_keyence_replies():
    assert parse_reply("MS,01,+0012.3456", "MS,01") == [Reading(12.3456)]
    assert parse_reply("M1,+01.2345", "M1") == [Reading(1.2345)]
    assert [r.status for r in parse_reply("M0,+01.2345,-FFFFFFF", "M0")] == \
        ["ok", "over-range-"]
    for bad in ("MS,02,+0012.3456", "MS,01,+00q2.3456", "ER,MS", "garbage"):
        with pytest.raises(ReplyError):
            parse_reply(bad, "MS,01")


def test_format_value():
    assert format_value(12.3456) == "+0012.3456"
    assert format_value(-0.00004) == "-0000.0000"
    assert parse_value(format_value(-45.12346)).value == -45.1235
