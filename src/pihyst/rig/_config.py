"""The rig configuration: a TOML file with the sections [rig], [supply], [sensor] and,
for the simulated instruments, [emulator].

Errors are :class:`ConfigError`, one line naming the file, the key and, where it can be
found, the line: ``rig.toml:12: [supply] scale: must be a positive number, got -1``.
"""

import math
import os
import re
import sys
from dataclasses import dataclass, field, fields

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


class ConfigError(ValueError):
    """A rig configuration could not be used; the message is one line naming the file,
    the line where it can be found, and the key.

    Examples
    --------
    >>> from pihyst.rig import ConfigError, parse_config
    >>> try:
    ...     parse_config("[supply]\\nscale = -1\\n", source="rig.toml")
    ... except ConfigError as err:
    ...     print(err)
    rig.toml:2: [supply] scale: must be a positive number, got -1.0
    """


def char_bits(port_config: "SupplyConfig | SensorConfig") -> int:
    """Bits on the wire per byte: start, 8 data, parity (unless N), stop bits."""
    return 1 + 8 + (port_config.parity != "N") + port_config.stopbits


SUPPLY_PROTOCOLS = ("modbus-rtu", "ascii")
SENSOR_PROTOCOLS = ("keyence-lk-g5000", "keyence-lk-g3000")
REGISTER_FORMATS = ("uint16", "uint32", "float32")
WORD_ORDERS = ("big", "little")
#: the largest register value of each setpoint format
REGISTER_MAX = {"uint16": 0xFFFF, "uint32": 0xFFFFFFFF, "float32": 3.4028234663852886e38}


@dataclass(frozen=True)
class LoopSettings:
    """[rig]: the controller loop and its safety limits.

    Parameters
    ----------
    rate_hz : float
        The loop's rate (Hz): one setpoint and one reading per tick.
    u_min, u_max : float
        The voltage limits (V); no command leaves them. ``u_min`` must be 0.
    slew_V_per_s : float or None
        The largest voltage change per second (None: no slew limit).
    ramp_V_per_s : float or None
        The rate of the ramps from and to 0 V at the start and end of a run (None: the
        slew limit, else 50 V/s).
    max_comm_errors : int
        Consecutive failed exchanges that stop a run.
    max_invalid_readings : int
        Consecutive invalid sensor readings that stop a run.
    max_overruns : int
        Consecutive overruns (a tick later than its period) that stop a run.
    watchdog_periods : float
        A loop stall this long (in periods) zeroes the output.
    readback_every : int
        Ticks between readbacks of the supply's voltage (when it has a readback).
    readback_tolerance_V : float
        The largest difference between setpoint and readback (V).
    stuck_ticks : int
        A reading unchanged this many ticks while the voltage moves ``stuck_volts``
        stops the run (0: off).
    stuck_volts : float
        See ``stuck_ticks`` (V).

    Examples
    --------
    >>> from pihyst.rig import LoopSettings
    >>> loop = LoopSettings(rate_hz=50.0, slew_V_per_s=100.0)
    >>> loop.period_s, loop.start_ramp_V_per_s
    (0.02, 100.0)
    """

    rate_hz: float = 20.0
    u_min: float = 0.0
    u_max: float = 150.0
    slew_V_per_s: float | None = None     # None: no slew limit
    ramp_V_per_s: float | None = None     # start ramp; default: the slew limit, else 50 V/s
    max_comm_errors: int = 3              # consecutive failed exchanges that stop a run
    max_invalid_readings: int = 5         # consecutive invalid readings that stop a run
    max_overruns: int = 10                # consecutive overruns that stop a run
    watchdog_periods: float = 5.0         # loop stall (in periods) that zeroes the output
    readback_every: int = 1               # ticks between readbacks (when configured)
    readback_tolerance_V: float = 1.0
    stuck_ticks: int = 20                 # a reading unchanged this long while the voltage
    #                                       moves stuck_volts stops the run (0: off)
    stuck_volts: float = 5.0

    @property
    def period_s(self) -> float:
        """The loop's period (s)."""
        return 1.0 / self.rate_hz

    @property
    def start_ramp_V_per_s(self) -> float:
        """The rate of the start and end ramps (V/s)."""
        if self.ramp_V_per_s is not None:
            return self.ramp_V_per_s
        return self.slew_V_per_s if self.slew_V_per_s is not None else 50.0


