"""A learning run in the report: the error per trial (the learning curve) and the
tracking before (trial 0, the starting feedforward) and after (the best trial), read from
the CSV that ``pihyst learn`` and ``pihyst rig learn`` write (docs/theory/learning.md)."""

import html
from dataclasses import dataclass

import numpy as np

from pihyst.exceptions import RecordError
from pihyst.io import read_columns

COLUMNS = ["trial", "probe", "accepted", "rms_um", "time_s", "desired_um", "displacement_um"]


@dataclass(frozen=True)
class LearningRun:
    """One learning run: per trial ``rms_um``, ``accepted``, ``probe``; the period's
    ``time_s`` and ``desired_um``; the measured period of trial 0 and of the best."""

    source: str
    rms_um: np.ndarray
    accepted: np.ndarray
    probe: np.ndarray
    time_s: np.ndarray
    desired_um: np.ndarray
    first_um: np.ndarray
    best_um: np.ndarray

    @property
    def best_trial(self):
        return int(np.flatnonzero(self.rms_um == self.rms_um.min())[-1])

    def summary(self):
        """The JSON-ready figures of the run (metrics.json)."""
        return {"source": self.source, "trials": int(self.rms_um.size),
                "rms_um": self.rms_um.tolist(), "accepted": self.accepted.tolist(),
                "probe": self.probe.tolist(), "best_trial": self.best_trial,
                "improvement": float(self.rms_um[0] / self.rms_um.min())
                if self.rms_um.min() > 0 else None}


def read_learning_run(path):
    """The :class:`LearningRun` of a learning CSV; RecordError naming the file when it is
    not one."""
    columns, lines = read_columns(path, COLUMNS)
    trial = columns["trial"]
    trials = np.unique(trial)
    if trials.size == 0 or not np.array_equal(trials, np.arange(trials.size)):
        raise RecordError(f"{path}: column 'trial' must number the trials 0, 1, 2, ...")
    first = trial == 0
    n = int(np.count_nonzero(first))
    if trial.size != n * trials.size or np.any(trial.reshape(trials.size, n).T != trials):
        raise RecordError(f"{path}: every trial must have the same {n} samples, trial by "
                          f"trial (as pihyst learn writes them)")
    per_trial = {k: columns[k].reshape(trials.size, n)[:, 0] for k in
                 ("rms_um", "accepted", "probe")}
    rms = per_trial["rms_um"]
    best = int(np.flatnonzero(rms == rms.min())[-1])
    y = columns["displacement_um"].reshape(trials.size, n)
    return LearningRun(str(path), rms, per_trial["accepted"].astype(bool),
                       per_trial["probe"].astype(bool), columns["time_s"][:n],
                       columns["desired_um"][:n], y[0], y[best])


def add_learning_figures(run, figs, plot):
    figs.add("learning_curve", "Learning curve",
             "RMS tracking error per trial (measured - desired); trial 0 is the starting "
             "feedforward. Undone trials are open circles, probe trials marked P.",
             plot.learning_curve_plot(run.rms_um, run.accepted, run.probe))
    figs.add("learning_tracking", "Tracking before and after learning",
             f"One period: trial 0 and the best trial ({run.best_trial}).",
             plot.tracking_plot(run.time_s, run.desired_um,
                                {"none": run.first_um, "best": run.best_um},
                                {"none": run.first_um - run.desired_um,
                                 "best": run.best_um - run.desired_um},
                                labels={"none": "trial 0", "best": f"trial {run.best_trial}"},
                                title="Tracking one period before and after learning"))


def learning_html(run, figs):
    best = run.best_trial
    rows = "".join(
        f"<tr><td>{j}</td><td>{'probe' if p else ('start' if j == 0 else 'learn')}</td>"
        f"<td>{e:.4g}</td><td>{'yes' if ok else 'undone'}</td></tr>"
        for j, (e, ok, p) in enumerate(zip(run.rms_um, run.accepted, run.probe)))
    return "\n".join([
        "<h2>Learning feedforward</h2>",
        f"<p>Learning run <code>{html.escape(run.source)}</code>: {run.rms_um.size} trials "
        f"of a {run.time_s.size}-sample period; RMS error {run.rms_um[0]:.4g} µm at trial 0, "
        f"{run.rms_um[best]:.4g} µm at the best, trial {best} "
        f"({run.rms_um[0] / max(run.rms_um[best], 1e-300):.1f} times lower).</p>",
        "<table class=\"data\"><tr><th>trial</th><th>kind</th><th>RMS error (µm)</th>"
        f"<th>kept</th></tr>{rows}</table>",
        figs.html("learning_curve"), figs.html("learning_tracking")])
