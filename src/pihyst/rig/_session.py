"""A rig session: the instruments of a configuration (real, or emulated in this process),
and a program run on them into a log."""

import datetime
import os

from pihyst._version import __version__
from pihyst.model._units import display_unit
from pihyst.rig import _serial_handlers
from pihyst.rig._clock import VirtualClock, WallClock
from pihyst.rig._controller import Controller, check_limits
from pihyst.rig._emulators import Emulators
from pihyst.rig._log import CsvRunLog
from pihyst.rig._sensor import open_sensor
from pihyst.rig._supply import open_supply


def is_emulated(config):
    """True if both ports of ``config`` are ``pihystsim://`` URLs (in-process emulators)."""
    return all(_serial_handlers.url_name(c.port) is not None
               for c in (config.supply, config.sensor))


class Rig:
    """The supply and sensor drivers of ``config``, opened; a context manager that closes
    them (and stops the emulators it started).

    Parameters
    ----------
    config : RigConfig
    emulate : bool, optional
        Start the emulated instruments in this process (default: when both ports are
        ``pihystsim://`` URLs).
    clock : clock, optional
        Default: a VirtualClock with emulators (runs take the time of their computation),
        else the wall clock. ``real_time=True`` forces the wall clock.
    plant : str, optional
        The emulators' simulated beam (default: ``[emulator] plant``).
    faults : iterable of Fault
        Faults the emulators inject.
    """

    def __init__(self, config, *, emulate=None, clock=None, real_time=False, plant=None,
                 faults=()):
        self.config = config
        self.emulate = is_emulated(config) if emulate is None else emulate
        if clock is None:
            clock = VirtualClock() if self.emulate and not real_time else WallClock
        self.clock = clock
        self.emulators = None
        self._names = []
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
        self.supply = self.sensor = None
        try:
            s, n = config.supply, config.sensor
            self.supply = open_supply(s, clock, port=open_port(
                supply_url, s.baudrate, s.timeout_s, "supply", s.parity, s.stopbits))
            self.sensor = open_sensor(n, port=open_port(
                sensor_url, n.baudrate, n.timeout_s, "sensor", n.parity, n.stopbits))
        except BaseException:
            self.close()
            raise

    def close(self):
        for driver in (self.supply, self.sensor):
            if driver is not None:
                try:
                    driver.close()
                except OSError:
                    pass
        for name, device in self._names:
            _serial_handlers.unregister(name, device)
        self._names = []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def describe(self):
        where = "emulated instruments" if self.emulate else "instruments"
        time_kind = "virtual time" if getattr(self.clock, "virtual", False) else "real time"
        beam = f" on the simulated beam '{self.emulators.plant.name}'" if self.emulators else ""
        return f"{where}{beam}, {time_kind}"

    def controller(self, log=None, **kwargs):
        return Controller(self.supply, self.sensor, self.config.rig, log=log,
                          clock=self.clock, **kwargs)

    def run(self, program, log_path=None, *, notes=(), fsync=False, handle_signals=True):
        """Run ``program`` into the log ``log_path`` (CSV, or HDF5 for .h5/.hdf5; None:
        no file); returns the :class:`RunResult`. Rig limits the supply may not be sent
        are an InvalidArgumentError before the log is opened."""
        check_limits(self.supply, self.config.rig)
        log = None
        if log_path is not None:
            cls = CsvRunLog
            if str(log_path).lower().endswith((".h5", ".hdf5")):
                from pihyst.rig._hdf5 import Hdf5RunLog as cls
            log = cls(log_path, metadata(self, program, notes), fsync=fsync)
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


def metadata(rig, program, notes=()):
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


def remove_quietly(path):
    try:
        os.remove(path)
    except OSError:
        pass
