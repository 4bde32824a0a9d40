"""PyMeasure Procedures that run ``pihyst rig record`` and ``track``: the rig
of a configuration file (real instruments, or the emulated ones of ``pihystsim://``
ports), pihyst's controller with all its safety (limits, slew, the start ramp, 0 V and
output off on every way out), and every tick emitted as a result as it happens, so that
PyMeasure's ManagedWindow plots the loop live and its Results file keeps it.

The emitted columns are those of pihyst's run log (:data:`~pihyst.rig.COLUMNS`).
:class:`RigProcedure` is the base for procedures of one's own: it opens the rig and runs
a program on it, emitting every tick (examples/pymeasure_learn.py builds ``pihyst rig
learn``'s iterative learning on it). PyMeasure's abort button stops the run through the
controller (reason 'stop requested'): ramp to 0 V, output off. A run that stops early for
any other reason (a fault, a sensor out of range) raises :class:`RunStopped` after that
same shutdown, so the Worker marks the experiment failed.
"""

import inspect
import logging
from collections.abc import Callable
from dataclasses import asdict
from typing import Any

import numpy as np
from pymeasure.experiment import (
    BooleanParameter,
    FloatParameter,
    IntegerParameter,
    ListParameter,
    Parameter,
    Procedure,
)

from pihyst.exceptions import InvalidArgumentError
from pihyst.rig._log import COLUMNS
from pihyst.rig._programs import FeedbackProgram, FeedforwardProgram, VoltageProgram
from pihyst.rig.pymeasure._inputs import (
    SIGNALS,
    desired_per_tick,
    model_at_tick,
    signal_voltages,
)

log = logging.getLogger(__name__)
log.addHandler(logging.NullHandler())


class RunStopped(RuntimeError):
    """A rig run stopped before its program's end (the supply was zeroed unless the
    message says otherwise).

    Examples
    --------
    >>> from pihyst.rig.pymeasure import RunStopped
    >>> issubclass(RunStopped, RuntimeError)
    True
    """


class _EmitLog:
    """The controller's log: every tick goes to the procedure as a result (the status
    texts without commas, PyMeasure's delimiter), every note to the Python log."""

    def __init__(self, procedure: "RigProcedure", n_ticks: int,
                 extra: dict[str, Any] | None = None,
                 progress: tuple[float, float] = (0.0, 100.0)) -> None:
        self.procedure = procedure
        self.n_ticks = max(1, n_ticks)
        self.extra = extra or {}
        self.progress = progress
        self.notes: list[str] = []

    def write(self, record: Any) -> None:
        row = asdict(record)
        for key in ("sensor_status", "supply_status"):
            row[key] = row[key].replace(",", ";")
        self.procedure.emit("results", {**row, **self.extra})
        if record.phase == "run":
            lo, hi = self.progress
            done = min(1.0, (record.tick + 1) / self.n_ticks)
            self.procedure.emit("progress", lo + (hi - lo) * done)

    def note(self, text: str) -> None:
        self.notes.append(text)
        log.info(text)


