"""PyMeasure Instrument classes for the rig's instruments. Each one holds pihyst's own
driver (``driver``) on an :class:`~pihyst.rig.pymeasure._port.AdapterPort`, so it speaks
exactly the bytes ``pihyst rig`` speaks: the framing, the CRC, the dialects' echo and
prompt, the ``ER`` codes and the over-range markers are the drivers' and the codecs'
(:mod:`pihyst.rig._codecs`), not repeated here.

``adapter`` is what PyMeasure takes: a VISA resource name (``"ASRL/dev/ttyUSB0::INSTR"``,
``"TCPIP::127.0.0.1::5020::SOCKET"``; the configured baud rate, parity, stop bits and
timeout are passed to PyVISA unless given), or an Adapter (``SerialAdapter("COM3")``,
``SerialAdapter(serial.serial_for_url("socket://127.0.0.1:5020"))``).
"""

import math
import os
from collections.abc import Mapping
from typing import Any

from pymeasure.instruments import Instrument
from pymeasure.instruments.validators import strict_range
from pyvisa.constants import Parity, StopBits

from pihyst.exceptions import InvalidArgumentError
from pihyst.rig._codecs import Reading
from pihyst.rig._config import (
    ConfigError,
    RigConfig,
    SensorConfig,
    SupplyConfig,
    _Checker,
    _section,
    load_config,
)
from pihyst.rig._sensor import KeyenceSensor
from pihyst.rig._supply import AsciiSupply, ModbusRtuSupply
from pihyst.rig.pymeasure._port import AdapterPort

_PARITY = {"N": Parity.none, "E": Parity.even, "O": Parity.odd}
_STOPBITS = {1: StopBits.one, 2: StopBits.two}


def section_of(config: Any, name: str, cls: type, protocol: str) -> Any:
    """The ``[name]`` section (a ``cls``) of ``config`` for an instrument that speaks
    ``protocol``: None (the defaults), a :class:`~pihyst.rig.RigConfig`, a rig TOML file,
    a ``cls`` or a dict of the section's keys (checked as in a file; ``protocol`` unless
    it says one). A section of another protocol is a ConfigError."""
    if config is None:
        section = cls(protocol=protocol)
    elif isinstance(config, (str, os.PathLike)):
        section = getattr(load_config(config), name)
    elif isinstance(config, RigConfig):
        section = getattr(config, name)
    elif isinstance(config, cls):
        section = config
    elif isinstance(config, dict):
        section = _section(_Checker("config", ""), {name: {"protocol": protocol, **config}},
                           name, cls)
    else:
        raise ConfigError(f"config: expected a rig configuration, a TOML file, a "
                          f"{cls.__name__} or a dict of [{name}] keys, got "
                          f"{type(config).__name__}")
    if section.protocol != protocol:
        raise ConfigError(f"config: [{name}] protocol is {section.protocol!r}; this "
                          f"instrument speaks {protocol!r}")
    return section


def _visa_settings(kwargs: dict[str, Any], section: Any) -> None:
    """PyVISA settings from the configuration, unless the caller gave them."""
    kwargs.setdefault("timeout", max(1, int(round(1000 * section.timeout_s))))
    asrl = dict(kwargs.get("asrl", {}))
    asrl.setdefault("baud_rate", section.baudrate)
    asrl.setdefault("parity", _PARITY[section.parity])
    asrl.setdefault("stop_bits", _STOPBITS[section.stopbits])
    kwargs["asrl"] = asrl


def _visa_keywords(visa_library: str, timeout: int | None, asrl: Mapping[str, Any] | None,
                   visa_options: Mapping[str, Any] | None) -> dict[str, Any]:
    """The keywords PyMeasure passes to its VISAAdapter (and PyVISA) for a resource name."""
    kwargs = dict(visa_options or {})
    if visa_library:
        kwargs["visa_library"] = visa_library
    if timeout is not None:
        kwargs["timeout"] = timeout
    if asrl is not None:
        kwargs["asrl"] = dict(asrl)
    return kwargs


