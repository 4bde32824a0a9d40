"""Supply drivers: one small interface (``set_voltage``, ``read_voltage``, ``output_on``,
``output_off``, ``close``) over Modbus RTU (minimalmodbus) or an ASCII line protocol.

Errors are ``OSError`` subclasses: :class:`~pihyst.rig._ports.RigError`, minimalmodbus's
``ModbusException`` (no answer, bad CRC, exception reply) and pyserial's
``SerialException``. The controller counts them as communication errors. A setpoint the
supply may not be sent (not finite, negative, more than its register holds) is refused
before sending with an :class:`~pihyst.exceptions.InvalidArgumentError`
(``check_setpoint``); the controller checks the rig's limits so before a run.
"""

import math
import re
from typing import Any

import minimalmodbus

from pihyst.exceptions import InvalidArgumentError
from pihyst.rig._clock import WallClock
from pihyst.rig._codecs import register_count
from pihyst.rig._ports import RigError, close_port, open_port, port_errors, read_line

_BYTEORDER = {"big": minimalmodbus.BYTEORDER_BIG,             # ABCD: high word first
              "little": minimalmodbus.BYTEORDER_LITTLE_SWAP}  # CDAB: low word first


class _Instrument(minimalmodbus.Instrument):
    """minimalmodbus builds and checks the frames (CRC, function codes, exception replies,
    number formats); this transport writes and reads them with an injectable clock, so the
    3.5-character silence between frames also holds in virtual time."""

    def __init__(self, port: Any, address: int, clock: Any) -> None:
        super().__init__(port, address)
        self._clock = clock
        self._last_read = -math.inf

    @port_errors("supply")
    def _communicate(self, request: bytes, number_of_bytes_to_read: int) -> bytes:
        # t_silence = 3.5 characters of 11 bits, at least 1.75 ms (Modbus over serial line)
        silence = max(3.5 * 11 / self.serial.baudrate, 0.00175)
        wait = self._last_read + silence - self._clock.now()
        if wait > 0:
            self._clock.sleep(wait)
        self.serial.reset_input_buffer()
        self.serial.write(request)
        answer = self.serial.read(number_of_bytes_to_read)
        self._last_read = self._clock.now()
        if not answer:
            raise minimalmodbus.NoResponseError("no answer from the supply within "
                                                f"{self.serial.timeout:g} s")
        return answer


def _check_volts(volts: object) -> float:
    """``volts`` as a float a unipolar supply may be sent; InvalidArgumentError saying why
    not otherwise."""
    try:
        volts = float(volts)  # type: ignore[arg-type]  # anything: refused below if not
    except (TypeError, ValueError):
        raise InvalidArgumentError(f"supply setpoint: refusing to send {volts!r:.40}, which "
                                   f"is not a number of volts") from None
    if not math.isfinite(volts):
        raise InvalidArgumentError(f"supply setpoint: refusing to send a non-finite setpoint "
                                   f"({volts})")
    if volts < 0:
        raise InvalidArgumentError(f"supply setpoint: refusing to send a negative setpoint "
                                   f"({volts:g} V) to a unipolar supply")
    return volts


