"""The fixed-rate loop: read the sensor -> compute the command -> limits and slew -> send ->
log, at absolute deadlines t_k = t_0 + k / rate on a monotonic clock.

A tick that ends after the next deadline is an overrun: it is counted and flagged, and
the schedule restarts from that moment (no burst of catch-up ticks, no tick skipped).

Safety on every exit path: the normal end, an exception, ``max_comm_errors`` consecutive
failed exchanges, ``max_invalid_readings`` consecutive invalid readings,
``max_overruns`` consecutive overruns, a readback that differs from the command, a
stuck sensor, the watchdog, Ctrl-C (SIGINT) and SIGTERM all end in :meth:`_shutdown`:
0 V (ramped at the slew limit when one is set), output off, and a log line saying why.
The run starts at 0 V with the output on and ramps to the program's first voltage.
"""

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pihyst.exceptions import InvalidArgumentError
from pihyst.rig._clock import WallClock
from pihyst.rig._log import TickRecord
from pihyst.rig._safety import SetpointGuard, SignalGuard, StopRun, Terminated, Watchdog

NAN = math.nan
#: how long the readback may take to fall to 0 V after the output is switched off
RESIDUAL_WAIT_S = 1.0
#: how long 0 V and output off are sent again after a failure (at least 3 times each): a
#: supply that answers a few exchanges with errors or not at all (bus noise, a busy
#: controller) is zeroed once it answers, however many of the run's tries it took
ZERO_RETRY_S = 2.0


@dataclass
class RunResult:
    """What a run did: why it stopped, its ticks, its timing.

    Parameters
    ----------
    reason : str
        Why the run stopped (``"end of the program"``, or what stopped it).
    completed : bool
        The program ran to its end.
    records : list of TickRecord
        Every tick: the ramp up, the run and the shutdown.
    period_s : float
        The loop's period (s).
    overruns : int
        Ticks that ended after the next tick's deadline.
    final_voltage_V : float
        The last voltage sent.
    zeroed : bool
        0 V was sent and the output switched off at the end.

    Examples
    --------
    >>> from pihyst.rig import Rig, VoltageProgram, parse_config
    >>> config = parse_config('[rig]\\nrate_hz = 10.0\\n'
    ...                       '[supply]\\nport = "pihystsim://supply"\\n'
    ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
    >>> with Rig(config) as rig:
    ...     result = rig.run(VoltageProgram([0.0, 20.0, 40.0, 20.0]), handle_signals=False)
    >>> result.completed, result.zeroed, len(result.column("voltage_V", phase="run"))
    (True, True, 4)
    """

    reason: str                  # why the run stopped
    completed: bool              # the program ran to its end
    records: list[TickRecord] = field(repr=False)
    period_s: float = 0.0
    overruns: int = 0
    final_voltage_V: float = NAN
    zeroed: bool = False         # 0 V was sent and the output switched off at the end

    def column(self, name: str, phase: str | None = None) -> np.ndarray:
        """One number column of the ticks, as floats.

        Parameters
        ----------
        name : str
            A number column of :class:`TickRecord` (``"voltage_V"``,
            ``"displacement_um"``, ``"late_s"``, ...).
        phase : str or None
            Only the ticks of this phase (``"ramp-up"``, ``"run"``, ``"shutdown"``);
            None: all.

        Returns
        -------
        ndarray
            One value per tick.

        Examples
        --------
        >>> from pihyst.rig import Rig, VoltageProgram, parse_config
        >>> config = parse_config('[rig]\\nrate_hz = 10.0\\n'
        ...                       '[supply]\\nport = "pihystsim://supply"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     result = rig.run(VoltageProgram([0.0, 20.0, 40.0, 20.0]), handle_signals=False)
        >>> result.column("voltage_V", phase="run")
        array([ 0., 20., 40., 20.])
        """
        rows = [r for r in self.records if phase is None or r.phase == phase]
        return np.array([getattr(r, name) for r in rows], dtype=float)

    def timing(self) -> dict[str, float]:
        """Loop timing: lateness of tick starts (jitter), busy time per tick, overruns.

        Returns
        -------
        dict of str to float
            ``ticks`` and ``overruns`` (counts), ``period_ms``, ``jitter_mean_ms``,
            ``jitter_p99_ms``, ``jitter_max_ms``, ``busy_mean_ms``, ``busy_max_ms`` and
            ``utilisation_pct`` (only the counts for a run without ticks).

        Examples
        --------
        >>> from pihyst.rig import Rig, VoltageProgram, parse_config
        >>> config = parse_config('[rig]\\nrate_hz = 10.0\\n'
        ...                       '[supply]\\nport = "pihystsim://supply"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     result = rig.run(VoltageProgram([0.0, 20.0, 40.0, 20.0]), handle_signals=False)
        >>> timing = result.timing()
        >>> timing["period_ms"], timing["overruns"], timing["ticks"] == len(result.records)
        (100.0, 0, True)
        """
        late = self.column("late_s")
        busy = self.column("busy_s")
        if late.size == 0:
            return {"ticks": 0, "overruns": 0}
        return {"ticks": int(late.size), "overruns": self.overruns,
                "period_ms": 1000 * self.period_s,
                "jitter_mean_ms": 1000 * float(np.mean(late)),
                "jitter_p99_ms": 1000 * float(np.percentile(late, 99)),
                "jitter_max_ms": 1000 * float(np.max(late)),
                "busy_mean_ms": 1000 * float(np.mean(busy)),
                "busy_max_ms": 1000 * float(np.max(busy)),
                "utilisation_pct": 100 * float(np.mean(busy)) / self.period_s}