class _RigInstrument(Instrument):
    def __init__(self, adapter: Any, name: str, section: Any, kwargs: dict[str, Any]) -> None:
        if isinstance(adapter, (int, str)):
            _visa_settings(kwargs, section)
        super().__init__(adapter, name, includeSCPI=False, **kwargs)
        self.config = section
        self.port = AdapterPort(self.adapter, section.baudrate, section.timeout_s, name)


# ----------------------------------------------------------------------------- sensor
class _KeyenceLK(_RigInstrument):
    protocol = ""

    def __init__(self, adapter: Any, name: str | None = None, config: Any = None, *,
                 visa_library: str = "", timeout: int | None = None,
                 asrl: Mapping[str, Any] | None = None,
                 visa_options: Mapping[str, Any] | None = None) -> None:
        section = section_of(config, "sensor", SensorConfig, self.protocol)
        super().__init__(adapter, name or f"KEYENCE {self.protocol[8:].upper()}", section,
                         _visa_keywords(visa_library, timeout, asrl, visa_options))
        self.driver = KeyenceSensor(self.port, section)

    @property
    def reading(self) -> Reading:
        """One measurement of the configured output: a :class:`~pihyst.rig.Reading` in
        micrometres (``value`` None and ``status`` 'over-range+', 'over-range-' or
        'invalid' when the controller reports no value). ``ER`` replies raise
        :class:`~pihyst.rig.KeyenceError`."""
        return self.driver.read()

    @property
    def displacement(self) -> float:
        """One measurement in micrometres (``sign * scale_um * reported``); NaN when
        the controller reports over-range or invalid (see :attr:`reading`)."""
        reading = self.driver.read()
        return reading.value if reading.valid and reading.value is not None else math.nan


class KeyenceLKG5000(_KeyenceLK):
    """KEYENCE LK-G5000 / LK-HD controller: ``MS,01\\r`` -> ``MS,01,+0012.3456\\r``.

    Parameters
    ----------
    adapter : str, int or pymeasure Adapter
        A VISA resource name or a PyMeasure adapter.
    name : str, optional
        The instrument's name (default: ``"KEYENCE LK-G5000"``).
    config : RigConfig, path, SensorConfig or dict, optional
        The ``[sensor]`` settings (output, scale_um, sign, baudrate, timeout_s...).
    visa_library : str
        PyVISA's library, when ``adapter`` is a resource name (``"@py"``: pyvisa-py,
        ``"FILE.yaml@sim"``: pyvisa-sim; default: PyVISA's choice).
    timeout : int or None
        PyVISA's timeout (ms) for a resource name (default: ``timeout_s`` of the
        configuration).
    asrl : dict or None
        PyVISA's serial settings for an ``ASRL`` resource (default: the configuration's
        baud rate, parity and stop bits; the keys given override them).
    visa_options : dict or None
        Any other keyword of PyMeasure's ``VISAAdapter`` and PyVISA's ``open_resource``
        (``query_delay``, ``tcpip``, ...), for a resource name.

    Examples
    --------
    >>> from pymeasure.test import expected_protocol
    >>> from pihyst.rig.pymeasure import KeyenceLKG5000
    >>> with expected_protocol(KeyenceLKG5000, [(b"MS,01\\r", b"MS,01,+0012.3456\\r")]) as s:
    ...     s.displacement
    12.3456
    """

    protocol = "keyence-lk-g5000"


class KeyenceLKG3000(_KeyenceLK):
    """KEYENCE LK-G3000 controller: ``M1\\r`` -> ``M1,+01.2345\\r``.

    Parameters
    ----------
    adapter : str, int or pymeasure Adapter
        A VISA resource name or a PyMeasure adapter.
    name : str, optional
        The instrument's name (default: ``"KEYENCE LK-G3000"``).
    config : RigConfig, path, SensorConfig or dict, optional
        The ``[sensor]`` settings (output 1 or 2, scale_um, sign, baudrate, ...).
    visa_library : str
        PyVISA's library, when ``adapter`` is a resource name (``"@py"``: pyvisa-py,
        ``"FILE.yaml@sim"``: pyvisa-sim; default: PyVISA's choice).
    timeout : int or None
        PyVISA's timeout (ms) for a resource name (default: ``timeout_s`` of the
        configuration).
    asrl : dict or None
        PyVISA's serial settings for an ``ASRL`` resource (default: the configuration's
        baud rate, parity and stop bits; the keys given override them).
    visa_options : dict or None
        Any other keyword of PyMeasure's ``VISAAdapter`` and PyVISA's ``open_resource``
        (``query_delay``, ``tcpip``, ...), for a resource name.

    Examples
    --------
    >>> from pymeasure.test import expected_protocol
    >>> from pihyst.rig.pymeasure import KeyenceLKG3000
    >>> with expected_protocol(KeyenceLKG3000, [(b"M2\\r", b"M2,-01.2345\\r")],
    ...                        config={"output": 2}) as sensor:
    ...     sensor.displacement
    -1.2345
    """

    protocol = "keyence-lk-g3000"