class ModbusRtuSupply:
    """A supply on Modbus RTU with the register map of ``cfg`` (a
    :class:`~pihyst.rig.SupplyConfig`): the setpoint in volts x ``scale`` as uint16,
    uint32 or float32 (two registers in ``word_order``), optional output-enable register
    (1 on, 0 off) and readback register (same format and scale).

    Parameters
    ----------
    port : serial.SerialBase
        The open port (:func:`open_supply` opens it).
    cfg : SupplyConfig
        The register map.
    clock : WallClock or VirtualClock
        The clock of the 3.5-character silence between frames.

    Examples
    --------
    >>> from pihyst.rig import Rig, parse_config
    >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
    ...                       'readback_register = 12\\noutput_register = 9\\n'
    ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
    >>> with Rig(config) as rig:
    ...     supply = rig.supply
    ...     supply.output_on(); supply.set_voltage(42.5)
    ...     volts = supply.read_voltage()
    ...     supply.set_voltage(0.0); supply.output_off()
    >>> type(supply).__name__, volts
    ('ModbusRtuSupply', 42.5)
    """

    def __init__(self, port: Any, cfg: Any, clock: Any = WallClock) -> None:
        self.cfg = cfg
        self.port = port
        self.instrument = _Instrument(port, cfg.address, clock)
        self._byteorder = _BYTEORDER[cfg.word_order]

    def _write(self, register: int, value: float) -> None:
        c = self.cfg
        if c.setpoint_format == "float32":
            self.instrument.write_float(register, value, 2, self._byteorder)
        elif c.setpoint_format == "uint32":
            self.instrument.write_long(register, int(round(value)), False, self._byteorder)
        else:
            self.instrument.write_register(register, int(round(value)), 0, 6)

    def check_setpoint(self, volts: float) -> float:
        """The register value of ``volts``, if the supply may be sent it.

        Parameters
        ----------
        volts : float
            The setpoint (V).

        Returns
        -------
        float
            ``volts * scale``, in register units (rounded when sent as an integer).

        Raises
        ------
        InvalidArgumentError
            ``volts`` is not a finite number, is negative, or is more than the setpoint
            register holds.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
        ...                       'scale = 100\\nsetpoint_format = "uint16"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     print(rig.supply.check_setpoint(12.5))
        ...     rig.supply.check_setpoint(700.0)
        Traceback (most recent call last):
        ...
        pihyst.exceptions.InvalidArgumentError: supply setpoint: 700 V is 70000 register ...
        """
        volts = _check_volts(volts)
        counts = volts * self.cfg.scale
        limit = {"uint16": 0xFFFF, "uint32": 0xFFFFFFFF}.get(self.cfg.setpoint_format)
        if limit is not None and round(counts) > limit:
            raise InvalidArgumentError(
                f"supply setpoint: {volts:g} V is {counts:g} register units at [supply] "
                f"scale {self.cfg.scale:g}: more than a {self.cfg.setpoint_format} setpoint "
                f"register holds ({limit})")
        return counts

    def set_voltage(self, volts: float) -> None:
        """Write the setpoint register(s).

        Parameters
        ----------
        volts : float
            The setpoint (V), checked by :meth:`check_setpoint` first.

        Raises
        ------
        InvalidArgumentError
            A setpoint the supply may not be sent (nothing is sent).
        OSError
            A communication error (minimalmodbus's ``ModbusException``, :class:`RigError`).

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
        ...                       'readback_register = 12\\noutput_register = 9\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.set_voltage(10.0)
        ...     rig.emulators.supply_state.last_setpoint_V
        10.0
        """
        self._write(self.cfg.setpoint_register, self.check_setpoint(volts))

    @property
    def has_readback(self) -> bool:
        """True if a readback register is configured."""
        return self.cfg.readback_register is not None

    def read_voltage(self) -> float | None:
        """The supply's readback.

        Returns
        -------
        float or None
            The output voltage it reports (V); None if no readback register is
            configured.

        Raises
        ------
        OSError
            A communication error.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
        ...                       'readback_register = 12\\noutput_register = 9\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.output_on(); rig.supply.set_voltage(25.0)
        ...     rig.supply.read_voltage()
        25.0
        """
        c = self.cfg
        if c.readback_register is None:
            return None
        if c.setpoint_format == "float32":
            counts = self.instrument.read_float(c.readback_register, 3, 2, self._byteorder)
        elif c.setpoint_format == "uint32":
            counts = self.instrument.read_long(c.readback_register, 3, False, self._byteorder)
        else:
            counts = self.instrument.read_register(c.readback_register, 0, 3)
        return counts / c.scale

    def _output(self, on: bool) -> None:
        if self.cfg.output_register is not None:
            self.instrument.write_register(self.cfg.output_register, int(on), 0, 6)

    def output_on(self) -> None:
        """Switch the output on (writes 1 to the output register, if there is one).

        Raises
        ------
        OSError
            A communication error.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
        ...                       'readback_register = 12\\noutput_register = 9\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.set_voltage(5.0); before = rig.emulators.supply_state.output_V
        ...     rig.supply.output_on(); after = rig.emulators.supply_state.output_V
        >>> before, after
        (0.0, 5.0)
        """
        self._output(True)

    def output_off(self) -> None:
        """Switch the output off (writes 0 to the output register, if there is one).

        Raises
        ------
        OSError
            A communication error.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
        ...                       'readback_register = 12\\noutput_register = 9\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.output_on(); rig.supply.set_voltage(5.0)
        ...     rig.supply.output_off()
        ...     rig.emulators.supply_state.output_V
        0.0
        """
        self._output(False)

    @property
    def has_watchdog(self) -> bool:
        """True if the configuration names the supply's communication watchdog."""
        return self.cfg.watchdog_s is not None and self.cfg.watchdog_register is not None

    def arm_watchdog(self) -> None:
        """Output off after ``watchdog_s`` without a request (every request feeds it).

        Raises
        ------
        InvalidArgumentError
            No watchdog is configured.
        OSError
            A communication error.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\nwatchdog_s = 1.0\\n'
        ...                       'watchdog_register = 20\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.arm_watchdog()
        ...     rig.emulators.supply_state.watchdog_s
        1.0
        """
        c = self.cfg
        if c.watchdog_register is None or c.watchdog_s is None:
            raise InvalidArgumentError("supply: no watchdog configured ([supply] watchdog_s "
                                       "and watchdog_register)")
        self.instrument.write_register(c.watchdog_register,
                                       int(round(c.watchdog_s * c.watchdog_scale)), 0, 6)

    def disarm_watchdog(self) -> None:
        """Disarm the supply's watchdog (writes 0 to its register).

        Raises
        ------
        InvalidArgumentError
            No watchdog is configured.
        OSError
            A communication error.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\nwatchdog_s = 1.0\\n'
        ...                       'watchdog_register = 20\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.arm_watchdog(); rig.supply.disarm_watchdog()
        ...     rig.emulators.supply_state.watchdog_s
        0.0
        """
        if self.cfg.watchdog_register is None:
            raise InvalidArgumentError("supply: no watchdog configured ([supply] "
                                       "watchdog_register)")
        self.instrument.write_register(self.cfg.watchdog_register, 0, 0, 6)

    def close(self) -> None:
        """Close the port.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
        ...                       'readback_register = 12\\noutput_register = 9\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> rig = Rig(config)
        >>> rig.supply.close(); rig.supply.port.is_open
        False
        >>> rig.close()
        """
        close_port(self.port)

    def describe(self) -> str:
        """One line for the log: the port, slave address and register map.

        Returns
        -------
        str
            The line.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
        ...                       'readback_register = 12\\noutput_register = 9\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     print(rig.supply.describe()[:60])
        Modbus RTU supply at pihystsim://supply (slave 1, setpoint r
        """
        c = self.cfg
        return (f"Modbus RTU supply at {c.port} (slave {c.address}, setpoint register "
                f"{c.setpoint_register} as {c.setpoint_format}, {register_count(c.setpoint_format)}"
                f" register(s), word order {c.word_order}, {c.scale:g} units per volt)")


