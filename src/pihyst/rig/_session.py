"""A rig session: the instruments of a configuration (real, or emulated in this process),
and a program run on them into a log."""

import datetime
import os
from collections.abc import Callable, Iterable
from typing import Any

from pihyst._version import __version__
from pihyst.model._units import display_unit
from pihyst.rig import _serial_handlers
from pihyst.rig._clock import VirtualClock, WallClock
from pihyst.rig._controller import Controller, RunResult, check_limits
from pihyst.rig._emulators import Emulators
from pihyst.rig._log import CsvRunLog
from pihyst.rig._sensor import open_sensor
from pihyst.rig._supply import open_supply


def is_emulated(config: Any) -> bool:
    """Whether both ports of ``config`` are ``pihystsim://`` URLs (in-process emulators).

    Parameters
    ----------
    config : RigConfig
        The configuration.

    Returns
    -------
    bool
        True if the supply's and the sensor's ports are both emulated.

    Examples
    --------
    >>> from pihyst.rig import RigConfig, SensorConfig, SupplyConfig, is_emulated
    >>> is_emulated(RigConfig(supply=SupplyConfig(port="pihystsim://supply"),
    ...                       sensor=SensorConfig(port="pihystsim://sensor")))
    True
    >>> is_emulated(RigConfig())
    False
    """
    return all(_serial_handlers.url_name(c.port) is not None
               for c in (config.supply, config.sensor))