class RigProcedure(Procedure):
    """The base of the rig's procedures: the configuration file, the rig it opens in
    :meth:`open_rig`, and :meth:`run_program`, one safe run of a program (a
    :class:`~pihyst.rig.VoltageProgram`, ...) with every tick emitted. A subclass
    builds its program(s) in ``startup`` (then calls ``open_rig``) and runs them in
    ``execute``; :meth:`shutdown` closes the rig.

    A subclass's own Parameters are keywords of its constructor too (unless it defines
    ``__init__``): ``MyProcedure(config=..., trials=3)``, as ``help()`` shows.

    Parameters
    ----------
    config : str or None
        The rig configuration (TOML file); None: the Parameter's default.
    real_time : bool or None
        Run emulated instruments on the wall clock; None: the Parameter's default (no).

    Raises
    ------
    TypeError
        A keyword that is not a Parameter of the procedure.

    Examples
    --------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "rig.toml")
    >>> with open(path, "w") as f:
    ...     _ = f.write('[rig]\\nrate_hz = 10.0\\n[supply]\\nport = "pihystsim://supply"\\n'
    ...                 '[sensor]\\nport = "pihystsim://sensor"\\n')
    >>> from pihyst.rig import VoltageProgram
    >>> from pihyst.rig.pymeasure import RigProcedure
    >>> procedure = RigProcedure(config=path)
    >>> _ = procedure.open_rig(procedure.load_config())
    >>> result = procedure.run_program(VoltageProgram([10.0, 20.0]))
    >>> procedure.shutdown()
    >>> result.completed, procedure.emulators.supply_state.last_setpoint_V
    (True, 0.0)
    """

    config = Parameter("Rig configuration (TOML file)", default="examples/rig/emulated.toml")
    real_time = BooleanParameter("Wall-clock time for emulated instruments", default=False)

    DATA_COLUMNS = list(COLUMNS)

    rig: Any = None
    results_of_runs: list[Any] | None = None
    #: emulated instruments only: faults to inject (:class:`~pihyst.rig.Fault`)
    faults: tuple[Any, ...] = ()
    #: the rig's emulated instruments (None on a real rig), kept after the rig closes
    emulators: Any = None

    def __init__(self, *, config: str | None = None, real_time: bool | None = None) -> None:
        self._set_parameters(config=config, real_time=real_time)

    def _set_parameters(self, **values: Any) -> None:
        """PyMeasure's Procedure.__init__ with the values given (None: the default)."""
        Procedure.__init__(self, **{k: v for k, v in values.items() if v is not None})

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "__init__" not in vars(cls):
            cls.__init__ = _parameter_keywords(cls)  # type: ignore[method-assign]

    def emit(self, topic: str, record: Any) -> None:
        """Send a result; outside a PyMeasure Worker (which replaces this), results are
        not sent anywhere: the run's ticks are in :attr:`result` (``records``).

        Parameters
        ----------
        topic : str
            ``"results"`` (a dict of one tick's columns) or ``"progress"`` (percent).
        record : dict or float
            The tick, or the progress.

        Examples
        --------
        >>> from pihyst.rig.pymeasure import RigProcedure
        >>> RigProcedure().emit("progress", 50.0)    # nowhere to send it
        """

    def should_stop(self) -> bool:
        """Whether the run is to stop; outside a PyMeasure Worker (which replaces this),
        nothing asks for a stop.

        Returns
        -------
        bool
            False.

        Examples
        --------
        >>> from pihyst.rig.pymeasure import RigProcedure
        >>> RigProcedure().should_stop()
        False
        """
        return False

    def load_config(self) -> Any:
        """The rig configuration of the ``config`` Parameter, read and checked.

        Returns
        -------
        RigConfig
            The configuration.

        Raises
        ------
        ConfigError
            A file that cannot be read, or a bad configuration.

        Examples
        --------
        >>> import os, tempfile
        >>> path = os.path.join(tempfile.mkdtemp(), "rig.toml")
        >>> with open(path, "w") as f:
        ...     _ = f.write('[rig]\\nrate_hz = 10.0\\n[supply]\\nport = "pihystsim://supply"\\n'
        ...                 '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> from pihyst.rig.pymeasure import RigProcedure
        >>> RigProcedure(config=path).load_config().rig.rate_hz
        10.0
        """
        from pihyst.rig import load_config
        return load_config(self.config)

    def open_rig(self, config: Any) -> Any:
        """Open the rig of ``config`` (its emulators too, for ``pihystsim://`` ports).

        Parameters
        ----------
        config : RigConfig
            The configuration.

        Returns
        -------
        Rig
            The open rig, also in :attr:`rig` (closed by :meth:`shutdown`).

        Raises
        ------
        RigError
            A port that does not open.

        Examples
        --------
        >>> import os, tempfile
        >>> path = os.path.join(tempfile.mkdtemp(), "rig.toml")
        >>> with open(path, "w") as f:
        ...     _ = f.write('[rig]\\nrate_hz = 10.0\\n[supply]\\nport = "pihystsim://supply"\\n'
        ...                 '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> from pihyst.rig.pymeasure import RigProcedure
        >>> procedure = RigProcedure(config=path)
        >>> procedure.open_rig(procedure.load_config()).describe()
        "emulated instruments on the simulated beam 'paper-beam', virtual time"
        >>> procedure.shutdown()
        """
        from pihyst.rig import Rig
        self.rig = Rig(config, real_time=bool(self.real_time), faults=self.faults)
        self.emulators = self.rig.emulators
        log.info("rig: %s", self.rig.describe())
        return self.rig

    def run_program(self, program: Any, extra: dict[str, Any] | None = None,
                    progress: tuple[float, float] = (0.0, 100.0)) -> Any:
        """One run of ``program`` on the open rig, every tick emitted.

        Parameters
        ----------
        program : VoltageProgram, FeedforwardProgram or FeedbackProgram
            What to drive.
        extra : dict or None
            Columns added to every emitted tick (``{"trial": 2}``).
        progress : tuple of float
            The progress (percent) emitted at the run's first and last tick.

        Returns
        -------
        RunResult
            The run, also in :attr:`result`.

        Raises
        ------
        RunStopped
            A run that stopped early (not for an abort), or could not zero the supply.

        Examples
        --------
        >>> import os, tempfile
        >>> path = os.path.join(tempfile.mkdtemp(), "rig.toml")
        >>> with open(path, "w") as f:
        ...     _ = f.write('[rig]\\nrate_hz = 10.0\\n[supply]\\nport = "pihystsim://supply"\\n'
        ...                 '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> from pihyst.rig import Fault, VoltageProgram
        >>> from pihyst.rig.pymeasure import RigProcedure
        >>> procedure = RigProcedure(config=path)
        >>> procedure.faults = (Fault("no-reply", "sensor"),)
        >>> _ = procedure.open_rig(procedure.load_config())
        >>> try:
        ...     procedure.run_program(VoltageProgram([10.0] * 10))
        ... except RunStopped as err:
        ...     print(str(err)[:40])
        the run stopped early: 3 consecutive com
        >>> procedure.shutdown()
        """
        emit = _EmitLog(self, program.n_ticks, extra, progress)
        controller = self.rig.controller(emit, handle_signals=False,
                                         stop_requested=self.should_stop)
        result = controller.run(program)
        self.results_of_runs = (self.results_of_runs or []) + [result]
        if not result.zeroed:
            raise RunStopped(f"{result.reason}; WARNING: the supply could not be zeroed: the "
                             "beam may still be charged")
        if not result.completed and result.reason != "stop requested":
            raise RunStopped(f"the run stopped early: {result.reason}; 0 V, output off")
        return result

    @property
    def result(self) -> Any:
        """The last run's :class:`~pihyst.rig.RunResult` (None before one)."""
        return self.results_of_runs[-1] if self.results_of_runs else None

    def shutdown(self) -> None:
        """Close the rig (nothing without one).

        The controller has zeroed the supply on every way out of a run; 0 V and output
        off are sent once more in case the procedure failed between opening the rig and
        running (best effort: a supply that does not answer is reported by the run
        itself).

        Examples
        --------
        >>> import os, tempfile
        >>> path = os.path.join(tempfile.mkdtemp(), "rig.toml")
        >>> with open(path, "w") as f:
        ...     _ = f.write('[rig]\\nrate_hz = 10.0\\n[supply]\\nport = "pihystsim://supply"\\n'
        ...                 '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> from pihyst.rig.pymeasure import RigProcedure
        >>> procedure = RigProcedure(config=path)
        >>> rig = procedure.open_rig(procedure.load_config())
        >>> procedure.shutdown(); procedure.rig is None, rig.supply.port.is_open
        (True, False)
        """
        if self.rig is None:
            return
        try:
            for what, send in (("0 V", lambda: self.rig.supply.set_voltage(0.0)),
                               ("output off", self.rig.supply.output_off)):
                try:
                    send()
                except OSError as err:
                    log.warning("shutdown: could not send %s: %s", what, err)
        finally:
            self.rig.close()
            self.rig = None