# ----------------------------------------------------------------------------- supplies
class _Supply(_RigInstrument):
    """Common part of the supplies: the setpoint within ``[0, max_voltage]``, the
    readback, the output switch, and :meth:`shutdown` to 0 V with the output off."""

    driver_class: type[ModbusRtuSupply] | type[AsciiSupply] = ModbusRtuSupply

    def __init__(self, adapter: Any, name: str, section: Any, max_voltage: float,
                 kwargs: dict[str, Any]) -> None:
        super().__init__(adapter, name, section, kwargs)
        self.driver = self.driver_class(self.port, section)
        max_voltage = float(max_voltage)
        if not (math.isfinite(max_voltage) and max_voltage > 0):
            raise InvalidArgumentError(f"max_voltage must be a positive number of volts, got "
                             f"{max_voltage}")
        self.driver.check_setpoint(max_voltage)   # the register holds it at this scale
        self.max_voltage = max_voltage
        self._setpoint: float | None = None
        self._output: bool | None = None

    @property
    def voltage_setpoint(self) -> float | None:
        """Control the setpoint in volts (0 .. ``max_voltage``; a value outside is a
        ValueError and nothing is sent). Getting returns the last value sent (None
        before the first)."""
        return self._setpoint

    @voltage_setpoint.setter
    def voltage_setpoint(self, volts: float) -> None:
        volts = strict_range(float(volts), (0.0, self.max_voltage))
        self.driver.set_voltage(volts)
        self._setpoint = volts

    @property
    def voltage(self) -> float | None:
        """Measure the supply's readback in volts (None without a readback configured)."""
        return self.driver.read_voltage()

    @property
    def output_enabled(self) -> bool | None:
        """Control the output switch (True on, False off); getting returns the last
        state sent (None before the first)."""
        return self._output

    @output_enabled.setter
    def output_enabled(self, on: bool) -> None:
        on = bool(on)
        (self.driver.output_on if on else self.driver.output_off)()
        self._output = on

    def shutdown(self) -> None:
        """0 V, then output off, the second tried even when the first fails (PyMeasure
        calls this when an experiment ends, and ``with`` on leaving the block).

        Raises
        ------
        OSError
            The first communication error, after both were tried.

        Examples
        --------
        >>> from pymeasure.test import expected_protocol
        >>> from pihyst.rig.pymeasure import AsciiHVSupply
        >>> pairs = [(b"VOLT 0.00\\r\\n", None), (b"OUTP OFF\\r\\n", None)]
        >>> with expected_protocol(AsciiHVSupply, pairs,
        ...                        config={"output_off_command": "OUTP OFF"}) as supply:
        ...     supply.shutdown()
        >>> supply.voltage_setpoint, supply.output_enabled
        (0.0, False)
        """
        errors: list[OSError] = []
        for name, value in (("voltage_setpoint", 0.0), ("output_enabled", False)):
            try:
                setattr(self, name, value)
            except OSError as err:
                errors.append(err)
        super().shutdown()
        if errors:
            raise errors[0]


