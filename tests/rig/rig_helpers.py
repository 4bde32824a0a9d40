"""Shared pieces of the rig tests: configurations and a scripted serial port."""

from pihyst.rig import parse_config

BASE = {
    "rig": {"rate_hz": 20.0, "u_min": 0.0, "u_max": 150.0, "slew_V_per_s": 200.0},
    "supply": {"port": "pihystsim://supply", "baudrate": 19200, "protocol": "modbus-rtu",
               "address": 1, "setpoint_register": 10, "setpoint_format": "float32",
               "word_order": "big", "scale": 1.0, "output_register": 9,
               "readback_register": 12},
    "sensor": {"port": "pihystsim://sensor", "baudrate": 115200,
               "protocol": "keyence-lk-g5000", "output": 1, "scale_um": 1.0, "sign": 1},
    "emulator": {"plant": "paper-beam", "seed": 0},
}


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"').replace("\r", "\\r") \
            .replace("\n", "\\n") + '"'
    return repr(v)


def config_text(**sections):
    """TOML of BASE with ``sections`` (dicts) merged in; a value None drops the key."""
    lines = []
    for name, base in BASE.items():
        values = {**base, **sections.get(name, {})}
        lines.append(f"[{name}]")
        lines += [f"{k} = {toml_value(v)}" for k, v in values.items() if v is not None]
    return "\n".join(lines) + "\n"


def make_config(**sections):
    return parse_config(config_text(**sections), source="test.toml")


class ScriptedPort:
    """A pyserial-like port that asserts every byte written and plays the scripted replies:
    ``script`` is a list of (expected bytes written, reply bytes)."""

    def __init__(self, script, timeout=0.1):
        self.script = list(script)
        self.timeout = timeout
        self.baudrate = 19200
        self.port = "scripted"
        self.is_open = True
        self._rx = b""

    def write(self, data):
        assert self.script, f"unexpected write {bytes(data)!r}"
        expected, reply = self.script.pop(0)
        assert bytes(data) == expected, f"sent {bytes(data)!r}, expected {expected!r}"
        self._rx += reply
        return len(data)

    def read(self, size=1):
        out, self._rx = self._rx[:size], self._rx[size:]
        return out

    def read_until(self, expected=b"\n", size=None):
        i = self._rx.find(expected)
        n = len(self._rx) if i < 0 else i + len(expected)
        return self.read(n)

    def reset_input_buffer(self):
        self._rx = b""

    def reset_output_buffer(self):
        pass

    def flush(self):
        pass

    def open(self):
        self.is_open = True

    def close(self):
        self.is_open = False

    def done(self):
        assert not self.script, f"expected more exchanges: {self.script}"
        assert not self._rx, f"unread reply bytes {self._rx!r}"