class RecordProcedure(RigProcedure):
    """``pihyst rig record``: drive a voltage signal, one sample per tick (default the
    paper's 0-150-0 V, 300 s triangle; ``u_max`` 0 takes ``[rig] u_max``).

    Parameters
    ----------
    config : str or None
        The rig configuration (TOML file).
    real_time : bool or None
        Run emulated instruments on the wall clock.
    signal : str or None
        One of ``"triangle"``, ``"sine"``, ``"decaying-triangles"``, ``"random-ramps"``,
        ``"staircase"``.
    u_min, u_max : float or None
        The signal's voltages (V; ``u_max`` 0: the rig's ``u_max``).
    period : float or None
        The signal's period (s).
    cycles : int or None
        Its number of periods.

    Examples
    --------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "rig.toml")
    >>> with open(path, "w") as f:
    ...     _ = f.write('[rig]\\nrate_hz = 10.0\\n[supply]\\nport = "pihystsim://supply"\\n'
    ...                 '[sensor]\\nport = "pihystsim://sensor"\\n')
    >>> from pihyst.rig.pymeasure import RecordProcedure
    >>> procedure = RecordProcedure(config=path, period=4.0, u_max=100.0)
    >>> procedure.startup(); procedure.execute(); procedure.shutdown()
    >>> y = procedure.result.column("displacement_um", phase="run")
    >>> len(y), bool(25 < y.max() < 35)
    (41, True)
    """

    signal = ListParameter("Signal", choices=SIGNALS, default="triangle")
    u_min = FloatParameter("Lowest voltage", units="V", minimum=0.0, default=0.0)
    u_max = FloatParameter("Highest voltage (0 for the rig u_max)", units="V", minimum=0.0,
                           default=0.0)
    period = FloatParameter("Period", units="s", minimum=1e-3, default=300.0)
    cycles = IntegerParameter("Cycles", minimum=1, default=1)

    def __init__(self, *, config: str | None = None, real_time: bool | None = None,
                 signal: str | None = None, u_min: float | None = None,
                 u_max: float | None = None, period: float | None = None,
                 cycles: int | None = None) -> None:
        self._set_parameters(config=config, real_time=real_time, signal=signal, u_min=u_min,
                             u_max=u_max, period=period, cycles=cycles)

    def voltages(self, config: Any) -> VoltageProgram:
        """The program of the signal Parameters at the rig's rate.

        Parameters
        ----------
        config : RigConfig
            The rig: its rate and its limits.

        Returns
        -------
        VoltageProgram
            One voltage per tick.

        Raises
        ------
        InvalidArgumentError
            Voltages outside the rig's limits.

        Examples
        --------
        >>> from pihyst.rig import RigConfig
        >>> from pihyst.rig.pymeasure import RecordProcedure
        >>> RecordProcedure(period=2.0).voltages(RigConfig()).describe()
        'record: triangle 0-150 V, period 2 s, 1 cycle(s) (41 ticks)'
        """
        r = config.rig
        u_max = self.u_max or r.u_max
        if not r.u_min <= self.u_min < u_max <= r.u_max:
            raise InvalidArgumentError(f"voltages {self.u_min:g}..{u_max:g} V must lie within "
                                       f"the rig's limits [{r.u_min:g}, {r.u_max:g}] V with "
                                       "min < max")
        u = signal_voltages(self.signal, self.u_min, u_max, self.period, self.cycles,
                            1.0 / r.rate_hz)
        return VoltageProgram(u, f"{self.signal} {self.u_min:g}-{u_max:g} V, period "
                                 f"{self.period:g} s, {self.cycles} cycle(s)")

    def startup(self) -> None:
        """Build the program and open the rig (PyMeasure calls this first).

        Raises
        ------
        ConfigError
            A bad configuration.
        InvalidArgumentError
            Voltages outside the rig's limits.

        Examples
        --------
        >>> import os, tempfile
        >>> path = os.path.join(tempfile.mkdtemp(), "rig.toml")
        >>> with open(path, "w") as f:
        ...     _ = f.write('[rig]\\nrate_hz = 10.0\\n[supply]\\nport = "pihystsim://supply"\\n'
        ...                 '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> from pihyst.rig.pymeasure import RecordProcedure
        >>> procedure = RecordProcedure(config=path, period=2.0)
        >>> procedure.startup(); procedure.program.n_ticks
        21
        >>> procedure.shutdown()
        """
        config = self.load_config()
        self.program = self.voltages(config)
        self.open_rig(config)

    def execute(self) -> None:
        """Run the program, every tick emitted (PyMeasure calls this after ``startup``).

        Raises
        ------
        RunStopped
            A run that stopped early (not for an abort).

        Examples
        --------
        >>> import os, tempfile
        >>> path = os.path.join(tempfile.mkdtemp(), "rig.toml")
        >>> with open(path, "w") as f:
        ...     _ = f.write('[rig]\\nrate_hz = 10.0\\n[supply]\\nport = "pihystsim://supply"\\n'
        ...                 '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> from pihyst.rig.pymeasure import RecordProcedure
        >>> procedure = RecordProcedure(config=path, period=2.0)
        >>> procedure.startup(); procedure.execute(); procedure.shutdown()
        >>> procedure.result.reason
        'end of the program'
        """
        self.run_program(self.program)