@dataclass(frozen=True)
class SupplyConfig:
    """[supply]: the programmable high-voltage supply.

    Parameters
    ----------
    port : str
        A serial device or a pyserial URL (``pihystsim://supply``: the emulated one).
    baudrate : int
        Bits per second.
    protocol : str
        ``"modbus-rtu"`` or ``"ascii"`` (a line protocol: SCPI-like, MDT693B-like).
    timeout_s : float
        How long to wait for a reply (s).
    parity : str
        ``"N"``, ``"E"`` or ``"O"`` (Modbus RTU's default is E).
    stopbits : int
        1 or 2.
    address : int
        Modbus: the slave address, 1..247.
    setpoint_register : int
        Modbus: the first holding register of the setpoint.
    setpoint_format : str
        Modbus: ``"uint16"``, ``"uint32"`` or ``"float32"``.
    word_order : str
        Modbus: ``"big"`` (high word first) or ``"little"`` (CDAB).
    scale : float
        Modbus: register units per volt.
    output_register : int or None
        Modbus: the register that switches the output (1 on, 0 off), if any.
    readback_register : int or None
        Modbus: the register of the measured output voltage (same format and scale as
        the setpoint), if any.
    terminator : str
        ASCII: the end of a line.
    set_command : str
        ASCII: the command that sets the voltage, a template with ``{volts}``.
    query_command : str or None
        ASCII: the command that reads the output voltage back (``"MEAS:VOLT?"``), if
        any.
    output_on_command, output_off_command : str or None
        ASCII: the commands that switch the output, if any.
    echo : bool
        ASCII: the device echoes each command.
    prompt : str
        ASCII: what the device sends when it is ready again (``">"``), if anything.
    reply_pattern : str
        ASCII: a regular expression that finds the number in a reply.
    watchdog_s : float or None
        The supply's communication watchdog: its output goes off after this long without
        a request; armed at the start of a run when set.
    watchdog_register : int or None
        Modbus: the register that holds the watchdog's timeout.
    watchdog_scale : float
        Modbus: the watchdog register's units per second (1000: ms).
    watchdog_command : str or None
        ASCII: the command that arms the watchdog, a template with ``{seconds}`` (0
        disarms).

    Examples
    --------
    >>> from pihyst.rig import SupplyConfig
    >>> SupplyConfig(protocol="ascii", set_command="V {volts:.1f}").set_command.format(volts=12)
    'V 12.0'
    """

    port: str = "/dev/ttyUSB0"
    baudrate: int = 19200
    protocol: str = "modbus-rtu"
    timeout_s: float = 0.1
    parity: str = "N"                     # N, E or O (Modbus RTU's default is E)
    stopbits: int = 1                     # 1 or 2
    # Modbus RTU
    address: int = 1
    setpoint_register: int = 10
    setpoint_format: str = "float32"
    word_order: str = "big"
    scale: float = 1.0                    # register units per volt
    output_register: int | None = None    # 1 = on, 0 = off
    readback_register: int | None = None  # same format and scale as the setpoint
    # ASCII line protocol
    terminator: str = "\r\n"
    set_command: str = "VOLT {volts:.2f}"
    query_command: str | None = None      # e.g. "MEAS:VOLT?"
    output_on_command: str | None = None  # e.g. "OUTP ON"
    output_off_command: str | None = None
    echo: bool = False                    # the device echoes each command
    prompt: str = ""                      # sent by the device when it is ready again
    reply_pattern: str = r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?"
    # the supply's communication watchdog: output off after watchdog_s without a request
    watchdog_s: float | None = None       # armed at the start of a run when set
    watchdog_register: int | None = None  # Modbus: holds the timeout (function 06) ...
    watchdog_scale: float = 1000.0        # ... in these units per second (1000: ms)
    watchdog_command: str | None = None   # ASCII: e.g. "WDOG {seconds:.1f}" (0 disarms)