class AsciiSupply:
    """A supply with an ASCII line protocol: ``set_command`` ('VOLT {volts:.2f}'),
    ``query_command`` ('MEAS:VOLT?'), ``output_on_command``/``output_off_command``, each
    followed by ``terminator``. With ``echo`` the device repeats each command; with a
    ``prompt`` (e.g. '*') it acknowledges a set command (and may put it before a query's
    reply). The number in a query's reply line is the first match of
    ``reply_pattern``.

    Parameters
    ----------
    port : serial.SerialBase
        The open port (:func:`open_supply` opens it).
    cfg : SupplyConfig
        The commands and the line protocol.
    clock : WallClock or VirtualClock
        Unused (the interface of :class:`ModbusRtuSupply`).

    Examples
    --------
    >>> from pihyst.rig import Rig, parse_config
    >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\nprotocol = "ascii"\\n'
    ...                       'query_command = "MEAS:VOLT?"\\n'
    ...                       'output_on_command = "OUTP ON"\\n'
    ...                       'output_off_command = "OUTP OFF"\\n'
    ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
    >>> with Rig(config) as rig:
    ...     rig.supply.output_on(); rig.supply.set_voltage(30.0)
    ...     rig.supply.read_voltage()
    30.0
    """

    def __init__(self, port: Any, cfg: Any, clock: Any = WallClock) -> None:
        self.cfg = cfg
        self.port = port
        self._term = cfg.terminator.encode("ascii")
        self._prompt = cfg.prompt.encode("ascii")
        self._number = re.compile(cfg.reply_pattern)

    @port_errors("supply")
    def _command(self, text: str, query: bool = False) -> str:
        """Send one command; returns the reply line of a query (prompt and blanks
        stripped). A set command with a prompt is acknowledged by the prompt alone:
        anything before it is an error message."""
        c, port = self.cfg, self.port
        port.reset_input_buffer()
        sent = text.encode("ascii") + self._term
        port.write(sent)
        if c.echo:
            echo = read_line(port, self._term, "supply")
            # the prompt that ends a query's reply may come after this command went out
            # (an MDT693B answers 'vlimit?' with '*[ 100]\r*'): it precedes the echo
            while self._prompt and echo.startswith(self._prompt) and echo != sent:
                echo = echo[len(self._prompt):]
            if echo != sent:
                raise RigError(f"supply: expected the echo {sent!r}, got {echo!r}")
        raw = b""
        if query:
            raw = read_line(port, self._term, "supply")[:-len(self._term)]
        elif self._prompt:
            raw = read_line(port, self._prompt, "supply")[:-len(self._prompt)]
        reply = raw.decode("ascii", "replace").strip()
        if self._prompt:
            reply = reply.lstrip(c.prompt).strip()
        if reply and (not query or "ERR" in reply.upper()):
            raise RigError(f"supply: {text!r} answered {reply!r}")
        return reply

    def check_setpoint(self, volts: float) -> float:
        """``volts`` as it is sent, if the supply may be sent it.

        Parameters
        ----------
        volts : float
            The setpoint (V).

        Returns
        -------
        float
            The setpoint (V).

        Raises
        ------
        InvalidArgumentError
            ``volts`` is not a finite number, or is negative.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\nprotocol = "ascii"\\n'
        ...                       'query_command = "MEAS:VOLT?"\\n'
        ...                       'output_on_command = "OUTP ON"\\n'
        ...                       'output_off_command = "OUTP OFF"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.check_setpoint(-1.0)
        Traceback (most recent call last):
        ...
        pihyst.exceptions.InvalidArgumentError: supply setpoint: refusing to send a negative ...
        """
        return _check_volts(volts)

    def set_voltage(self, volts: float) -> None:
        """Send ``set_command`` with the setpoint.

        Parameters
        ----------
        volts : float
            The setpoint (V), checked by :meth:`check_setpoint` first.

        Raises
        ------
        InvalidArgumentError
            A setpoint the supply may not be sent (nothing is sent).
        RigError
            No reply, a wrong echo, or an error message from the supply.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\nprotocol = "ascii"\\n'
        ...                       'query_command = "MEAS:VOLT?"\\n'
        ...                       'output_on_command = "OUTP ON"\\n'
        ...                       'output_off_command = "OUTP OFF"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.set_voltage(12.0)
        ...     rig.emulators.supply_state.last_setpoint_V
        12.0
        """
        self._command(self.cfg.set_command.format(volts=self.check_setpoint(volts)))

    @property
    def has_readback(self) -> bool:
        """True if a query command is configured."""
        return self.cfg.query_command is not None

    def read_voltage(self) -> float | None:
        """The supply's readback: ``query_command``, and the number in its reply.

        Returns
        -------
        float or None
            The output voltage it reports (V); None without a query command.

        Raises
        ------
        RigError
            No reply, or no number in it.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\nprotocol = "ascii"\\n'
        ...                       'query_command = "MEAS:VOLT?"\\n'
        ...                       'output_on_command = "OUTP ON"\\n'
        ...                       'output_off_command = "OUTP OFF"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.read_voltage()
        0.0
        """
        if self.cfg.query_command is None:
            return None
        reply = self._command(self.cfg.query_command, query=True)
        m = self._number.search(reply)
        if not m:
            raise RigError(f"supply: no number in the reply {reply!r} to "
                           f"{self.cfg.query_command!r}")
        return float(m.group(0))

    def output_on(self) -> None:
        """Send ``output_on_command`` (if there is one).

        Raises
        ------
        RigError
            No reply, a wrong echo, or an error message from the supply.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\nprotocol = "ascii"\\n'
        ...                       'query_command = "MEAS:VOLT?"\\n'
        ...                       'output_on_command = "OUTP ON"\\n'
        ...                       'output_off_command = "OUTP OFF"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.set_voltage(8.0); rig.supply.output_on()
        ...     rig.emulators.supply_state.output_V
        8.0
        """
        if self.cfg.output_on_command:
            self._command(self.cfg.output_on_command)

    def output_off(self) -> None:
        """Send ``output_off_command`` (if there is one).

        Raises
        ------
        RigError
            No reply, a wrong echo, or an error message from the supply.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\nprotocol = "ascii"\\n'
        ...                       'query_command = "MEAS:VOLT?"\\n'
        ...                       'output_on_command = "OUTP ON"\\n'
        ...                       'output_off_command = "OUTP OFF"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.output_on(); rig.supply.set_voltage(8.0)
        ...     rig.supply.output_off()
        ...     rig.emulators.supply_state.output_V
        0.0
        """
        if self.cfg.output_off_command:
            self._command(self.cfg.output_off_command)

    @property
    def has_watchdog(self) -> bool:
        """True if the configuration names the supply's communication watchdog."""
        return self.cfg.watchdog_s is not None and self.cfg.watchdog_command is not None

    def arm_watchdog(self) -> None:
        """Output off after ``watchdog_s`` without a command (every command feeds it).

        Raises
        ------
        InvalidArgumentError
            No watchdog is configured.
        RigError
            No reply, a wrong echo, or an error message from the supply.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\nprotocol = "ascii"\\n'
        ...                       'watchdog_s = 1.0\\nwatchdog_command = "WDOG {seconds:.1f}"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.arm_watchdog()
        ...     rig.emulators.supply_state.watchdog_s
        1.0
        """
        if self.cfg.watchdog_command is None:
            raise InvalidArgumentError("supply: no watchdog configured ([supply] watchdog_s "
                                       "and watchdog_command)")
        self._command(self.cfg.watchdog_command.format(seconds=self.cfg.watchdog_s))

    def disarm_watchdog(self) -> None:
        """Disarm the supply's watchdog (``watchdog_command`` with 0 s).

        Raises
        ------
        InvalidArgumentError
            No watchdog is configured.
        RigError
            No reply, a wrong echo, or an error message from the supply.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\nprotocol = "ascii"\\n'
        ...                       'watchdog_s = 1.0\\nwatchdog_command = "WDOG {seconds:.1f}"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.arm_watchdog(); rig.supply.disarm_watchdog()
        ...     rig.emulators.supply_state.watchdog_s
        0.0
        """
        if self.cfg.watchdog_command is None:
            raise InvalidArgumentError("supply: no watchdog configured ([supply] "
                                       "watchdog_command)")
        self._command(self.cfg.watchdog_command.format(seconds=0.0))

    def close(self) -> None:
        """Close the port.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\nprotocol = "ascii"\\n'
        ...                       'query_command = "MEAS:VOLT?"\\n'
        ...                       'output_on_command = "OUTP ON"\\n'
        ...                       'output_off_command = "OUTP OFF"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> rig = Rig(config)
        >>> rig.supply.close(); rig.supply.port.is_open
        False
        >>> rig.close()
        """
        close_port(self.port)

    def describe(self) -> str:
        """One line for the log: the port and the set command.

        Returns
        -------
        str
            The line.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\nprotocol = "ascii"\\n'
        ...                       'query_command = "MEAS:VOLT?"\\n'
        ...                       'output_on_command = "OUTP ON"\\n'
        ...                       'output_off_command = "OUTP OFF"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.supply.describe()
        "ASCII supply at pihystsim://supply ('VOLT {volts:.2f}')"
        """
        return f"ASCII supply at {self.cfg.port} ({self.cfg.set_command!r})"