class Controller:
    """Runs programs on a supply and a sensor.

    Parameters
    ----------
    supply : ModbusRtuSupply or AsciiSupply
        The supply's driver.
    sensor : KeyenceSensor
        The sensor's driver.
    settings : LoopSettings
        Rate, limits, slew and the stop criteria ([rig] of the configuration).
    log : CsvRunLog, optional
        Receives every tick and the notes.
    clock : object with ``now()`` and ``sleep(s)``
        Default: the monotonic wall clock. A VirtualClock runs in virtual time.
    watchdog : bool, optional
        Run the stall watchdog thread (default: with a wall clock only; in virtual time
        a stall has no meaning).
    handle_signals : bool
        Turn SIGINT and SIGTERM into a safe stop (main thread only).
    stop_requested : callable, optional
        Asked after every tick; True stops the run safely (reason 'stop requested'), as a
        GUI's abort button does (``pihyst.rig.pymeasure``).

    Examples
    --------
    >>> from pihyst.rig import Rig, Controller, VoltageProgram, parse_config
    >>> config = parse_config('[rig]\\nrate_hz = 10.0\\n'
    ...                       '[supply]\\nport = "pihystsim://supply"\\n'
    ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
    >>> with Rig(config) as rig:
    ...     controller = Controller(rig.supply, rig.sensor, config.rig, clock=rig.clock,
    ...                             handle_signals=False)
    ...     result = controller.run(VoltageProgram([10.0, 20.0]))
    >>> result.reason, rig.emulators.supply_state.last_setpoint_V
    ('end of the program', 0.0)
    """

    def __init__(self, supply: Any, sensor: Any, settings: Any, *, log: Any = None,
                 clock: Any = WallClock, watchdog: bool | None = None,
                 handle_signals: bool = True,
                 stop_requested: Callable[[], bool] | None = None) -> None:
        self.supply, self.sensor, self.settings = supply, sensor, settings
        self.log = log
        self.clock = clock
        self.use_watchdog = (not getattr(clock, "virtual", False)) if watchdog is None \
            else watchdog
        self.handle_signals = handle_signals
        self.stop_requested = stop_requested
        self._supply_lock = threading.RLock()
        self._log_error: str | None = None  # why the log failed; not written to after

    # ------------------------------------------------------------------ helpers
    @property
    def log_error(self) -> str | None:
        """Why the log could not be written (None: it could)."""
        return self._log_error

    def _note(self, text):
        self._to_log("note", text)

    def _to_log(self, method, item):
        """Write to the log; a log that fails (disk full, a drive unplugged) is given up,
        never raised here: the shutdown that zeroes the supply writes to it too. The run
        stops at the end of the tick (:meth:`_check`)."""
        if self.log is None or self._log_error is not None:
            return
        try:
            getattr(self.log, method)(item)
        except Exception as err:  # noqa: BLE001 - whatever broke, the supply comes first
            self._log_error = f"{type(err).__name__}: {err}"

    def _send(self, u):
        # the guard learns the outcome under the supply lock: the watchdog thread may zero
        # the supply between this send and the next, and must leave the guard knowing it
        with self._supply_lock:
            if self._watchdog is not None and self._watchdog.tripped is not None:
                raise StopRun(f"watchdog: the loop stalled for {self._watchdog.tripped:.3f} s "
                              f"(limit {self._watchdog.limit_s:.3f} s); output zeroed")
            try:
                self.supply.set_voltage(u)
            except OSError:
                self.guard.failed(u)
                raise
            except InvalidArgumentError as err:     # refused before sending: it stays put
                raise StopRun(str(err)) from None
            self.guard.sent(u)

    def _zero_from_watchdog(self):
        if self._supply_lock.acquire(timeout=max(0.05, self.settings.period_s)):
            try:
                self.supply.set_voltage(0.0)
                self.guard.sent(0.0)      # the shutdown must not ramp up again from 0 V
                self.supply.output_off()
            except Exception:  # noqa: BLE001 - the loop reports the stall itself
                self.guard.failed(0.0)
            finally:
                self._supply_lock.release()

    def _read(self):
        """(displacement or NaN, status, error or None): errors are returned, not raised."""
        try:
            reading = self.sensor.read()
        except OSError as err:
            return NAN, f"error: {err}", _from("sensor", err)
        if not reading.valid:
            self._invalid += 1
            return NAN, reading.status, None
        self._invalid = 0
        return reading.value, "ok", None

    def _wait(self, deadline):
        if self._watchdog is not None:
            self._watchdog.idle()
        now = self.clock.now()
        if deadline > now:
            self.clock.sleep(deadline - now)
        if self._watchdog is not None:
            self._watchdog.busy()
        start = self.clock.now()
        return start, start - deadline

    def _advance(self, deadline, busy_end):
        """Next deadline; an overrun restarts the schedule at the end of the tick."""
        nxt = deadline + self.settings.period_s
        if busy_end > nxt:
            self.overruns += 1
            self._consecutive_overruns += 1
            return busy_end, 1
        self._consecutive_overruns = 0
        return nxt, 0

    # ------------------------------------------------------------------ one tick
    def _tick(self, phase, deadline, command_of):
        s = self.settings
        start, late = self._wait(deadline)
        y, status, error = self._read()
        reference, command = command_of(y)
        u = self.guard.check(command)
        supply_status = "ok"
        sent = NAN
        try:
            self._send(u)
            sent = u
        except OSError as err:
            error = error or _from("supply", err)
            supply_status = f"error: {err}"
        readback = NAN
        if (self.supply.has_readback and phase == "run" and supply_status == "ok"
                and self.tick % s.readback_every == 0):
            try:
                with self._supply_lock:
                    readback = self.supply.read_voltage()
            except OSError as err:
                error = error or f"supply readback: {err}"
                supply_status = f"error: {err}"
        # consecutive ticks with a failed exchange
        if error is None:
            self._comm_errors = 0
        else:
            self._comm_errors += 1
            self._last_error = error
        # the first trouble of the current streak: what a stop names first
        trouble = error or (None if status == "ok" else f"sensor reading {status}")
        if trouble is None:
            self._first_cause = None
        elif self._first_cause is None:
            self._first_cause = (self.tick, trouble)
        end = self.clock.now()
        nxt, overrun = self._advance(deadline, end)
        record = TickRecord(self.tick, start - self.t0, phase, reference, command, sent,
                            readback, y, status, supply_status, overrun, late, end - start)
        self._record(record)
        self._check(record)
        return nxt

    def _record(self, record):
        self.records.append(record)
        self._to_log("write", record)
        self.tick += 1

    def _stop(self, message):
        """StopRun with ``message``, naming first the trouble that began the streak of
        bad ticks it ends (a silent sensor, before the readback that the supply's own
        watchdog then zeroed)."""
        cause = self._first_cause
        if cause is not None and cause[1] not in message and not (
                cause[1].startswith("sensor reading") and "invalid sensor readings" in message):
            message = f"{cause[1]} (from tick {cause[0]}); then {message}"
        raise StopRun(message)

    def _check(self, r):
        s = self.settings
        if self.stop_requested is not None and self.stop_requested():
            raise StopRun("stop requested")
        if self._log_error is not None:
            raise StopRun(f"the log could not be written ({self._log_error})")
        if self._comm_errors >= s.max_comm_errors:
            self._stop(f"{self._comm_errors} consecutive communication errors (last: "
                       f"{self._last_error})")
        if self._invalid >= s.max_invalid_readings:
            self._stop(f"{self._invalid} consecutive invalid sensor readings "
                       f"({r.sensor_status})")
        if self._consecutive_overruns >= s.max_overruns:
            self._stop(f"{self._consecutive_overruns} consecutive overruns: the ticks take "
                       f"longer than the period {1000 * s.period_s:.1f} ms (last "
                       f"{1000 * r.busy_s:.1f} ms)")
        if not math.isnan(r.readback_V) and not math.isnan(r.voltage_V) and \
                abs(r.readback_V - r.voltage_V) > s.readback_tolerance_V:
            self._stop(f"readback {r.readback_V:.3f} V differs from the command "
                       f"{r.voltage_V:.3f} V by more than {s.readback_tolerance_V:g} V")
        if s.stuck_ticks and r.sensor_status == "ok":
            self._recent.append((r.displacement_um, r.voltage_V))
            del self._recent[:-s.stuck_ticks]
            if len(self._recent) == s.stuck_ticks:
                ys = {y for y, _ in self._recent}
                us = [u for _, u in self._recent if not math.isnan(u)]
                if len(ys) == 1 and us and max(us) - min(us) > s.stuck_volts:
                    self._stop(f"sensor value stuck at {r.displacement_um:g} µm for "
                               f"{s.stuck_ticks} ticks while the voltage moved "
                               f"{max(us) - min(us):.3g} V")

    # ------------------------------------------------------------------ run
    def run(self, program: Any) -> RunResult:
        """Run ``program`` to its end or to a stop; always end at 0 V, output off.

        Parameters
        ----------
        program : VoltageProgram, FeedforwardProgram or FeedbackProgram
            What to drive, tick by tick (or any object with their interface).

        Returns
        -------
        RunResult
            Why it stopped, and every tick.

        Raises
        ------
        InvalidArgumentError
            Rig limits the supply may not be sent, before anything is sent.
        Exception
            An unexpected error of the program or a driver, raised again after the safe
            stop (Ctrl-C, SIGTERM and the stop criteria end the run with a reason
            instead).

        Examples
        --------
        >>> from pihyst.rig import Rig, Controller, VoltageProgram, parse_config
        >>> config = parse_config('[rig]\\nrate_hz = 10.0\\n'
        ...                       '[supply]\\nport = "pihystsim://supply"\\n'
        ...                       '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> with Rig(config) as rig:
        ...     controller = rig.controller(handle_signals=False)
        ...     result = controller.run(VoltageProgram([10.0, 20.0, 30.0]))
        >>> result.completed, result.final_voltage_V
        (True, 0.0)
        """
        s = self.settings
        check_limits(self.supply, s)
        self.records: list[TickRecord] = []
        self.tick, self.overruns = 0, 0
        self._comm_errors = self._invalid = self._consecutive_overruns = 0
        self._last_error = ""
        self._first_cause = None
        self._log_error = None
        self._recent: list[tuple[float, float]] = []
        self._watchdog = None
        max_step = None if s.slew_V_per_s is None else s.slew_V_per_s * s.period_s
        self.guard = SetpointGuard(s.u_min, s.u_max, max_step)
        ramp = s.start_ramp_V_per_s * s.period_s
        completed, reason, error = False, None, None
        self.t0 = deadline = self.clock.now()
        signals = SignalGuard() if self.handle_signals else None
        if signals is not None:
            signals.__enter__()
        try:
            if self.use_watchdog:
                limit = s.watchdog_periods * s.period_s
                self._watchdog = Watchdog(limit, self._zero_from_watchdog).start()
                self._watchdog.busy()
            watchdog = getattr(self.supply, "has_watchdog", False)
            for attempt in range(s.max_comm_errors):
                try:
                    with self._supply_lock:
                        self.supply.set_voltage(0.0)
                        if watchdog:
                            # from now on the supply switches itself off when pihyst
                            # goes silent (killed, hung): every request feeds it
                            self.supply.arm_watchdog()
                        self.supply.output_on()
                    break
                except OSError as err:
                    if attempt == s.max_comm_errors - 1:
                        raise StopRun(f"could not start: supply: {err}") from None
            self.t0 = deadline = self.clock.now()
            if watchdog:
                self._note(f"supply watchdog armed: output off after "
                           f"{self.supply.cfg.watchdog_s:g} s without a request")
            self._note(f"start: 0 V, output on; {program.describe()}")
            if hasattr(program, "bind_tick"):
                program.bind_tick(s.period_s)
            target = program.initial_voltage()
            if not math.isfinite(target):
                raise StopRun(f"refused a non-finite first setpoint ({target})")
            target = min(max(target, s.u_min), s.u_max)
            u = 0.0
            while u != target:
                u = min(target, u + ramp) if target > u else max(target, u - ramp)
                deadline = self._tick("ramp-up", deadline, lambda y, u=u: (NAN, u))
            program.start()
            for k in range(program.n_ticks):
                deadline = self._tick("run", deadline,
                                      lambda y, k=k: program.command(k, None if math.isnan(y)
                                                                     else y))
            completed, reason = True, "end of the program"
        except StopRun as err:
            reason = str(err)
        except KeyboardInterrupt:
            reason = "interrupted (SIGINT, Ctrl-C)"
        except Terminated as err:
            reason = f"terminated ({err})"
        except Exception as err:
            reason = f"error: {type(err).__name__}: {err}"
            error = err
        finally:
            if signals is not None:
                signals.hold()
            try:
                zeroed, final = self._shutdown(reason or "interrupted", deadline)
            finally:
                if self._watchdog is not None:
                    self._watchdog.stop()
                if signals is not None:
                    signals.__exit__(None, None, None)
        result = RunResult(reason, completed, self.records, s.period_s, self.overruns, final,
                           zeroed)
        if error is not None:
            raise error
        return result

    def _shutdown(self, reason, deadline):
        """Ramp to 0 V at the slew limit (one step per tick, reading the sensor unless it
        is the sensor that failed), switch the output off, and say why in the log. Any
        error of a driver here counts as a failed exchange, never leaves this method: an
        exception out of it would leave the supply where it is."""
        s = self.settings
        self._note(f"stopping: {reason}")
        # a failing sensor would cost its timeout on every step of the ramp
        read_sensor = "sensor" not in reason and not reason.startswith("watchdog")
        step = None if s.slew_V_per_s is None else s.slew_V_per_s * s.period_s
        failures = 0
        while self.guard.hi > 0 and step is not None and failures < 2:
            start, late = self._wait(deadline)
            try:
                y, status, _ = self._read() if read_sensor else (NAN, "not read", None)
            except Exception as err:  # noqa: BLE001 - see the docstring
                y, status = NAN, f"error: {err}"
            try:
                with self._supply_lock:
                    # chosen under the lock: the watchdog may have zeroed the supply
                    u = self.guard.check(max(0.0, self.guard.hi - step))
                    if self.guard.hi <= 0:
                        break
                    try:
                        self.supply.set_voltage(u)
                    except Exception:
                        self.guard.failed(u)
                        raise
                    self.guard.sent(u)
                sent, supply_status = u, "ok"
            except Exception as err:  # noqa: BLE001 - see the docstring
                failures += 1
                sent, supply_status = NAN, f"error: {err}"
            end = self.clock.now()
            deadline, overrun = self._advance(deadline, end)
            self._record(TickRecord(self.tick, start - self.t0, "shutdown", NAN, u, sent, NAN,
                                    y, status, supply_status, overrun, late, end - start))
        if self.guard.hi > 0:
            self._note("the supply did not follow the ramp: 0 V at once" if step is not None
                       else "no slew limit: 0 V at once")
        problems = []
        for what, call in (("0 V", lambda: self.supply.set_voltage(0.0)),
                           ("output off", self.supply.output_off)):
            error = self._until_sent(call)
            if error is not None:
                problems.append(f"could not send {what}: {error}")
        if not problems and getattr(self.supply, "has_watchdog", False):
            try:
                with self._supply_lock:
                    self.supply.disarm_watchdog()      # the output is off already
            except Exception as err:  # noqa: BLE001 - see the docstring
                self._note(f"could not disarm the supply's watchdog: {err}")
        if not problems and self.supply.has_readback:
            left = self._residual_voltage()
            if left is not None:
                problems.append(f"the supply reads back {left:.3f} V after 0 V and output off")
        zeroed = not problems
        if zeroed:
            self.guard.sent(0.0)
            self._note(f"stopped: {reason}; 0 V sent and output off")
        else:
            self._note(f"stopped: {reason}; WARNING: {'; '.join(problems)} - the beam may "
                       "still be charged")
        return zeroed, self.guard.last if zeroed else NAN

    def _until_sent(self, call):
        """Send ``call`` to the supply until it succeeds, at least 3 times and for
        ZERO_RETRY_S, a tick apart; None when sent, else the last error."""
        give_up = self.clock.now() + ZERO_RETRY_S
        attempt = 0
        while True:
            try:
                with self._supply_lock:
                    call()
                return None
            except Exception as err:  # noqa: BLE001 - as in _shutdown
                attempt += 1
                if attempt >= 3 and self.clock.now() >= give_up:
                    return err
            self.clock.sleep(self.settings.period_s)

    def _residual_voltage(self):
        """The readback after 0 V and output off when it stays above the tolerance for
        RESIDUAL_WAIT_S (a supply that acknowledges but does not follow), else None."""
        s = self.settings
        value = None
        for attempt in range(max(1, math.ceil(RESIDUAL_WAIT_S * s.rate_hz))):
            if attempt:
                self.clock.sleep(s.period_s)
            try:
                with self._supply_lock:
                    value = self.supply.read_voltage()
            except Exception:  # noqa: BLE001 - as in _shutdown
                continue
            if value is None or abs(value) <= s.readback_tolerance_V:
                return None
        return value

def _from(device, err):
    """``device: what went wrong`` (the drivers' messages often name the device already)."""
    text = str(err)
    return text if text.startswith(device) else f"{device}: {text}"


def check_limits(supply: Any, settings: Any) -> None:
    """InvalidArgumentError unless ``supply`` may be sent every voltage within the rig's
    limits ``settings.u_min``..``u_max`` (the guard keeps every setpoint in them, and the
    checks are monotone: the two ends suffice)."""
    for volts in (settings.u_min, settings.u_max):
        try:
            supply.check_setpoint(volts)
        except InvalidArgumentError as err:
            raise InvalidArgumentError(f"[rig] limits {settings.u_min:g} .. {settings.u_max:g} "
                                       f"V: {err}") from None