@dataclass(frozen=True)
class SensorConfig:
    """[sensor]: the laser displacement sensor.

    Parameters
    ----------
    port : str
        A serial device or a pyserial URL (``pihystsim://sensor``: the emulated one).
    baudrate : int
        Bits per second.
    protocol : str
        ``"keyence-lk-g5000"`` or ``"keyence-lk-g3000"``.
    parity : str
        ``"N"``, ``"E"`` or ``"O"``.
    stopbits : int
        1 or 2.
    output : int
        The sensor head's output number (1..12 on an LK-G5000, 1..2 on an LK-G3000).
    scale_um : float
        Micrometres per reported unit.
    sign : int
        1, or -1 when the sensor counts the other way.
    timeout_s : float
        How long to wait for a reply (s).

    Examples
    --------
    >>> from pihyst.rig import SensorConfig
    >>> SensorConfig(protocol="keyence-lk-g3000", output=2).output
    2
    """

    port: str = "/dev/ttyUSB1"
    baudrate: int = 115200
    protocol: str = "keyence-lk-g5000"
    parity: str = "N"
    stopbits: int = 1
    output: int = 1
    scale_um: float = 1.0                 # micrometres per reported unit
    sign: int = 1
    timeout_s: float = 0.1


@dataclass(frozen=True)
class EmulatorConfig:
    """[emulator]: the simulated instruments (ignored on a real rig).

    Parameters
    ----------
    plant : str
        The simulated beam the instruments drive (a name of ``pihyst.sim.PLANT_NAMES``).
    seed : int
        The seed of the sensor's noise.
    supply_delay_s, sensor_delay_s : float
        Each instrument's processing time per request (s).
    sensor_decimals : int
        Digits after the point in the sensor's replies (0..6).
    sensor_range_um : float
        A reading above this in magnitude is over-range (µm).
    supply_max_V : float
        The supply's own limit (V).
    supply_step_V : float
        The supply's setpoint resolution (V).
    supply_watchdog_s : float
        When above 0, the supply's output goes off after this long without a request.
    supply_reply : str
        ASCII supply: the reply to ``query_command``, a template with ``{volts}``.

    Examples
    --------
    >>> from pihyst.rig import EmulatorConfig
    >>> EmulatorConfig().plant
    'paper-beam'
    """

    plant: str = "paper-beam"
    seed: int = 0
    supply_delay_s: float = 0.005         # the supply's processing time per request
    sensor_delay_s: float = 0.001
    sensor_decimals: int = 4              # digits after the point in the sensor's reply
    sensor_range_um: float = 300.0        # |reading| above this is over-range
    supply_max_V: float = 1000.0
    supply_step_V: float = 0.01
    supply_watchdog_s: float = 0.0        # > 0: output off after this long without a request
    supply_reply: str = "{volts:.3f}"     # ASCII supply: the reply to query_command


@dataclass(frozen=True)
class RigConfig:
    """The whole configuration, as :func:`parse_config` and :func:`load_config` return it.

    Parameters
    ----------
    rig : LoopSettings
        [rig]: the loop and its limits.
    supply : SupplyConfig
        [supply].
    sensor : SensorConfig
        [sensor].
    emulator : EmulatorConfig
        [emulator].
    source : str
        The file it came from.
    text : str
        The text of that file.

    Examples
    --------
    >>> from pihyst.rig import LoopSettings, RigConfig
    >>> RigConfig(rig=LoopSettings(rate_hz=10.0)).rig.period_s
    0.1
    """

    rig: LoopSettings = field(default_factory=LoopSettings)
    supply: SupplyConfig = field(default_factory=SupplyConfig)
    sensor: SensorConfig = field(default_factory=SensorConfig)
    emulator: EmulatorConfig = field(default_factory=EmulatorConfig)
    source: str = "<defaults>"
    text: str = ""

    def describe(self) -> str:
        """One line that says what the configuration drives, for log metadata.

        Returns
        -------
        str
            Source, ports, protocols and rate.

        Examples
        --------
        >>> from pihyst.rig import RigConfig
        >>> print(RigConfig().describe()[:70])
        <defaults>: supply /dev/ttyUSB0 (modbus-rtu @19200 addr 1 setpoint reg
        """
        s, n, r = self.supply, self.sensor, self.rig
        supply = (f"{s.protocol} @{s.baudrate} addr {s.address} setpoint reg "
                  f"{s.setpoint_register} {s.setpoint_format}/{s.word_order} x{s.scale:g}"
                  if s.protocol == "modbus-rtu" else
                  f"ascii @{s.baudrate} set {s.set_command!r}")
        return (f"{self.source}: supply {s.port} ({supply}); sensor {n.port} ({n.protocol} "
                f"@{n.baudrate} output {n.output} x{n.scale_um:g} µm sign {n.sign:+d}); "
                f"rate {r.rate_hz:g} Hz")


