"""Bytes of the instruments' protocols: Modbus RTU frames (CRC-16/Modbus, register
values) and KEYENCE LK replies. Pure functions, used by the drivers' checks and by the
emulated instruments (the drivers' own Modbus frames are built by minimalmodbus).
"""

import re
import struct
from collections.abc import Sequence
from dataclasses import dataclass

from pihyst.exceptions import InvalidArgumentError

# ----------------------------------------------------------------------------- Modbus RTU


def crc16_modbus(data: bytes) -> int:
    """CRC-16/Modbus: reflected polynomial 0xA001, initial value 0xFFFF.

    Parameters
    ----------
    data : bytes
        The bytes the CRC covers (a Modbus RTU frame without its CRC).

    Returns
    -------
    int
        The CRC, 0..0xFFFF (sent low byte first).

    Examples
    --------
    >>> from pihyst.rig import crc16_modbus
    >>> hex(crc16_modbus(b"123456789"))       # the catalogue check value
    '0x4b37'
    """
    crc = 0xFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc


def with_crc(frame: bytes) -> bytes:
    """The frame followed by its CRC, low byte first (as on the wire)."""
    return bytes(frame) + struct.pack("<H", crc16_modbus(frame))


def crc_ok(frame: bytes) -> bool:
    """Whether the last two bytes of ``frame`` are the CRC of the rest.

    Parameters
    ----------
    frame : bytes
        A Modbus RTU frame with its CRC (low byte first).

    Returns
    -------
    bool
        True if the CRC is right (False for a frame shorter than 4 bytes).

    Examples
    --------
    >>> from pihyst.rig import crc_ok
    >>> crc_ok(bytes.fromhex("010300000001840a")), crc_ok(bytes.fromhex("010300000001840b"))
    (True, False)
    """
    return len(frame) >= 4 and struct.pack("<H", crc16_modbus(frame[:-2])) == frame[-2:]


def register_count(fmt: str) -> int:
    """Registers a setpoint of format ``fmt`` occupies."""
    return 1 if fmt == "uint16" else 2


def encode_registers(value: float, fmt: str, word_order: str = "big") -> list[int]:
    """Register words (16-bit ints) holding ``value`` (already in register units).

    Integers are rounded; ``word_order`` 'little' puts the low word first (CDAB).

    Examples
    --------
    >>> encode_registers(150.0, "float32")
    [17174, 0]
    >>> encode_registers(100000, "uint32", "little")
    [34464, 1]
    """
    if fmt == "float32":
        raw = struct.pack(">f", value)
    elif fmt == "uint32":
        n = int(round(value))
        if not 0 <= n <= 0xFFFFFFFF:
            raise InvalidArgumentError(f"{value:g} does not fit a uint32 register pair")
        raw = struct.pack(">I", n)
    elif fmt == "uint16":
        n = int(round(value))
        if not 0 <= n <= 0xFFFF:
            raise InvalidArgumentError(f"{value:g} does not fit a uint16 register")
        return [n]
    else:
        raise InvalidArgumentError(f"unknown register format {fmt!r}")
    words = [raw[0] << 8 | raw[1], raw[2] << 8 | raw[3]]
    return words[::-1] if word_order == "little" else words


def decode_registers(words: Sequence[int], fmt: str, word_order: str = "big") -> float:
    """Inverse of :func:`encode_registers`."""
    if fmt == "uint16":
        return float(words[0])
    hi, lo = (words[1], words[0]) if word_order == "little" else (words[0], words[1])
    raw = struct.pack(">HH", hi, lo)
    return float(struct.unpack(">f" if fmt == "float32" else ">I", raw)[0])


#: Modbus exception codes (Modbus Application Protocol v1.1b3, section 7).
MODBUS_EXCEPTIONS = {1: "illegal function", 2: "illegal data address",
                     3: "illegal data value", 4: "server device failure"}


def request_length(buffer: bytes | bytearray) -> int | None:
    """Length of the Modbus RTU request at the start of ``buffer`` for the function codes
    a supply needs (03 read holding registers, 06 write single register, 16 write multiple
    registers), None while incomplete, -1 for a function code this module does not know."""
    if len(buffer) < 2:
        return None
    function = buffer[1]
    if function in (3, 6):
        return 8
    if function == 16:
        return None if len(buffer) < 7 else 9 + buffer[6]
    return -1


# ----------------------------------------------------------------------------- KEYENCE LK

#: ER codes: LK-G5000 / LK-HD communication manual, and the LK-G (LK-G3000) user manual.
KEYENCE_ERRORS = {
    "keyence-lk-g5000": {50: "command error", 51: "status error", 60: "command length error",
                         61: "parameter count error", 62: "parameter range error",
                         88: "timeout error", 99: "other error"},
    "keyence-lk-g3000": {0: "command error", 1: "status error", 20: "command length error",
                         21: "parameter count error", 22: "invalid parameter error",
                         88: "timeout error", 99: "other error"},
}