class ModbusHVSupply(_Supply):
    """A high-voltage supply on Modbus RTU with the register map of ``config``'s
    ``[supply]`` (setpoint as uint16/uint32/float32 in either word order, optional
    output-enable and readback registers), through minimalmodbus as in ``pihyst rig``.

    Parameters
    ----------
    adapter : str, int or pymeasure Adapter
        A VISA resource name or a PyMeasure adapter.
    name : str, optional
        The instrument's name.
    config : RigConfig, path, SupplyConfig or dict, optional
        The ``[supply]`` register map (protocol 'modbus-rtu').
    max_voltage : float, optional
        The highest setpoint it may be sent (default: ``[rig] u_max`` of a rig
        configuration, else 150 V).
    visa_library : str
        PyVISA's library, when ``adapter`` is a resource name (``"@py"``: pyvisa-py,
        ``"FILE.yaml@sim"``: pyvisa-sim; default: PyVISA's choice).
    timeout : int or None
        PyVISA's timeout (ms) for a resource name (default: ``timeout_s`` of the
        configuration).
    asrl : dict or None
        PyVISA's serial settings for an ``ASRL`` resource (default: the configuration's
        baud rate, parity and stop bits; the keys given override them).
    visa_options : dict or None
        Any other keyword of PyMeasure's ``VISAAdapter`` and PyVISA's ``open_resource``
        (``query_delay``, ``tcpip``, ...), for a resource name.

    Raises
    ------
    InvalidArgumentError
        A ``max_voltage`` that is not a positive number, or that the setpoint register
        cannot hold.
    ConfigError
        A bad configuration, or one of another protocol.

    Examples
    --------
    >>> from pymeasure.test import expected_protocol
    >>> from pihyst.rig import crc16_modbus
    >>> from pihyst.rig.pymeasure import ModbusHVSupply
    >>> def rtu(hex_frame):
    ...     frame = bytes.fromhex(hex_frame)
    ...     return frame + crc16_modbus(frame).to_bytes(2, "little")
    >>> set_10V = (rtu("01 10 000A 0002 04 4120 0000"), rtu("01 10 000A 0002"))
    >>> with expected_protocol(ModbusHVSupply, [set_10V],
    ...                        config={"output_register": 9}) as supply:
    ...     supply.voltage_setpoint = 10.0
    """

    driver_class = ModbusRtuSupply

    def __init__(self, adapter: Any, name: str = "Modbus RTU HV supply", config: Any = None,
                 max_voltage: float | None = None, *, visa_library: str = "",
                 timeout: int | None = None, asrl: Mapping[str, Any] | None = None,
                 visa_options: Mapping[str, Any] | None = None) -> None:
        section = section_of(config, "supply", SupplyConfig, "modbus-rtu")
        super().__init__(adapter, name, section, _max_voltage(config, max_voltage),
                         _visa_keywords(visa_library, timeout, asrl, visa_options))


class AsciiHVSupply(_Supply):
    """A high-voltage supply with an ASCII line protocol from ``config``'s ``[supply]``
    templates (``set_command``, ``query_command``, ``output_on_command``..., ``echo``,
    ``prompt``, ``terminator``).

    Parameters
    ----------
    adapter : str, int or pymeasure Adapter
        A VISA resource name or a PyMeasure adapter.
    name : str, optional
        The instrument's name.
    config : RigConfig, path, SupplyConfig or dict, optional
        The ``[supply]`` commands (protocol 'ascii').
    max_voltage : float, optional
        The highest setpoint it may be sent (default: ``[rig] u_max`` of a rig
        configuration, else 150 V).
    visa_library : str
        PyVISA's library, when ``adapter`` is a resource name (``"@py"``: pyvisa-py,
        ``"FILE.yaml@sim"``: pyvisa-sim; default: PyVISA's choice).
    timeout : int or None
        PyVISA's timeout (ms) for a resource name (default: ``timeout_s`` of the
        configuration).
    asrl : dict or None
        PyVISA's serial settings for an ``ASRL`` resource (default: the configuration's
        baud rate, parity and stop bits; the keys given override them).
    visa_options : dict or None
        Any other keyword of PyMeasure's ``VISAAdapter`` and PyVISA's ``open_resource``
        (``query_delay``, ``tcpip``, ...), for a resource name.

    Raises
    ------
    InvalidArgumentError
        A ``max_voltage`` that is not a positive number.
    ConfigError
        A bad configuration, or one of another protocol.

    Examples
    --------
    >>> from pymeasure.test import expected_protocol
    >>> from pihyst.rig.pymeasure import AsciiHVSupply
    >>> with expected_protocol(AsciiHVSupply, [(b"VOLT 12.50\\r\\n", None),
    ...                                        (b"MEAS:VOLT?\\r\\n", b"12.49\\r\\n")],
    ...                        config={"query_command": "MEAS:VOLT?"}) as supply:
    ...     supply.voltage_setpoint = 12.5
    ...     supply.voltage
    12.49
    """

    driver_class = AsciiSupply

    def __init__(self, adapter: Any, name: str = "ASCII HV supply", config: Any = None,
                 max_voltage: float | None = None, *, visa_library: str = "",
                 timeout: int | None = None, asrl: Mapping[str, Any] | None = None,
                 visa_options: Mapping[str, Any] | None = None) -> None:
        section = section_of(config, "supply", SupplyConfig, "ascii")
        super().__init__(adapter, name, section, _max_voltage(config, max_voltage),
                         _visa_keywords(visa_library, timeout, asrl, visa_options))