_SECTIONS = {"rig": LoopSettings, "supply": SupplyConfig, "sensor": SensorConfig,
             "emulator": EmulatorConfig}


def _key_line(text, section, key):
    """1-based line of ``key = ...`` inside ``[section]`` (0 if not found)."""
    current = None
    for n, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        m = re.match(r"\[\s*([A-Za-z0-9_.-]+)\s*\]", stripped)
        if m:
            current = m.group(1)
        elif current == section and re.match(rf"{re.escape(key)}\s*=", stripped):
            return n
    return 0


class _Checker:
    def __init__(self, path, text):
        self.path, self.text = path, text

    def fail(self, section, key, message):
        line = _key_line(self.text, section, key) if key else 0
        where = f"{self.path}:{line}" if line else self.path
        name = f"[{section}] {key}" if key else f"[{section}]"
        raise ConfigError(f"{where}: {name}: {message}")


def _convert(check, section, name, value, default):
    """Check one value against the type of its default."""
    kind = type(default)
    if name in ("slew_V_per_s", "ramp_V_per_s", "readback_tolerance_V", "scale", "scale_um",
                "rate_hz", "timeout_s", "watchdog_s", "watchdog_scale") or kind is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            check.fail(section, name, f"must be a number, got {value!r}")
        value = float(value)
        if not math.isfinite(value):
            check.fail(section, name, f"must be a finite number, got {value}")
        return value
    if name in ("output_register", "readback_register", "address", "baudrate",
                "watchdog_register") or kind is int:
        if isinstance(value, bool) or not isinstance(value, int):
            check.fail(section, name, f"must be a whole number, got {value!r}")
        return value
    if kind is bool:
        if not isinstance(value, bool):
            check.fail(section, name, f"must be true or false, got {value!r}")
        return value
    if not isinstance(value, str):
        check.fail(section, name, f"must be a string, got {value!r}")
    return value


def _section(check, data, section, cls):
    raw = data.get(section, {})
    if not isinstance(raw, dict):
        check.fail(section, None, "must be a table")
    known = {f.name: f for f in fields(cls)}
    values = {}
    for key, value in raw.items():
        if key not in known:
            check.fail(section, key, f"unknown key; known keys: {', '.join(known)}")
        values[key] = _convert(check, section, key, value, known[key].default)
    return cls(**values)


def _positive(check, section, name, value, allow_none=False):
    if value is None and allow_none:
        return
    if value is None or not value > 0:
        check.fail(section, name, f"must be a positive number, got {value!r}")