#: The code each dialect answers for an unknown command and for a bad parameter.
KEYENCE_COMMAND_ERROR = {"keyence-lk-g5000": 50, "keyence-lk-g3000": 0}
KEYENCE_PARAMETER_ERROR = {"keyence-lk-g5000": 62, "keyence-lk-g3000": 22}


class KeyenceError(IOError):
    """The controller answered ``ER,<command>,<code>``.

    Parameters
    ----------
    command : str
        The command it refused (as in the reply).
    code : int
        The error code of the reply.
    dialect : str
        ``"keyence-lk-g5000"`` or ``"keyence-lk-g3000"``: what the code means.

    Examples
    --------
    >>> from pihyst.rig import KeyenceError
    >>> print(KeyenceError("MS", 62))
    sensor error ER,MS,62 (parameter range error)
    """

    def __init__(self, command: str, code: int, dialect: str = "keyence-lk-g5000") -> None:
        self.command, self.code = command, code
        meaning = KEYENCE_ERRORS[dialect].get(code, "unknown error code")
        super().__init__(f"sensor error ER,{command},{code:02d} ({meaning})")


class ReplyError(IOError):
    """A reply that is not what the protocol allows (garbled, truncated, wrong command).

    Examples
    --------
    >>> from pihyst.rig import ReplyError
    >>> from pihyst.rig._codecs import parse_reply
    >>> try:
    ...     parse_reply("MS,0?,+0001.0000", "MS,01")
    ... except ReplyError as err:
    ...     print(err)
    reply 'MS,0?,+0001.0000' does not answer 'MS,01'
    """


@dataclass(frozen=True)
class Reading:
    """One sensor value, as the sensor reported it.

    Parameters
    ----------
    value : float or None
        The value in the sensor's units; None unless ``status`` is ``"ok"``.
    status : str
        ``"ok"``, ``"over-range+"``, ``"over-range-"`` or ``"invalid"``.

    Examples
    --------
    >>> from pihyst.rig import Reading
    >>> Reading(12.5).valid, Reading(None, "invalid").valid
    (True, False)
    """

    value: float | None = None
    status: str = "ok"

    @property
    def valid(self) -> bool:
        """True if the status is ``"ok"``."""
        return self.status == "ok"


_NUMBER = re.compile(r"[+-] *\d+(?:\.\d+)?|\d+(?:\.\d+)?")


def parse_value(field: str) -> Reading:
    """One value field of a Keyence reply: a signed decimal of any width, or the markers
    ``+FFFFFFF`` / ``-FFFFFFF`` (over-range) and ``XXXXXXXX`` (invalid, alarm).

    Examples
    --------
    >>> parse_value("+0012.3456"), parse_value("-FFFFFFF").status
    (Reading(value=12.3456, status='ok'), 'over-range-')
    """
    field = field.strip()
    if re.fullmatch(r"[+-]?F{7,8}", field):
        return Reading(None, "over-range-" if field.startswith("-") else "over-range+")
    if re.fullmatch(r"X{7,8}", field):
        return Reading(None, "invalid")
    if not _NUMBER.fullmatch(field):
        raise ReplyError(f"sensor value {field!r} is not a number")
    return Reading(float(field.replace(" ", "")), "ok")


def format_value(value: float, decimals: int = 4, width: int | None = None) -> str:
    """A value as the controller prints it: sign, zero-padded digits, ``decimals`` places;
    ``width`` (digits and point) defaults to 4 integer digits.

    Examples
    --------
    >>> format_value(12.3456), format_value(-1.5, decimals=2, width=5)
    ('+0012.3456', '-01.50')
    """
    if width is None:
        width = 4 + (decimals + 1 if decimals else 0)
    return f"{value:+0{width + 1}.{decimals}f}"


def parse_reply(reply: str, command: str, dialect: str = "keyence-lk-g5000") -> list[Reading]:
    """Values of a reply to ``command`` (without CR): ``MS,01,+0012.3456`` to ``MS,01``
    (LK-G5000) or ``M1,+01.2345`` to ``M1`` (LK-G3000). Raises :class:`KeyenceError`
    for ``ER,...`` and :class:`ReplyError` for anything else unexpected.

    Examples
    --------
    >>> parse_reply("M0,+01.2345,XXXXXXXX", "M0")[1].status
    'invalid'
    """
    if reply.startswith("ER,"):
        parts = reply.split(",")
        if len(parts) == 3 and parts[2].strip().isdigit():
            raise KeyenceError(parts[1], int(parts[2]), dialect)
        raise ReplyError(f"malformed error reply {reply!r}")
    prefix = command + ","
    if not reply.startswith(prefix):
        raise ReplyError(f"reply {reply!r} does not answer {command!r}")
    fields = reply[len(prefix):].split(",")
    return [parse_value(f) for f in fields]