def open_supply(cfg: Any, clock: Any = WallClock,
                port: Any = None) -> "ModbusRtuSupply | AsciiSupply":
    """The driver of the supply of ``cfg``, on ``port`` or on ``cfg.port`` opened.

    Parameters
    ----------
    cfg : SupplyConfig
        The supply's configuration: ``protocol`` chooses the driver.
    clock : WallClock or VirtualClock
        The clock of the Modbus driver's silences.
    port : serial.SerialBase or None
        An open pyserial-like port; None: open ``cfg.port``.

    Returns
    -------
    ModbusRtuSupply or AsciiSupply
        The driver.

    Raises
    ------
    RigError
        The port does not open.

    Examples
    --------
    >>> from pihyst.rig import SupplyConfig, open_supply
    >>> supply = open_supply(SupplyConfig(port="loop://", protocol="ascii"))
    >>> type(supply).__name__, supply.has_readback
    ('AsciiSupply', False)
    >>> supply.close()
    """
    if port is None:
        port = open_port(cfg.port, cfg.baudrate, cfg.timeout_s, "supply", cfg.parity,
                         cfg.stopbits)
    if cfg.protocol == "modbus-rtu":
        return ModbusRtuSupply(port, cfg, clock)
    return AsciiSupply(port, cfg, clock)