def _validate(check, cfg):
    r, s, n, e = cfg.rig, cfg.supply, cfg.sensor, cfg.emulator
    _positive(check, "rig", "rate_hz", r.rate_hz)
    if not r.u_min < r.u_max:
        check.fail("rig", "u_max", f"must be above u_min ({r.u_min:g}), got {r.u_max:g}")
    if r.u_min > 0 or r.u_max < 0:
        check.fail("rig", "u_min", f"the limits [{r.u_min:g}, {r.u_max:g}] V must include "
                   "0 V (runs start and end there)")
    if r.u_min < 0:
        # the drivers refuse a negative setpoint, and the shutdown ramps down to 0 V only
        check.fail("rig", "u_min", f"must be 0, got {r.u_min:g}: pihyst drives unipolar "
                   "supplies (0 V to u_max)")
    _positive(check, "rig", "slew_V_per_s", r.slew_V_per_s, allow_none=True)
    _positive(check, "rig", "ramp_V_per_s", r.ramp_V_per_s, allow_none=True)
    if r.ramp_V_per_s is not None and r.slew_V_per_s is not None and \
            r.ramp_V_per_s > r.slew_V_per_s:
        check.fail("rig", "ramp_V_per_s", f"the start ramp ({r.ramp_V_per_s:g} V/s) must not "
                   f"be faster than the slew limit ({r.slew_V_per_s:g} V/s)")
    for name in ("max_comm_errors", "max_invalid_readings", "max_overruns",
                 "readback_every"):
        if getattr(r, name) < 1:
            check.fail("rig", name, f"must be at least 1, got {getattr(r, name)}")
    if r.stuck_ticks < 0:
        check.fail("rig", "stuck_ticks", f"must be 0 (off) or more, got {r.stuck_ticks}")
    _positive(check, "rig", "watchdog_periods", r.watchdog_periods)
    _positive(check, "rig", "readback_tolerance_V", r.readback_tolerance_V)
    for sec, c, protocols in (("supply", s, SUPPLY_PROTOCOLS), ("sensor", n, SENSOR_PROTOCOLS)):
        if c.protocol not in protocols:
            check.fail(sec, "protocol", f"{c.protocol!r} is not one of {', '.join(protocols)}")
        _positive(check, sec, "baudrate", c.baudrate)
        _positive(check, sec, "timeout_s", c.timeout_s)
        if not c.port:
            check.fail(sec, "port", "must name a serial port or a pyserial URL")
        if c.parity not in ("N", "E", "O"):
            check.fail(sec, "parity", f"must be N, E or O, got {c.parity!r}")
        if c.stopbits not in (1, 2):
            check.fail(sec, "stopbits", f"must be 1 or 2, got {c.stopbits}")
    if s.protocol == "modbus-rtu" and not 1 <= s.address <= 247:
        # 0 is the broadcast address, to which no slave replies
        check.fail("supply", "address", f"must be a Modbus slave address 1..247, got {s.address}")
    if s.setpoint_format not in REGISTER_FORMATS:
        check.fail("supply", "setpoint_format",
                   f"{s.setpoint_format!r} is not one of {', '.join(REGISTER_FORMATS)}")
    if s.word_order not in WORD_ORDERS:
        check.fail("supply", "word_order", f"{s.word_order!r} is not big or little")
    _positive(check, "supply", "scale", s.scale)
    largest = REGISTER_MAX[s.setpoint_format]
    if s.protocol == "modbus-rtu" and round(r.u_max * s.scale) > largest:
        check.fail("rig", "u_max", f"{r.u_max:g} V is {r.u_max * s.scale:g} register units at "
                   f"[supply] scale {s.scale:g}: more than a {s.setpoint_format} setpoint "
                   f"holds ({largest:g})")
    _validate_watchdog(check, cfg)
    for name in ("setpoint_register", "output_register", "readback_register",
                 "watchdog_register"):
        v = getattr(s, name)
        if v is not None and not 0 <= v <= 0xFFFF:
            check.fail("supply", name, f"must be a register address 0..65535, got {v}")
    for name in ("set_command",):
        try:
            getattr(s, name).format(volts=1.0)
        except (KeyError, ValueError, IndexError) as err:
            check.fail("supply", name, f"bad template ({err}); use {{volts}} or "
                       "{volts:.2f} for the voltage")
    try:
        re.compile(s.reply_pattern)
    except re.error as err:
        check.fail("supply", "reply_pattern", f"not a regular expression: {err}")
    if s.protocol == "ascii" and not s.terminator:
        check.fail("supply", "terminator", "must not be empty")
    if n.output < 1 or n.output > (2 if n.protocol == "keyence-lk-g3000" else 12):
        check.fail("sensor", "output", f"no output {n.output} on a {n.protocol}")
    _positive(check, "sensor", "scale_um", n.scale_um)
    if n.sign not in (1, -1):
        check.fail("sensor", "sign", f"must be 1 or -1, got {n.sign}")
    for name in ("supply_delay_s", "sensor_delay_s", "supply_watchdog_s"):
        if getattr(e, name) < 0:
            check.fail("emulator", name, f"must be >= 0, got {getattr(e, name)}")
    if not 0 <= e.sensor_decimals <= 6:
        check.fail("emulator", "sensor_decimals", f"must be 0..6, got {e.sensor_decimals}")
    _positive(check, "emulator", "sensor_range_um", e.sensor_range_um)