#: The Thorlabs-MDT693B-like dialect (docs/rig.md): commands echoed, '*' acknowledges.
MDT693B_DIALECT = {"terminator": "\r", "set_command": "xvoltage={volts:.2f}",
                   "query_command": "xvoltage?", "echo": True, "prompt": "*"}


class MDT693BLikeSupply(AsciiHVSupply):
    """A Thorlabs-MDT693B-like supply: ``xvoltage=12.00\\r`` is echoed and acknowledged
    by ``*``; ``xvoltage?\\r`` answers ``xvoltage?\\r*[  12.0]\\r``.

    Parameters
    ----------
    adapter : str, int or pymeasure Adapter
        A VISA resource name or a PyMeasure adapter.
    name : str, optional
        The instrument's name.
    config : RigConfig, path, SupplyConfig or dict, optional
        A dict's keys override :data:`MDT693B_DIALECT`; a whole configuration is used
        as it is.
    max_voltage : float, optional
        The highest setpoint it may be sent (default: ``[rig] u_max`` of a rig
        configuration, else 150 V).
    visa_library : str
        PyVISA's library, when ``adapter`` is a resource name (``"@py"``: pyvisa-py,
        ``"FILE.yaml@sim"``: pyvisa-sim; default: PyVISA's choice).
    timeout : int or None
        PyVISA's timeout (ms) for a resource name (default: ``timeout_s`` of the
        configuration).
    asrl : dict or None
        PyVISA's serial settings for an ``ASRL`` resource (default: the configuration's
        baud rate, parity and stop bits; the keys given override them).
    visa_options : dict or None
        Any other keyword of PyMeasure's ``VISAAdapter`` and PyVISA's ``open_resource``
        (``query_delay``, ``tcpip``, ...), for a resource name.

    Raises
    ------
    InvalidArgumentError
        A ``max_voltage`` that is not a positive number.
    ConfigError
        A bad configuration, or one of another protocol.

    Examples
    --------
    >>> from pymeasure.test import expected_protocol
    >>> from pihyst.rig.pymeasure import MDT693BLikeSupply
    >>> with expected_protocol(MDT693BLikeSupply,
    ...                        [(b"xvoltage=12.50\\r", b"xvoltage=12.50\\r*"),
    ...                         (b"xvoltage?\\r", b"xvoltage?\\r*[  12.5]\\r")]) as supply:
    ...     supply.voltage_setpoint = 12.5
    ...     supply.voltage
    12.5
    """

    def __init__(self, adapter: Any, name: str = "MDT693B-like supply", config: Any = None,
                 max_voltage: float | None = None, *, visa_library: str = "",
                 timeout: int | None = None, asrl: Mapping[str, Any] | None = None,
                 visa_options: Mapping[str, Any] | None = None) -> None:
        if config is None or isinstance(config, dict):
            config = {**MDT693B_DIALECT, **(config or {})}
        super().__init__(adapter, name, config, max_voltage, visa_library=visa_library,
                         timeout=timeout, asrl=asrl, visa_options=visa_options)


def _max_voltage(config: Any, max_voltage: float | None) -> float:
    if max_voltage is not None:
        return max_voltage
    if isinstance(config, (str, os.PathLike)):
        config = load_config(config)
    return config.rig.u_max if isinstance(config, RigConfig) else 150.0
