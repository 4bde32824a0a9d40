"""Sensor drivers: KEYENCE LK-G5000 / LK-HD (``MS,01`` -> ``MS,01,+0012.3456``) and
LK-G3000 (``M1`` -> ``M1,+01.2345``), ASCII, CR-terminated.

:meth:`KeyenceSensor.read` returns a :class:`~pihyst.rig._codecs.Reading` in
micrometres: a value, or none with the status 'over-range+', 'over-range-' or 'invalid'
(never a number for those). ``ER,<cmd>,<code>`` raises
:class:`~pihyst.rig._codecs.KeyenceError`; a missing, cut or garbled reply raises
:class:`~pihyst.rig._ports.RigError` or :class:`~pihyst.rig._codecs.ReplyError`.
"""

from pihyst.rig._codecs import Reading, ReplyError, parse_reply
from pihyst.rig._ports import close_port, open_port, port_errors, read_line


class KeyenceSensor:
    """A KEYENCE LK controller; ``cfg`` is a :class:`~pihyst.rig.SensorConfig`
    (protocol, output, ``scale_um`` micrometres per reported unit, ``sign``)."""

    def __init__(self, port, cfg):
        self.cfg = cfg
        self.port = port
        if cfg.protocol == "keyence-lk-g3000":
            self.command = f"M{cfg.output}"
        else:
            self.command = f"MS,{cfg.output:02d}"
        self._request = (self.command + "\r").encode("ascii")

    @port_errors("sensor")
    def read(self):
        """One measurement of the configured output, in micrometres."""
        self.port.reset_input_buffer()
        self.port.write(self._request)
        raw = read_line(self.port, b"\r", "sensor")
        try:
            text = raw[:-1].decode("ascii")
        except UnicodeDecodeError:
            raise ReplyError(f"sensor: garbled reply {raw!r}") from None
        values = parse_reply(text, self.command, self.cfg.protocol)
        if len(values) != 1:
            raise ReplyError(f"sensor: expected one value in {text!r}")
        reading = values[0]
        if not reading.valid:
            return reading
        # y_um = sign * scale_um * reported
        return Reading(self.cfg.sign * self.cfg.scale_um * reading.value, "ok")

    def close(self):
        close_port(self.port)

    def describe(self):
        return (f"KEYENCE {self.cfg.protocol[8:].upper()} at {self.cfg.port}, output "
                f"{self.cfg.output} ({self.command!r}), {self.cfg.scale_um:g} µm per unit, "
                f"sign {self.cfg.sign:+d}")


def open_sensor(cfg, port=None):
    if port is None:
        port = open_port(cfg.port, cfg.baudrate, cfg.timeout_s, "sensor", cfg.parity,
                         cfg.stopbits)
    return KeyenceSensor(port, cfg)