def _validate_watchdog(check, cfg):
    """[supply] watchdog_s and the register or command that arms it: both or neither;
    a timeout that the loop's requests (one per tick at least) can keep from tripping,
    and that the register can hold."""
    s, r = cfg.supply, cfg.rig
    where = "watchdog_register" if s.protocol == "modbus-rtu" else "watchdog_command"
    how = getattr(s, where)
    if s.watchdog_s is None:
        if how is not None:
            check.fail("supply", where, "names the supply's watchdog but watchdog_s (its "
                       "timeout in seconds) is not set")
        return
    _positive(check, "supply", "watchdog_s", s.watchdog_s)
    if how is None:
        check.fail("supply", "watchdog_s", f"is set but {where} (how to arm the supply's "
                   "watchdog) is not")
    # a tick may take its period plus a sensor timeout and a supply timeout
    gap = r.period_s + cfg.sensor.timeout_s + s.timeout_s
    if s.watchdog_s < 2 * gap:
        check.fail("supply", "watchdog_s", f"{s.watchdog_s:g} s would trip between two "
                   f"ticks: at least {2 * gap:g} s (twice the period {r.period_s:g} s plus "
                   "the sensor's and the supply's timeouts)")
    if s.protocol == "modbus-rtu":
        _positive(check, "supply", "watchdog_scale", s.watchdog_scale)
        counts = round(s.watchdog_s * s.watchdog_scale)
        if not 1 <= counts <= 0xFFFF:
            check.fail("supply", "watchdog_s", f"{s.watchdog_s:g} s is {counts} register "
                       f"units at watchdog_scale {s.watchdog_scale:g}: a uint16 register "
                       "holds 1..65535")
    else:
        try:
            s.watchdog_command.format(seconds=1.0)
        except (KeyError, ValueError, IndexError, AttributeError) as err:
            check.fail("supply", "watchdog_command", f"bad template ({err}); use "
                       "{seconds} or {seconds:.1f} for the timeout")


def parse_config(text: str, source: str = "<string>") -> RigConfig:
    """A :class:`RigConfig` from TOML text, checked.

    Parameters
    ----------
    text : str
        TOML with the sections [rig], [supply], [sensor] and [emulator] (each optional;
        missing keys take their defaults).
    source : str
        What to call the text in error messages.

    Returns
    -------
    RigConfig
        The configuration.

    Raises
    ------
    ConfigError
        Text that is not TOML, an unknown section or key, or a value out of its range
        (one line: ``SOURCE:LINE: [section] key: ...``).

    Examples
    --------
    >>> from pihyst.rig import parse_config
    >>> cfg = parse_config("[rig]\\nrate_hz = 50\\n[supply]\\nport = 'pihystsim://supply'\\n")
    >>> cfg.rig.rate_hz, cfg.supply.port, cfg.sensor.protocol
    (50.0, 'pihystsim://supply', 'keyence-lk-g5000')
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(f"{source}: {err}") from None
    check = _Checker(source, text)
    for section in data:
        if section not in _SECTIONS:
            check.fail(section, None, f"unknown section; known: {', '.join(_SECTIONS)}")
    parts = {name: _section(check, data, name, cls) for name, cls in _SECTIONS.items()}
    cfg = RigConfig(**parts, source=source, text=text)
    _validate(check, cfg)
    from pihyst.rig._plants import PLANT_NAMES
    if cfg.emulator.plant not in PLANT_NAMES:
        check.fail("emulator", "plant", f"{cfg.emulator.plant!r} is not one of "
                   f"{', '.join(PLANT_NAMES)}")
    return cfg


def load_config(path: str | os.PathLike[str]) -> RigConfig:
    """Read and check a rig configuration file (TOML, see :func:`parse_config`).

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    RigConfig
        The configuration, with the file as its source.

    Raises
    ------
    ConfigError
        A file that cannot be read, is not UTF-8 text, or holds a bad configuration.

    Examples
    --------
    >>> import os, tempfile
    >>> from pihyst.rig import load_config
    >>> path = os.path.join(tempfile.mkdtemp(), "rig.toml")
    >>> with open(path, "w") as f:
    ...     _ = f.write("[rig]\\nrate_hz = 100\\n")
    >>> load_config(path).rig.period_s
    0.01
    """
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8-sig") as f:
            text = f.read()
    except OSError as err:
        raise ConfigError(f"{path}: cannot read file: {err.strerror}") from None
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: not a text file (UTF-8 expected)") from None
    return parse_config(text, source=path)