class Rig:
    """The supply and sensor drivers of ``config``, opened; a context manager that closes
    them (and stops the emulators it started).

    Parameters
    ----------
    config : RigConfig
        The instruments.
    emulate : bool, optional
        Start the emulated instruments in this process (default: when both ports are
        ``pihystsim://`` URLs).
    clock : clock, optional
        Default: a VirtualClock with emulators (runs take the time of their computation),
        else the wall clock.
    real_time : bool
        With emulators, run on the wall clock (runs take their real time).
    plant : str, optional
        The emulators' simulated beam (default: ``[emulator] plant``).
    faults : iterable of Fault
        Faults the emulators inject.

    Raises
    ------
    RigError
        A port that does not open (the ports already opened are closed).

    Examples
    --------
    >>> from pihyst.rig import Fault, Rig, VoltageProgram, parse_config
    >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
    ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
    >>> with Rig(config, faults=[Fault("no-reply", "sensor")]) as rig:
    ...     result = rig.run(VoltageProgram([10.0] * 20), handle_signals=False)
    >>> result.completed, result.zeroed
    (False, True)
    >>> result.reason[:35]
    '3 consecutive communication errors '
    """

    def __init__(self, config: Any, *, emulate: bool | None = None, clock: Any = None,
                 real_time: bool = False, plant: str | None = None,
                 faults: Iterable[Any] = ()) -> None:
        self.config = config
        self.emulate = is_emulated(config) if emulate is None else emulate
        if clock is None:
            clock = VirtualClock() if self.emulate and not real_time else WallClock
        self.clock = clock
        self.emulators: Emulators | None = None
        self._names: list[tuple[str, Any]] = []
        if self.emulate:
            self.emulators = Emulators(config, plant=plant, faults=faults, t0=clock.now())
            for what, device in self.emulators.devices.items():
                port = getattr(config, what).port
                name = _serial_handlers.url_name(port) or f"{what}-{id(self):x}"
                _serial_handlers.register(name, device, clock)
                self._names.append((name, device))
            supply_url, sensor_url = (f"{_serial_handlers.SCHEME}://{n}" for n, _ in self._names)
        else:
            supply_url, sensor_url = config.supply.port, config.sensor.port
        from pihyst.rig._ports import open_port
        self.supply: Any = None
        self.sensor: Any = None
        try:
            s, n = config.supply, config.sensor
            self.supply = open_supply(s, clock, port=open_port(
                supply_url, s.baudrate, s.timeout_s, "supply", s.parity, s.stopbits))
            self.sensor = open_sensor(n, port=open_port(
                sensor_url, n.baudrate, n.timeout_s, "sensor", n.parity, n.stopbits))
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        """Close the drivers' ports and stop the emulators (a second close does nothing).

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> rig = Rig(config)
        >>> rig.close(); rig.close()
        >>> rig.supply.port.is_open
        False
        """
        for driver in (self.supply, self.sensor):
            if driver is not None:
                try:
                    driver.close()
                except OSError:
                    pass
        for name, device in self._names:
            _serial_handlers.unregister(name, device)
        self._names = []

    def __enter__(self) -> "Rig":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def describe(self) -> str:
        """One line for the log: emulated or real instruments, virtual or real time.

        Returns
        -------
        str
            The line.

        Examples
        --------
        >>> from pihyst.rig import Rig, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     rig.describe()
        "emulated instruments on the simulated beam 'paper-beam', virtual time"
        """
        where = "emulated instruments" if self.emulate else "instruments"
        time_kind = "virtual time" if getattr(self.clock, "virtual", False) else "real time"
        beam = f" on the simulated beam '{self.emulators.plant.name}'" if self.emulators else ""
        return f"{where}{beam}, {time_kind}"

    def controller(self, log: Any = None, *, watchdog: bool | None = None,
                   handle_signals: bool = True,
                   stop_requested: Callable[[], bool] | None = None) -> Controller:
        """A :class:`Controller` on this rig's drivers, limits and clock.

        Parameters
        ----------
        log : CsvRunLog or None
            Receives every tick and the notes.
        watchdog : bool or None
            Run the stall watchdog thread (default: with a wall clock only).
        handle_signals : bool
            Turn SIGINT and SIGTERM into a safe stop (main thread only).
        stop_requested : callable or None
            Asked after every tick; True stops the run safely.

        Returns
        -------
        Controller
            The controller.

        Examples
        --------
        >>> from pihyst.rig import Rig, VoltageProgram, parse_config
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     result = rig.controller(handle_signals=False,
        ...                             stop_requested=lambda: True).run(VoltageProgram([5.0]))
        >>> result.reason
        'stop requested'
        """
        return Controller(self.supply, self.sensor, self.config.rig, log=log,
                          clock=self.clock, watchdog=watchdog, handle_signals=handle_signals,
                          stop_requested=stop_requested)

    def run(self, program: Any, log_path: str | os.PathLike[str] | None = None, *,
            notes: Iterable[str] = (), fsync: bool = False,
            handle_signals: bool = True) -> RunResult:
        """Run ``program`` into a log; always end at 0 V, output off.

        Parameters
        ----------
        program : VoltageProgram, FeedforwardProgram or FeedbackProgram
            What to drive, tick by tick.
        log_path : str, os.PathLike or None
            The log: CSV, or HDF5 for ``.h5``/``.hdf5`` (needs h5py); None: no file.
        notes : iterable of str
            Lines added to the log's metadata.
        fsync : bool
            Force every row to the disk (see :class:`CsvRunLog`).
        handle_signals : bool
            Turn SIGINT and SIGTERM into a safe stop (main thread only).

        Returns
        -------
        RunResult
            Why it stopped, and every tick.

        Raises
        ------
        InvalidArgumentError
            Rig limits the supply may not be sent, before the log is opened.

        Examples
        --------
        >>> import os, tempfile
        >>> from pihyst.rig import Rig, VoltageProgram, parse_config, read_run_log
        >>> config = parse_config('[supply]\\nport = "pihystsim://supply"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> path = os.path.join(tempfile.mkdtemp(), "run.csv")
        >>> with Rig(config) as rig:
        ...     result = rig.run(VoltageProgram([10.0, 20.0]), path, notes=["sample 3"],
        ...                      handle_signals=False)
        >>> columns, notes = read_run_log(path)
        >>> len(columns["tick"]) == len(result.records), "sample 3" in notes
        (True, True)
        """
        check_limits(self.supply, self.config.rig)
        log: Any = None
        if log_path is not None:
            lines = metadata(self, program, notes)
            if str(log_path).lower().endswith((".h5", ".hdf5")):
                from pihyst.rig._hdf5 import Hdf5RunLog
                log = Hdf5RunLog(log_path, lines, fsync=fsync)
            else:
                log = CsvRunLog(log_path, lines, fsync=fsync)
        controller = self.controller(log, handle_signals=handle_signals)
        try:
            return controller.run(program)
        finally:
            if log is not None:
                try:
                    log.close()
                except Exception:
                    # a log that already failed during the run (the run stopped for it)
                    if controller.log_error is None:
                        raise


def metadata(rig: Rig, program: Any, notes: Iterable[str] = ()) -> list[str]:
    """The ``#`` lines at the top of a run log."""
    cfg, r = rig.config, rig.config.rig
    slew = "none" if r.slew_V_per_s is None else f"{r.slew_V_per_s:g} V/s"
    lines = [f"pihyst {__version__} rig run log",
             f"start: {datetime.datetime.now(datetime.timezone.utc).isoformat(timespec='seconds')}",
             f"program: {program.describe()}",
             f"reference unit: {display_unit(program.reference_unit)}",
             f"rate: {r.rate_hz:g} Hz; limits: {r.u_min:g} .. {r.u_max:g} V; slew: {slew}",
             f"instruments: {rig.describe()}",
             f"supply: {rig.supply.describe()}",
             f"sensor: {rig.sensor.describe()}",
             f"configuration: {cfg.describe()}"]
    if rig.emulators is not None:
        lines.append(f"beam: {rig.emulators.plant.describe()}")
    lines += list(notes)
    lines += [f"config| {line}" for line in cfg.text.splitlines() if line.strip()]
    return lines


def remove_quietly(path: str | os.PathLike[str]) -> None:
    try:
        os.remove(path)
    except OSError:
        pass
