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

import logging
from dataclasses import asdict

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
    message says otherwise)."""


class _EmitLog:
    """The controller's log: every tick goes to the procedure as a result (the status
    texts without commas, PyMeasure's delimiter), every note to the Python log."""

    def __init__(self, procedure, n_ticks, extra=None, progress=(0.0, 100.0)):
        self.procedure = procedure
        self.n_ticks = max(1, n_ticks)
        self.extra = extra or {}
        self.progress = progress
        self.notes = []

    def write(self, record):
        row = asdict(record)
        for key in ("sensor_status", "supply_status"):
            row[key] = row[key].replace(",", ";")
        self.procedure.emit("results", {**row, **self.extra})
        if record.phase == "run":
            lo, hi = self.progress
            done = min(1.0, (record.tick + 1) / self.n_ticks)
            self.procedure.emit("progress", lo + (hi - lo) * done)

    def note(self, text):
        self.notes.append(text)
        log.info(text)


class RigProcedure(Procedure):
    """The base of the rig's procedures: the configuration file, the rig it opens in
    :meth:`open_rig`, and :meth:`run_program`, one safe run of a program (a
    :class:`~pihyst.rig.VoltageProgram`, ...) with every tick emitted. A subclass
    builds its program(s) in ``startup`` (then calls ``open_rig``) and runs them in
    ``execute``; :meth:`shutdown` closes the rig."""

    config = Parameter("Rig configuration (TOML file)", default="examples/rig/emulated.toml")
    real_time = BooleanParameter("Wall-clock time for emulated instruments", default=False)

    DATA_COLUMNS = list(COLUMNS)

    rig = None
    results_of_runs = None
    #: emulated instruments only: faults to inject (:class:`~pihyst.rig.Fault`)
    faults = ()
    #: the rig's emulated instruments (None on a real rig), kept after the rig closes
    emulators = None

    def emit(self, topic, record):
        """Outside a PyMeasure Worker (which replaces this), results are not sent
        anywhere: the run's ticks are in :attr:`result` (``records``)."""

    def should_stop(self):
        """Outside a PyMeasure Worker (which replaces this), nothing asks for a stop."""
        return False

    def load_config(self):
        from pihyst.rig import load_config
        return load_config(self.config)

    def open_rig(self, config):
        from pihyst.rig import Rig
        self.rig = Rig(config, real_time=bool(self.real_time), faults=self.faults)
        self.emulators = self.rig.emulators
        log.info("rig: %s", self.rig.describe())
        return self.rig

    def run_program(self, program, extra=None, progress=(0.0, 100.0)):
        """One run of ``program`` on the open rig, every tick emitted; returns the
        :class:`~pihyst.rig.RunResult`. Raises RunStopped for a run that stopped early
        (not for an abort) or could not zero the supply."""
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
    def result(self):
        """The last run's :class:`~pihyst.rig.RunResult` (None before one)."""
        return self.results_of_runs[-1] if self.results_of_runs else None

    def shutdown(self):
        """Close the rig. The controller has zeroed the supply on every way out of a run;
        0 V and output off are sent once more in case the procedure failed between
        opening the rig and running (best effort: a supply that does not answer is
        reported by the run itself)."""
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
    paper's 0-150-0 V, 300 s triangle; ``u_max`` 0 takes ``[rig] u_max``)."""

    signal = ListParameter("Signal", choices=SIGNALS, default="triangle")
    u_min = FloatParameter("Lowest voltage", units="V", minimum=0.0, default=0.0)
    u_max = FloatParameter("Highest voltage (0 for the rig u_max)", units="V", minimum=0.0,
                           default=0.0)
    period = FloatParameter("Period", units="s", minimum=1e-3, default=300.0)
    cycles = IntegerParameter("Cycles", minimum=1, default=1)

    def voltages(self, config):
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

    def startup(self):
        config = self.load_config()
        self.program = self.voltages(config)
        self.open_rig(config)

    def execute(self):
        self.run_program(self.program)


class TrackProcedure(RigProcedure):
    """``pihyst rig track``: the desired displacement of a CSV (``time_s``,
    ``displacement_um``, resampled at the tick rate, in the model's frame) through the
    exact inverse of the model; with a gain above 0, PID feedback on the measured
    error as well (KP V/µm, KI V/(µm s), KD V s/µm)."""

    model = Parameter("Model (JSON)", default="model.json")
    desired = Parameter("Desired displacement (CSV)", default="examples/rig/desired_triangle.csv")
    kp = FloatParameter("Feedback KP", units="V/µm", minimum=0.0, default=0.0)
    ki = FloatParameter("Feedback KI", units="V/(µm*s)", minimum=0.0, default=0.0)
    kd = FloatParameter("Feedback KD", units="V*s/µm", minimum=0.0, default=0.0)

    def startup(self):
        config = self.load_config()
        r = config.rig
        model = model_at_tick(self.model, r.rate_hz)
        desired = desired_per_tick(self.desired, r.rate_hz)
        max_step = None if r.slew_V_per_s is None else r.slew_V_per_s / r.rate_hz
        if self.kp or self.ki or self.kd:
            self.program = FeedbackProgram(model, desired, r.u_min, r.u_max, 1.0 / r.rate_hz,
                                           self.kp, self.ki, self.kd, max_step=max_step,
                                           description=self.desired)
        else:
            self.program = FeedforwardProgram(model, desired, r.u_min, r.u_max, max_step,
                                              description=self.desired)
        self.open_rig(config)

    def execute(self):
        self.run_program(self.program)

    def errors(self):
        """Tracking errors of the run (mean absolute, RMS, max; µm) over its valid ticks."""
        from pihyst import metrics
        y = self.result.column("displacement_um", phase="run")
        ref = self.result.column("reference", phase="run")
        ok = np.isfinite(y)
        return metrics.error_summary(ref[ok], y[ok], float(np.ptp(ref)))
