"""Sensor drivers: KEYENCE LK-G5000 / LK-HD (``MS,01`` -> ``MS,01,+0012.3456``) and
LK-G3000 (``M1`` -> ``M1,+01.2345``), ASCII, CR-terminated.

:meth:`KeyenceSensor.read` returns a :class:`~pihyst.rig._codecs.Reading` in
micrometres: a value, or none with the status 'over-range+', 'over-range-' or 'invalid'
(never a number for those). ``ER,<cmd>,<code>`` raises
:class:`~pihyst.rig._codecs.KeyenceError`; a missing, cut or garbled reply raises
:class:`~pihyst.rig._ports.RigError` or :class:`~pihyst.rig._codecs.ReplyError`.
"""

from typing import Any

from pihyst.rig._codecs import Reading, ReplyError, parse_reply
from pihyst.rig._ports import close_port, open_port, port_errors, read_line


class KeyenceSensor:
    """A KEYENCE LK controller on an open port (:func:`open_sensor` opens it).

    Parameters
    ----------
    port : serial.SerialBase
        The open port (pyserial, or anything with its ``write``, ``read_until`` and
        ``reset_input_buffer``).
    cfg : SensorConfig
        Protocol, output, ``scale_um`` (micrometres per reported unit) and ``sign``.

    Examples
    --------
    >>> from pihyst.rig import KeyenceSensor, SensorConfig, open_port
    >>> port = open_port("loop://", 115200, 0.1, "sensor")   # the reply is the request
    >>> sensor = KeyenceSensor(port, SensorConfig(port="loop://"))
    >>> sensor.command
    'MS,01'
    >>> sensor.close()
    """

    def __init__(self, port: Any, cfg: Any) -> None:
        self.cfg = cfg
        self.port = port
        if cfg.protocol == "keyence-lk-g3000":
            self.command = f"M{cfg.output}"
        else:
            self.command = f"MS,{cfg.output:02d}"
        self._request = (self.command + "\r").encode("ascii")

    @port_errors("sensor")
    def read(self) -> Reading:
        """One measurement of the configured output, in micrometres.

        Returns
        -------
        Reading
            ``sign * scale_um *`` the reported value (µm), or no value with the status
            ``"over-range+"``, ``"over-range-"`` or ``"invalid"``.

        Raises
        ------
        KeyenceError
            The controller answered ``ER,<command>,<code>``.
        ReplyError
            A garbled reply, or one that does not answer the command.
        RigError
            No reply (:class:`NoReplyError`), a reply cut short, or a port error.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.set_voltage(50.0); rig.clock.sleep(1.0)
        ...     reading = rig.sensor.read()
        >>> reading.status, round(reading.value)
        ('ok', 10)
        """
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

    def close(self) -> None:
        """Close the port.

        Examples
        --------
        >>> from pihyst.rig import SensorConfig, open_sensor
        >>> sensor = open_sensor(SensorConfig(port="loop://"))
        >>> sensor.close(); sensor.port.is_open
        False
        """
        close_port(self.port)

    def describe(self) -> str:
        """One line for the log: the model, port, output, scale and sign.

        Returns
        -------
        str
            The line.

        Examples
        --------
        >>> from pihyst.rig import SensorConfig, open_sensor
        >>> sensor = open_sensor(SensorConfig(port="loop://", protocol="keyence-lk-g3000"))
        >>> sensor.describe()
        "KEYENCE LK-G3000 at loop://, output 1 ('M1'), 1 µm per unit, sign +1"
        >>> sensor.close()
        """
        return (f"KEYENCE {self.cfg.protocol[8:].upper()} at {self.cfg.port}, output "
                f"{self.cfg.output} ({self.command!r}), {self.cfg.scale_um:g} µm per unit, "
                f"sign {self.cfg.sign:+d}")


def open_sensor(cfg: Any, port: Any = None) -> KeyenceSensor:
    """The driver of the sensor of ``cfg``, on ``port`` or on ``cfg.port`` opened.

    Parameters
    ----------
    cfg : SensorConfig
        The sensor's configuration.
    port : serial.SerialBase or None
        An open pyserial-like port; None: open ``cfg.port`` (a device or a pyserial URL).

    Returns
    -------
    KeyenceSensor
        The driver.

    Raises
    ------
    RigError
        The port does not open.

    Examples
    --------
    >>> from pihyst.rig import SensorConfig, open_sensor
    >>> sensor = open_sensor(SensorConfig(port="loop://", output=3))
    >>> sensor.command
    'MS,03'
    >>> sensor.close()
    """
    if port is None:
        port = open_port(cfg.port, cfg.baudrate, cfg.timeout_s, "sensor", cfg.parity,
                         cfg.stopbits)
    return KeyenceSensor(port, cfg)
