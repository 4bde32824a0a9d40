"""The paper's experiment through the emulated instruments, in virtual time: record the
loop with the 0-150-0 V, 300 s triangle over Modbus RTU and the KEYENCE protocol, fit
the paper's multislope PI (thresholds 0, 20, 30, 40) to the logged loop, and track the
triangular trajectory through the rig, open loop and with feedback.

Used by the demo (:func:`pihyst.study.paper_study` with ``rig=True``); the report
shows the loop timing (busy time, jitter, overruns) and the tracking through the rig.
"""

import os
import tempfile
from dataclasses import dataclass, field

import numpy as np

from pihyst._atomic import write_atomically
from pihyst.identify import fit
from pihyst.metrics import error_summary
from pihyst.rig import FeedbackProgram, FeedforwardProgram, Rig, VoltageProgram, parse_config
from pihyst.sim.signals import triangle

RUNS = ("record", "open_loop", "feedback")

_CONFIG = """
[rig]
rate_hz = {rate_hz}
u_min = 0.0
u_max = 150.0
slew_V_per_s = 200.0
[supply]
port = "pihystsim://study-supply"
baudrate = 19200
protocol = "modbus-rtu"
address = 1
setpoint_register = 10
setpoint_format = "float32"
word_order = "big"
scale = 1.0
output_register = 9
readback_register = 12
[sensor]
port = "pihystsim://study-sensor"
baudrate = 115200
protocol = "keyence-lk-g5000"
output = 1
scale_um = 1.0
sign = 1
[emulator]
plant = "{plant}"
seed = {seed}
"""


@dataclass
class RigStudy:
    """Results of :func:`rig_study`: the three runs, their logs (CSV text), the model
    fitted to the logged loop, loop timing and tracking errors per run."""

    plant: str
    rate_hz: float
    gains: tuple
    config_text: str
    results: dict = field(repr=False)         # run name -> RunResult
    logs: dict = field(repr=False)            # run name -> CSV text of the run log
    model: object = None
    timing: dict = field(default_factory=dict)
    tracking: dict = field(default_factory=dict)
    realtime: dict = field(default_factory=dict)   # timing of a short run on the wall clock

    def series(self, run):
        """(t, reference, voltage, displacement) of the run's 'run' ticks."""
        r = self.results[run]
        return tuple(r.column(c, "run") for c in ("time_s", "reference", "voltage_V",
                                                   "displacement_um"))

    def metrics(self):
        return {"plant": self.plant, "rate_hz": self.rate_hz,
                "feedback_gains": list(self.gains), "timing": self.timing,
                "tracking": self.tracking, "realtime": self.realtime,
                "stopped": {k: r.reason for k, r in self.results.items()},
                "model_thresholds": self.model.thresholds.tolist(),
                "model_weights": self.model.weights.tolist()}

    def write_logs(self, out_dir):
        """Write the run logs as ``rig_<run>.csv``; returns the file names."""
        names = []
        for run, text in self.logs.items():
            name = f"rig_{run}.csv"
            write_atomically(os.path.join(out_dir, name), text)
            names.append(name)
        return names


def rig_study(plant="paper-beam", *, seed=0, rate_hz=10.0, gains=(1.0, 10.0), period_s=300.0,
              realtime_s=0.0, progress=None):
    """Record -> fit -> track (open loop, with feedback) through the emulated instruments.

    Parameters
    ----------
    plant : str
        The simulated beam behind the emulated instruments.
    seed : int
        Noise seed of the beam.
    rate_hz : float
        Controller rate.
    gains : (KP, KI) or (KP, KI, KD)
        Feedback gains (V/um, V/(um s), V s/um).
    period_s : float
        Period of the triangles (the paper's 300 s).
    realtime_s : float
        Also run the loop this long on the wall clock (0 V to 20 V), to measure the
        timing jitter, which virtual time does not have.
    progress : callable or None
        Receives one line per run.

    Returns
    -------
    RigStudy

    Examples
    --------
    >>> s = rig_study(period_s=30.0)
    >>> s.tracking["feedback"]["mean_abs"] < s.tracking["open_loop"]["mean_abs"]
    True
    """
    say = progress or (lambda line: None)
    text = _CONFIG.format(rate_hz=float(rate_hz), plant=plant, seed=int(seed))
    config = parse_config(text, source="rig study (emulated instruments)")
    dt = 1.0 / rate_hz
    results, logs = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        def run(name, program):
            path = os.path.join(tmp, f"{name}.csv")
            with Rig(config) as rig:
                results[name] = rig.run(program, path, handle_signals=False)
            with open(path, encoding="utf-8") as f:
                logs[name] = f.read()
            return results[name]

        say(f"rig: recording the loop through the emulated supply (Modbus RTU, 19 200 baud) "
            f"and sensor (KEYENCE LK-G5000), {rate_hz:g} Hz, virtual time")
        _, u = triangle(period_s=period_s, dt=dt)
        loop = run("record", VoltageProgram(u, f"0-150-0 V triangle, {period_s:g} s"))
        u_log = loop.column("voltage_V", "run")
        y_log = loop.column("displacement_um", "run")
        ok = np.isfinite(y_log) & np.isfinite(u_log)
        model = fit(u_log[ok], y_log[ok], family="multislope",
                    thresholds=[0.0, 20.0, 30.0, 40.0], initial_state="zero",
                    offset=False).model
        peak = float(np.max(y_log[ok]))
        _, desired = triangle(u_max=0.98 * peak, period_s=period_s, dt=dt)
        max_step = config.rig.slew_V_per_s * dt
        say("rig: tracking the triangular trajectory open loop (the multislope inverse)")
        run("open_loop", FeedforwardProgram(model, desired, 0.0, 150.0, max_step,
                                            "triangle 0 -> 98 % of the recorded peak -> 0"))
        say(f"rig: tracking with feedback (Kp {gains[0]:g} V/µm, Ki {gains[1]:g} V/(µm s))")
        run("feedback", FeedbackProgram(model, desired, 0.0, 150.0, dt, *gains,
                                        max_step=max_step,
                                        description="triangle 0 -> 98 % of the recorded "
                                                    "peak -> 0"))
        if realtime_s > 0:
            say(f"rig: {realtime_s:g} s of the loop on the wall clock (timing jitter)")
            n = max(2, int(round(realtime_s * rate_hz)))
            with Rig(config, real_time=True) as rig:
                live = rig.controller(handle_signals=False).run(
                    VoltageProgram(np.linspace(0.0, 20.0, n), "0-20 V ramp"))
    study = RigStudy(plant, float(rate_hz), tuple(gains), text, results, logs, model)
    if realtime_s > 0:
        study.realtime = live.timing()
    for name, result in results.items():
        study.timing[name] = result.timing()
    span = float(np.ptp(desired))
    for name in ("open_loop", "feedback"):
        _, ref, _, y = study.series(name)
        ok = np.isfinite(y)
        study.tracking[name] = error_summary(ref[ok], y[ok], span)
    return study