class TrackProcedure(RigProcedure):
    """``pihyst rig track``: the desired displacement of a CSV (``time_s``,
    ``displacement_um``, resampled at the tick rate, in the model's frame) through the
    exact inverse of the model; with a gain above 0, PID feedback on the measured
    error as well (KP V/µm, KI V/(µm s), KD V s/µm).

    Parameters
    ----------
    config : str or None
        The rig configuration (TOML file).
    real_time : bool or None
        Run emulated instruments on the wall clock.
    model : str or None
        The model (JSON file).
    desired : str or None
        The desired displacement (CSV file).
    kp, ki, kd : float or None
        The feedback's gains (all 0: open loop).

    Examples
    --------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "rig.toml")
    >>> with open(path, "w") as f:
    ...     _ = f.write('[rig]\\nrate_hz = 10.0\\n[supply]\\nport = "pihystsim://supply"\\n'
    ...                 '[sensor]\\nport = "pihystsim://sensor"\\n')
    >>> import pihyst
    >>> from pihyst.io import save_model
    >>> from pihyst.rig.pymeasure import TrackProcedure
    >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    >>> save_model(model, os.path.join(os.path.dirname(path), "model.json"))
    >>> desired = os.path.join(os.path.dirname(path), "desired.csv")
    >>> with open(desired, "w") as f:
    ...     _ = f.write("displacement_um\\n" + "\\n".join(["5", "10", "15", "10"]) + "\\n")
    >>> procedure = TrackProcedure(config=path, desired=desired,
    ...                            model=os.path.join(os.path.dirname(path), "model.json"))
    >>> procedure.startup(); procedure.execute(); procedure.shutdown()
    >>> procedure.result.column("reference", phase="run")
    array([ 5., 10., 15., 10.])
    """

    model = Parameter("Model (JSON)", default="model.json")
    desired = Parameter("Desired displacement (CSV)", default="examples/rig/desired_triangle.csv")
    kp = FloatParameter("Feedback KP", units="V/µm", minimum=0.0, default=0.0)
    ki = FloatParameter("Feedback KI", units="V/(µm*s)", minimum=0.0, default=0.0)
    kd = FloatParameter("Feedback KD", units="V*s/µm", minimum=0.0, default=0.0)

    def __init__(self, *, config: str | None = None, real_time: bool | None = None,
                 model: str | None = None, desired: str | None = None,
                 kp: float | None = None, ki: float | None = None,
                 kd: float | None = None) -> None:
        self._set_parameters(config=config, real_time=real_time, model=model,
                             desired=desired, kp=kp, ki=ki, kd=kd)

    def startup(self) -> None:
        """Read the model and the desired displacement, build the program and open the
        rig (PyMeasure calls this first).

        Raises
        ------
        ConfigError
            A bad configuration.
        InvalidArgumentError
            A model or desired displacement that cannot be used.

        Examples
        --------
        >>> import os, tempfile
        >>> path = os.path.join(tempfile.mkdtemp(), "rig.toml")
        >>> with open(path, "w") as f:
        ...     _ = f.write('[rig]\\nrate_hz = 10.0\\n[supply]\\nport = "pihystsim://supply"\\n'
        ...                 '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> from pihyst.rig.pymeasure import TrackProcedure
        >>> TrackProcedure(config=path, model="no-such-model.json").startup()
        Traceback (most recent call last):
        ...
        pihyst.exceptions.InvalidModelError: no-such-model.json: cannot read model: ...
        """
        config = self.load_config()
        r = config.rig
        model = model_at_tick(self.model, r.rate_hz)
        desired = desired_per_tick(self.desired, r.rate_hz)
        max_step = None if r.slew_V_per_s is None else r.slew_V_per_s / r.rate_hz
        self.program: FeedforwardProgram
        if self.kp or self.ki or self.kd:
            self.program = FeedbackProgram(model, desired, r.u_min, r.u_max, 1.0 / r.rate_hz,
                                           self.kp, self.ki, self.kd, max_step=max_step,
                                           description=self.desired)
        else:
            self.program = FeedforwardProgram(model, desired, r.u_min, r.u_max, max_step,
                                              description=self.desired)
        self.open_rig(config)

    def execute(self) -> None:
        """Run the program, every tick emitted (PyMeasure calls this after ``startup``).

        Raises
        ------
        RunStopped
            A run that stopped early (not for an abort).

        Examples
        --------
        >>> import os, tempfile
        >>> path = os.path.join(tempfile.mkdtemp(), "rig.toml")
        >>> with open(path, "w") as f:
        ...     _ = f.write('[rig]\\nrate_hz = 10.0\\n[supply]\\nport = "pihystsim://supply"\\n'
        ...                 '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> import pihyst
        >>> from pihyst.io import save_model
        >>> from pihyst.rig.pymeasure import TrackProcedure
        >>> folder = os.path.dirname(path)
        >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
        >>> save_model(model, os.path.join(folder, "model.json"))
        >>> with open(os.path.join(folder, "desired.csv"), "w") as f:
        ...     _ = f.write("displacement_um\\n5\\n10\\n15\\n10\\n")
        >>> procedure = TrackProcedure(config=path, model=os.path.join(folder, "model.json"),
        ...                            desired=os.path.join(folder, "desired.csv"))
        >>> procedure.startup(); procedure.execute(); procedure.shutdown()
        >>> procedure.result.completed
        True
        """
        self.run_program(self.program)

    def errors(self) -> dict[str, float | None]:
        """Tracking errors of the run (mean absolute, RMS, max; µm) over its valid ticks.

        Returns
        -------
        dict of str to float
            :func:`pihyst.metrics.error_summary` of the measured against the desired
            displacement: ``mean_abs``, ``max_abs``, ``rms`` (µm) and the same in
            percent of the desired range (``*_pct``; None for a range of 0).

        Examples
        --------
        >>> import os, tempfile
        >>> path = os.path.join(tempfile.mkdtemp(), "rig.toml")
        >>> with open(path, "w") as f:
        ...     _ = f.write('[rig]\\nrate_hz = 10.0\\n[supply]\\nport = "pihystsim://supply"\\n'
        ...                 '[sensor]\\nport = "pihystsim://sensor"\\n')
        >>> import pihyst
        >>> from pihyst.io import save_model
        >>> from pihyst.rig.pymeasure import TrackProcedure
        >>> folder = os.path.dirname(path)
        >>> model = pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
        >>> save_model(model, os.path.join(folder, "model.json"))
        >>> with open(os.path.join(folder, "desired.csv"), "w") as f:
        ...     _ = f.write("displacement_um\\n5\\n10\\n15\\n10\\n")
        >>> procedure = TrackProcedure(config=path, model=os.path.join(folder, "model.json"),
        ...                            desired=os.path.join(folder, "desired.csv"))
        >>> procedure.startup(); procedure.execute(); procedure.shutdown()
        >>> errors = procedure.errors()
        >>> sorted(errors)
        ['max_abs', 'max_abs_pct', 'mean_abs', 'mean_abs_pct', 'rms', 'rms_pct']
        >>> bool(0 < errors["rms"] <= errors["max_abs"])
        True
        """
        from pihyst import metrics
        y = self.result.column("displacement_um", phase="run")
        ref = self.result.column("reference", phase="run")
        ok = np.isfinite(y)
        return metrics.error_summary(ref[ok], y[ok], float(np.ptp(ref)))


def _parameter_keywords(cls: type) -> Callable[..., None]:
    """An ``__init__`` for a RigProcedure subclass of one's own that takes its
    Parameters as keywords (PyMeasure's Procedure takes ``**kwargs`` and drops unknown
    ones silently); its signature names them, for ``help()``."""
    names = [name for name, value in inspect.getmembers(cls) if isinstance(value, Parameter)]

    self_parameter = inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD)
    signature = inspect.Signature(
        [self_parameter] + [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY,
                                              default=None) for name in names])

    def __init__(self: RigProcedure, **values: Any) -> None:
        signature.bind(self, **values)    # TypeError for a keyword that is no Parameter
        self._set_parameters(**values)

    __init__.__signature__ = signature  # type: ignore[attr-defined]
    __init__.__qualname__ = f"{cls.__qualname__}.__init__"
    __init__.__doc__ = (f"{cls.__name__}'s Parameters ({', '.join(names)}) as keywords; "
                        "None: the Parameter's default.")
    return __init__