LABELS = {"open_loop": "open loop (multislope inverse)", "feedback": "with feedback"}


def rig_figure(study):
    """Tracking through the rig, open loop and with feedback (matplotlib figure)."""
    from pihyst.study._plot import tracking_plot  # lazy: matplotlib
    t, ref, _, y_open = study.series("open_loop")
    _, _, _, y_fb = study.series("feedback")
    return tracking_plot(t, ref, {"open_loop": y_open, "feedback": y_fb},
                         {"open_loop": y_open - ref, "feedback": y_fb - ref},
                         labels=LABELS, title="Tracking through the emulated instruments")


def _cells(row):
    return "<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>"


def rig_html(study, figure_html=""):
    """The report's section on the rig (HTML)."""
    head = ("<table class=\"data\"><thead><tr>" +
            "".join(f"<th>{h}</th>" for h in ("run", "ticks", "busy per tick (ms)",
                                               "utilisation", "start jitter p99 (ms)",
                                               "overruns", "stopped")) +
            "</tr></thead><tbody>")
    rows = []
    names = {"record": "record the loop", **LABELS}
    for run in RUNS:
        t = study.timing[run]
        rows.append(_cells([names[run], t["ticks"], f"{t['busy_mean_ms']:.2f}",
                            f"{t['utilisation_pct']:.0f} %", f"{t['jitter_p99_ms']:.2f}",
                            t["overruns"], study.results[run].reason]))
    if study.realtime:
        t = study.realtime
        rows.append(_cells(["wall clock, 0-20 V ramp", t["ticks"], f"{t['busy_mean_ms']:.2f}",
                            f"{t['utilisation_pct']:.0f} %", f"{t['jitter_p99_ms']:.2f}",
                            t["overruns"], "end of the program"]))
    timing = head + "".join(rows) + "</tbody></table>"
    track = ["<table class=\"data\"><thead><tr><th>through the rig</th><th>mean |error| "
             "(µm)</th><th>RMS (µm)</th><th>max |error| (µm)</th><th>mean, % of range</th>"
             "</tr></thead><tbody>"]
    for run in ("open_loop", "feedback"):
        e = study.tracking[run]
        track.append(_cells([LABELS[run], f"{e['mean_abs']:.4f}", f"{e['rms']:.4f}",
                             f"{e['max_abs']:.4f}", f"{e['mean_abs_pct']:.3g} %"]))
    track.append("</tbody></table>")
    gains = ", ".join(f"{g:g}" for g in study.gains)
    return "\n".join([
        "<h2>The experiment through the instruments' protocols</h2>",
        f"<p>The same experiment run by pihyst's controller through emulated instruments "
        f"that speak the real protocols: a supply on Modbus RTU at 19 200 baud (float32 "
        f"setpoint, output-enable and readback registers) and a KEYENCE LK-G5000 sensor "
        f"at 115 200 baud, coupled through the simulated beam '{study.plant}', at "
        f"{study.rate_hz:g} Hz in virtual time (bytes take their time on the emulated "
        f"wire; the runs take the time of their computation). The loop was recorded, the "
        f"paper's multislope PI (0, 20, 30, 40) fitted to the logged loop, and the "
        f"triangle tracked open loop and with PI feedback (gains {gains}, V/µm and "
        f"V/(µm s)). Logs: <code>rig_record.csv</code>, <code>rig_open_loop.csv</code>, "
        f"<code>rig_feedback.csv</code>.</p>",
        "<h3>Loop timing</h3>",
        "<p>Busy time is the wire time of a tick's exchanges plus the instruments' "
        "processing (sensor read, setpoint write, readback). In virtual time the ticks "
        "start exactly on their deadlines; the wall-clock row shows the jitter of a real "
        "run on this computer.</p>", timing,
        "<h3>Tracking through the rig</h3>",
        "<p>Open loop, the inverse model cannot remove what it does not model: the "
        "beam's creep and the model's error. Feedback on the measured displacement "
        "removes them.</p>", "".join(track), figure_html])
