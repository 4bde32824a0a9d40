"""The paper's study end to end on a simulated beam, and the same fit-and-compare study
on a user's own record. Computation only: ``_plot`` draws, ``_report`` writes the files.

The paper's study (Xu, Zhang, Rong and Ni 2020; docs/paper.md):

1. record the loop with the 0-150-0 V triangle of 300 s period;
2. fit the conventional PI with thresholds (0, 10, 30, 150) and the multislope PI with
   (0, 20, 30, 40), as the paper did: zero initial state, no offset (Table 1, Figs. 7-8);
3. fit pihyst's automatic best (every PI family, thresholds chosen on held-back cycles) on a
   record that also has minor loops, and judge all three on a record with reversals
   inside the range that no model was fitted on;
4. invert the models and track a triangular displacement on the beam (Figs. 11-12), and a
   trajectory with reversals inside the range;
5. repeat the comparison on the other simulated beams.

Errors are measured minus model (the paper's sign: its conventional PI ends 3.09 um above
the beam at 0 V, an error of -3.09 um).
"""

import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pihyst import paper
from pihyst._version import __version__
from pihyst.exceptions import PihystWarning
from pihyst.identify import PI_FAMILY_NAMES, fit
from pihyst.inverse import compensate
from pihyst.metrics import error_summary
from pihyst.sim import PLANT_NAMES, make_plant
from pihyst.sim.signals import decaying_triangles, random_ramps, triangle

PAPER_SPAN_V = paper.DRIVE_U_MAX_V
CLASSICAL_THRESHOLDS = paper.TABLE1_CLASSICAL_THRESHOLDS
MULTISLOPE_THRESHOLDS = paper.TABLE1_MULTISLOPE_THRESHOLDS
MODEL_KEYS = ("classical", "multislope", "best")

#: The paper's numbers (docs/paper.md), shown beside pihyst's.
PAPER = paper.published()


@dataclass
class Recording:
    """A measured (or simulated) record.

    Parameters
    ----------
    name : str
        The record's name in the report.
    t : numpy.ndarray
        Sample times (s).
    u : numpy.ndarray
        Voltages (V).
    y : numpy.ndarray
        Displacements (µm).
    description : str
        Where it comes from, for the report.

    Examples
    --------
    >>> import numpy as np
    >>> rec = Recording("loop", np.arange(3.0), np.array([0.0, 150, 0]), np.array([0.0, 40, 2]))
    >>> rec.span_y
    40.0
    """

    name: str
    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    description: str = ""

    @property
    def span_y(self):
        """The peak-to-peak of the displacement (µm)."""
        return float(np.ptp(self.y))


@dataclass
class FittedModel:
    """One identified model and how it was obtained.

    Parameters
    ----------
    key : str
        ``"classical"``, ``"multislope"`` or ``"best"``.
    label : str
        What the report calls it.
    model : PIModel
        The fitted model.
    requested_thresholds : list, optional
        The thresholds asked for (the paper's, scaled), before unusable ones were left
        out.
    notes : list of str
        What the fit said (warnings, thresholds left out).
    fit_report : FitReport, optional
        The fit's report.

    Examples
    --------
    >>> import pihyst
    >>> FittedModel("classical", "conventional PI", pihyst.ClassicalPI([0], [1.0])).notes
    []
    """

    key: str
    label: str
    model: Any
    requested_thresholds: list | None = None
    notes: list = field(default_factory=list)
    fit_report: Any = None


@dataclass
class Study:
    """Everything the report shows; ``metrics`` is its JSON-ready summary.

    Made by :func:`paper_study` and :func:`loop_study`, written by
    :func:`pihyst.study.write_report`.

    Parameters
    ----------
    mode : str
        ``"demo"`` (the simulated beam) or ``"report"`` (a user's record).
    title : str
        The report's title.
    source : str
        Where the data comes from.
    loop : Recording
        The record the models were fitted to.
    models : dict
        Model key -> :class:`FittedModel`.
    predictions : dict
        Record name -> {model key: prediction}.
    operators : dict
        ``"classical"``/``"multislope"`` -> (u, operator outputs, thresholds).
    metrics : dict
        The JSON-ready summary (metrics.json).
    records : dict
        The other records, by name.
    tracking : dict
        Experiment name -> dict of arrays (desired, voltage, measured).
    variants : list
        The comparison repeated on the other simulated beams.
    variant_loops : dict
        Their loops, by beam.
    rig : object, optional
        The study through the emulated rig (``pihyst.study._rig_study.RigStudy``).
    learning : object, optional
        A learning run (``pihyst.study._learning.LearningRun``).

    Examples
    --------
    >>> study = paper_study(dt=2.0, variants=False, progress=None)
    >>> study.mode, sorted(study.models)
    ('demo', ['best', 'classical', 'multislope'])
    """

    mode: str                       # "demo" (simulated beam) or "report" (a user's record)
    title: str
    source: str
    loop: Recording
    models: dict
    predictions: dict               # record name -> {model key: prediction}
    operators: dict                 # "classical"/"multislope" -> (u, outputs, thresholds)
    metrics: dict
    records: dict = field(default_factory=dict)
    tracking: dict = field(default_factory=dict)   # experiment name -> dict of arrays
    variants: list = field(default_factory=list)
    variant_loops: dict = field(default_factory=dict)
    rig: object = None              # pihyst.study._rig_study.RigStudy: the study through the rig
    learning: object = None         # pihyst.study._learning.LearningRun: a learning run


# ----------------------------------------------------------------------------- helpers
class Progress:
    """Numbered progress lines with elapsed times, sent to ``sink`` (e.g. print)."""

    def __init__(self, sink, total):
        self.sink, self.total, self.n = sink, total, 0
        self.t0 = self.t_step = time.perf_counter()
        self.timings = {}
        self._label = None

    def step(self, label):
        self._close()
        self.n += 1
        self._label = label
        self.t_step = time.perf_counter()
        if self.sink:
            self.sink(f"[{self.n}/{self.total}] {label} ...")

    def _close(self):
        if self._label is not None:
            self.timings[self._label] = time.perf_counter() - self.t_step

    def done(self):
        self._close()
        self._label = None
        return time.perf_counter() - self.t0


def _quiet(call, notes):
    """Run ``call()``; pihyst's warnings become notes (they belong in the report)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PihystWarning)
        out = call()
    for w in caught:
        if issubclass(w.category, PihystWarning):
            notes.append(str(w.message))
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return out


def signed_extremes(u: NDArray[np.float64],
                    error: NDArray[np.float64]) -> dict[str, float | None]:
    """The error of largest magnitude (with its sign) in the low, middle and high third
    of the input range, as the paper reports them.

    Parameters
    ----------
    u : numpy.ndarray
        The input of each sample (V).
    error : numpy.ndarray
        The error at each sample (µm, measured - model).

    Returns
    -------
    dict
        ``low``, ``middle``, ``high``: the signed extreme error of each third (None for a
        third without samples).

    Examples
    --------
    >>> import numpy as np
    >>> signed_extremes(np.array([0.0, 50, 100, 150]), np.array([-3.0, 1, 2, -0.5]))
    {'low': -3.0, 'middle': 2.0, 'high': 2.0}
    """
    lo, hi = float(np.min(u)), float(np.max(u))
    edges = lo + (hi - lo) * np.array([0.0, 1 / 3, 2 / 3, 1.0])
    out: dict[str, float | None] = {}
    for name, a, b in zip(("low", "middle", "high"), edges[:-1], edges[1:]):
        inside = (u >= a) & (u <= b)
        if not np.any(inside):
            out[name] = None
            continue
        e = error[inside]
        k = int(np.argmax(np.abs(e)))
        out[name] = float(e[k])
    return out


def fit_metrics(rec, y_hat):
    """Errors (measured - model) of a prediction on a record."""
    summary = error_summary(rec.y, y_hat, rec.span_y)
    summary["extremes"] = signed_extremes(rec.u, rec.y - y_hat)
    return summary


def tracking_metrics(desired, measured, voltage, saturated=None):
    """Tracking errors (measured - desired) in um and % of the desired range."""
    summary = error_summary(desired, measured, float(np.ptp(desired)))
    summary["voltage_range"] = [float(np.min(voltage)), float(np.max(voltage))]
    summary["saturated_samples"] = None if saturated is None else int(np.count_nonzero(saturated))
    return summary


def _usable_thresholds(thresholds, span, zero_state):
    """Split thresholds into those whose classical operator moves on a record of input
    span ``span`` and those that never move (their weight is undetermined)."""
    # From a zero state a classical play of threshold r moves once the input exceeds r;
    # from a cycled or settled state, operators with r >= span/2 stay constant.
    limit = span if zero_state else span / 2
    keep = [r for r in thresholds if r < limit * (1 - 1e-12)]
    drop = [r for r in thresholds if r not in keep]
    return keep, drop


def fit_paper_models(rec: "Recording", *, paper_method: bool = True,
                     scale: float = 1.0) -> dict[str, "FittedModel"]:
    """The conventional and the multislope PI with the paper's thresholds (times
    ``scale``), fitted to ``rec``.

    Parameters
    ----------
    rec : Recording
        The record to fit.
    paper_method : bool
        Zero initial state and no offset, as the paper (for records that start at rest
        at 0 V with the sensor zeroed there); otherwise the initial state is found from
        the data and an offset is fitted (any record).
    scale : float
        Factor on the paper's thresholds (the record's span / 150 V).

    Returns
    -------
    dict
        ``"classical"`` and ``"multislope"`` -> :class:`FittedModel`.

    Raises
    ------
    FitError
        If the record cannot be fitted.

    Examples
    --------
    >>> from pihyst.sim import make_plant
    >>> from pihyst.sim.signals import triangle
    >>> t, u = triangle(dt=2.0)
    >>> rec = Recording("loop", t, u, make_plant("paper-beam").run(u, t))
    >>> sorted(fit_paper_models(rec))
    ['classical', 'multislope']
    """
    options: dict[str, Any] = ({"initial_state": "zero", "offset": False} if paper_method
                               else {})
    span = float(np.ptp(rec.u))
    out = {}
    classical = [r * scale for r in CLASSICAL_THRESHOLDS]
    keep, drop = _usable_thresholds(classical, span, paper_method)
    notes = []
    for r in drop:
        notes.append(f"threshold r = {r:g} V never moves on this record (a classical play "
                     f"operator leaves its state only when the input sweeps beyond r), so "
                     f"its weight is undetermined and it was left out"
                     + (" (the paper's weight 0.582 for r = 150 V multiplies an output that "
                        "stays 0 on a 0-150 V drive)" if r == 150.0 else ""))
    res = _quiet(lambda: fit(rec.u, rec.y, family="classical", thresholds=keep, **options),
                 notes)
    out["classical"] = FittedModel(
        "classical", "conventional PI, paper's thresholds", res.model,
        requested_thresholds=classical, notes=notes, fit_report=res.report)
    multislope = [r * scale for r in MULTISLOPE_THRESHOLDS]
    notes = []
    res = _quiet(lambda: fit(rec.u, rec.y, family="multislope", thresholds=multislope,
                             **options), notes)
    out["multislope"] = FittedModel(
        "multislope", "multislope PI, paper's thresholds", res.model,
        requested_thresholds=multislope, notes=notes, fit_report=res.report)
    return out


def fit_best(rec):
    """pihyst's automatic choice among the PI families (the study compares PI models
    with the paper's: thresholds and weights), thresholds and family judged on
    held-back cycles."""
    notes = []
    res = _quiet(lambda: fit(rec.u, rec.y, family=list(PI_FAMILY_NAMES)), notes)
    title = res.report.family(res.report.chosen)["title"]
    return FittedModel("best", f"pihyst's automatic best: {title}", res.model,
                       notes=notes, fit_report=res.report)


def _model_entry(fm):
    m = fm.model
    entry = {"label": fm.label, "family": m.family, "n_operators": int(m.n_operators),
             "weights": [float(w) for w in m.weights], "offset": float(m.offset),
             "input_range": list(m.input_range), "notes": list(fm.notes)}
    if hasattr(m, "thresholds"):
        entry["thresholds"] = [float(r) for r in m.thresholds]
    if fm.requested_thresholds is not None:
        entry["requested_thresholds"] = [float(r) for r in fm.requested_thresholds]
    if m.family == "multislope":
        entry["shape"] = {"U": m.U, "a": m.a, "b": m.b, "h": m.h}
    if fm.fit_report is not None:
        rep = fm.fit_report
        chosen = rep.family(rep.chosen)
        entry["chosen_family"] = rep.chosen
        entry["title"] = chosen["title"]
        if "shape" in chosen:
            entry["shape"] = chosen["shape"]
        if "thresholds" not in entry and "thresholds" in chosen:
            # stored as polylines (input range not starting at 0): thresholds from the fit
            entry["thresholds"] = [float(r) for r in chosen["thresholds"]]
        entry["criterion"] = rep.to_dict()["criterion"]
        entry["compared"] = {f["family"]: (f["errors"]["held_back"] or f["errors"]["fit"])
                             for f in rep.families}
    return entry


def operator_curves(models, u_lo, u_hi, step=0.5):
    """Outputs of each operator of the fitted classical and multislope models over one
    u_lo -> u_hi -> u_lo cycle from their initial state (paper Figs. 4 and 5)."""
    n = max(2, int(round((u_hi - u_lo) / step)))
    up = np.linspace(u_lo, u_hi, n + 1)
    u = np.concatenate([up, up[-2::-1]])
    out = {}
    for key in ("classical", "multislope"):
        if key not in models:
            continue
        fm = models[key]
        m = fm.model
        thresholds = getattr(m, "thresholds", None)
        if thresholds is None:
            kept = [r for r in (fm.requested_thresholds or ()) if r <= u_hi - u_lo]
            thresholds = kept if len(kept) == m.n_operators else range(m.n_operators)
        out[key] = {"u": u, "outputs": m.operators(u),
                    "thresholds": [float(r) for r in thresholds],
                    "annotations": _multislope_marks(m) if key == "multislope" else []}
    return out


def _multislope_marks(m):
    """Fig. 5's landmarks of the largest-threshold multislope operator: the rising kink
    at ((b - 1)U + (1 - a)r)/(b - a), the hold from U down to U - h r, the falling kink
    at ((1 - a)U - (1 - a h)r)/(b - a) (95 V, 150 -> 130 V and 15 V for r = 40)."""
    if m.family != "multislope":
        return []
    r = float(m.thresholds.max())
    U, a, b, h = m.U, m.a, m.b, m.h
    rise = ((b - 1) * U + (1 - a) * r) / (b - a)
    fall = ((1 - a) * U - (1 - a * h) * r) / (b - a)
    hold_end = U - h * r
    return [(rise, a * (rise - r), f"rising kink {rise:.4g} V"),
            (U, U - r, ""),
            (hold_end, U - r, f"holds from {U:.4g} V to {hold_end:.4g} V"),
            (fall, b * fall, f"falling kink {fall:.4g} V")]


def _improvement(classical, multislope):
    # 100 (1 - MAE_multislope / MAE_conventional), the paper's "78.6 % less"
    return 100.0 * (1.0 - multislope / classical) if classical > 0 else None


def _record(plant, name, t, u, description):
    return Recording(name, t, u, plant.run(u, t), description)


def _concat(*signals, dt):
    """Signals one after the other (each starts where the previous ended, at u_min)."""
    u = np.concatenate([signals[0][1]] + [s[1][1:] for s in signals[1:]])
    return np.arange(u.size) * dt, u


# ----------------------------------------------------------------------------- demo
def paper_study(plant: str = "paper-beam", *, seed: int = 0, dt: float = 0.1,
                variants: bool = True, rig: bool = False,
                progress: Callable[[str], object] | None = print) -> "Study":
    """The paper's study on the simulated beam ``plant``.

    Parameters
    ----------
    plant : str
        Simulated beam (:data:`pihyst.sim.PLANT_NAMES`).
    seed : int
        Noise seed of the first record; later records use seed + 1, + 2, ...
    dt : float
        Sample interval of the paper's records (s); the identification and variant
        records use max(dt, 0.2 s) and max(dt, 0.5 s).
    variants : bool
        Repeat the comparison on every other simulated beam.
    rig : bool
        Also run the experiment through the emulated instruments (pihyst.rig), in
        virtual time: record, fit, track open loop and with feedback.
    progress : callable or None
        Receives one line per step.

    Returns
    -------
    Study

    Examples
    --------
    >>> study = paper_study(dt=2.0, variants=False, progress=None)
    >>> bool(study.metrics["improvement_pct"] > 60)     # paper: 78.6 % less error
    True
    >>> study.models["multislope"].model.thresholds.tolist()
    [0.0, 20.0, 30.0, 40.0]
    """
    n_steps = 7 + (1 if variants else 0) + (1 if rig else 0)
    prog = Progress(progress, n_steps)
    beam = make_plant(plant, seed=seed)
    u_max = beam.u_max

    prog.step(f"recording the loop on the simulated beam '{plant}': 0-{u_max:g}-0 V "
              f"triangle, 300 s")
    t, u = triangle(u_max=u_max, dt=dt)
    loop = _record(beam, "loop", t, u, "the paper's drive: 0-150-0 V triangle, 300 s period")

    prog.step("fitting the conventional PI (0, 10, 30, 150) and the multislope PI "
              "(0, 20, 30, 40) as the paper did")
    models = fit_paper_models(loop)

    prog.step("recording an identification run with minor loops and fitting pihyst's "
              "automatic best")
    dt_id = max(dt, 0.2)
    t_id, u_id = _concat(triangle(u_max=u_max, n_cycles=2, dt=dt_id),
                         decaying_triangles(u_max=u_max, dt=dt_id), dt=dt_id)
    ident = _record(make_plant(plant, seed=seed + 1), "identification", t_id, u_id,
                    "two 0-150-0 V triangles, then five decaying triangles (minor loops)")
    models["best"] = fit_best(ident)

    prog.step("judging the three models on a record with reversals inside the range")
    t_v, u_v = random_ramps(u_max=u_max, n_ramps=20, dt=dt_id, seed=seed + 100)
    valid = _record(make_plant(plant, seed=seed + 2), "validation", t_v, u_v,
                    "20 ramps at 1 V/s between random levels (seed "
                    f"{seed + 100}), fitted by no model")
    predictions: dict[str, dict[str, Any]] = {"loop": {}, "validation": {}}
    for key, fm in models.items():
        predictions["loop"][key] = fm.model.predict(loop.u)
        predictions["validation"][key] = fm.model.predict(valid.u)

    prog.step("compensating a triangular displacement trajectory and driving the beam "
              "(Figs. 11-12)")
    peak = float(loop.y[np.argmax(loop.u)])
    t_d, y_d = triangle(u_max=0.98 * peak, dt=dt)
    tracking = {"triangle": _track(plant, seed + 3, models, t_d, y_d, peak, u_max,
                                   "0 -> 98 % of the recorded peak -> 0 µm, 300 s")}

    prog.step("tracking a trajectory with reversals inside the range")
    t_r, y_r = random_ramps(u_max=0.9 * peak, n_ramps=12, rate=2 * peak / 300.0, dt=dt,
                            seed=seed + 200)
    tracking["reversals"] = _track(plant, seed + 4, models, t_r, y_r, peak, u_max,
                                   "12 ramps between random levels in 0-90 % of the "
                                   "recorded peak")

    rig_results = None
    if rig:
        from pihyst.study._rig_study import rig_study
        prog.step("the experiment through the emulated instruments' protocols (virtual time)")
        rig_results = rig_study(plant, seed=seed + 5, realtime_s=3.0, progress=progress)

    variant_rows, variant_loops = [], {}
    if variants:
        prog.step("repeating the comparison on the other simulated beams")
        for name in PLANT_NAMES:
            row, loop_v = _variant(name, seed, u_max, max(dt, 0.5))
            variant_rows.append(row)
            variant_loops[name] = loop_v

    prog.step("computing the operators (Figs. 4-5) and the metrics")
    operators = operator_curves(models, 0.0, u_max)
    records = {"loop": loop, "identification": ident, "validation": valid}
    metrics = _demo_metrics(beam, loop, valid, models, predictions, tracking, variant_rows,
                            seed, dt)
    study = Study("demo", "Multislope PI modelling and feedforward compensation of a "
                  "piezoelectric beam: the paper's study on pihyst's simulated beam",
                  beam.describe(), loop, models, predictions,
                  operators, metrics, records=records, tracking=tracking,
                  variants=variant_rows, variant_loops=variant_loops, rig=rig_results)
    if rig_results is not None:
        metrics["rig"] = rig_results.metrics()
    metrics["timing_s"] = {"steps": dict(prog.timings)}
    metrics["timing_s"]["total_computation"] = prog.done()
    metrics["timing_s"]["steps"].update(prog.timings)
    return study


def _track(plant, seed, models, t, desired, peak, u_max, description):
    """Compensate ``desired`` with each model (and none: voltage proportional to the
    desired displacement), drive a fresh beam, measure."""
    out = {"description": description, "t": t, "desired": desired, "voltage": {},
           "measured": {}, "metrics": {}}
    runs = {"none": (desired * (u_max / peak), None)}
    for key in ("multislope", "classical", "best"):
        res = compensate(models[key].model, desired, u_min=0.0, u_max=u_max)
        runs[key] = (res.voltage, res.saturated)
    for key, (voltage, saturated) in runs.items():
        measured = make_plant(plant, seed=seed).run(voltage, t)
        out["voltage"][key] = voltage
        out["measured"][key] = measured
        out["metrics"][key] = tracking_metrics(desired, measured, voltage, saturated)
    return out


def _variant(name, seed, u_max, dt):
    """The comparison on one simulated beam (coarser sampling, same method)."""
    t, u = triangle(u_max=u_max, dt=dt)
    loop = _record(make_plant(name, seed=seed), "loop", t, u, "")
    models = fit_paper_models(loop)
    t_id, u_id = _concat(triangle(u_max=u_max, n_cycles=2, dt=dt),
                         decaying_triangles(u_max=u_max, dt=dt), dt=dt)
    models["best"] = fit_best(_record(make_plant(name, seed=seed + 1), "identification",
                                      t_id, u_id, ""))
    t_v, u_v = random_ramps(u_max=u_max, n_ramps=20, dt=dt, seed=seed + 100)
    valid = _record(make_plant(name, seed=seed + 2), "validation", t_v, u_v, "")
    row = {"plant": name, "range_um": loop.span_y, "loop": {}, "validation": {},
           "best_family": models["best"].fit_report.chosen}
    for key, fm in models.items():
        row["loop"][key] = error_summary(loop.y, fm.model.predict(loop.u),
                                         loop.span_y)["mean_abs"]
        row["validation"][key] = error_summary(valid.y, fm.model.predict(valid.u),
                                               valid.span_y)["mean_abs"]
    row["improvement_pct"] = _improvement(row["loop"]["classical"], row["loop"]["multislope"])
    return row, (loop.u, loop.y)


def _demo_metrics(beam, loop, valid, models, predictions, tracking, variant_rows, seed, dt):
    fits = {k: fit_metrics(loop, predictions["loop"][k]) for k in models}
    val = {k: fit_metrics(valid, predictions["validation"][k]) for k in models}
    tri = tracking["triangle"]["metrics"]
    return {
        "pihyst_version": __version__,
        "mode": "demo",
        "plant": {"name": beam.name, "description": beam.describe(), "seed": seed,
                  "dt_s": dt},
        "loop": {"samples": int(loop.u.size), "peak_um": float(loop.y[np.argmax(loop.u)]),
                 "end_um": float(loop.y[-1]), "range_um": loop.span_y},
        "models": {k: _model_entry(fm) for k, fm in models.items()},
        "fit": fits,
        "improvement_pct": _improvement(fits["classical"]["mean_abs"],
                                        fits["multislope"]["mean_abs"]),
        "validation": val,
        "tracking": {name: {"description": tr["description"], "errors": tr["metrics"]}
                     for name, tr in tracking.items()},
        "headline": {
            "fit_mean_abs_classical_um": fits["classical"]["mean_abs"],
            "fit_mean_abs_multislope_um": fits["multislope"]["mean_abs"],
            "fit_improvement_pct": _improvement(fits["classical"]["mean_abs"],
                                                fits["multislope"]["mean_abs"]),
            "tracking_mean_abs_multislope_um": tri["multislope"]["mean_abs"],
            "tracking_rms_multislope_um": tri["multislope"]["rms"],
            "tracking_mean_abs_pct_of_range": tri["multislope"]["mean_abs_pct"],
        },
        "variants": variant_rows,
        "paper": PAPER,
    }


# ----------------------------------------------------------------------------- report
def loop_study(t: ArrayLike, u: ArrayLike, y: ArrayLike, *, source: str,
               progress: Callable[[str], object] | None = print) -> "Study":
    """The fit-and-compare study on a user's own record (no simulator).

    The paper's thresholds are scaled to the record's input span and measured from the
    bottom of its range; the initial state is found from the data and an offset is
    fitted (the record may start anywhere, the sensor zero is arbitrary).

    Parameters
    ----------
    t : array_like
        Sample times (s).
    u : array_like
        Voltages (V).
    y : array_like
        Displacements (µm).
    source : str
        Where the record comes from (its file), for the report.
    progress : callable or None
        Receives one line per step.

    Returns
    -------
    Study
        The study, for :func:`pihyst.study.write_report`.

    Raises
    ------
    FitError
        If the record cannot be fitted.

    Examples
    --------
    >>> from pihyst.sim import make_plant
    >>> from pihyst.sim.signals import decaying_triangles
    >>> t, u = decaying_triangles(dt=2.0)
    >>> y = make_plant("remanent").run(u, t)
    >>> study = loop_study(t, u, y, source="example", progress=None)
    >>> sorted(study.models)
    ['best', 'classical', 'multislope']
    """
    prog = Progress(progress, 3)
    loop = Recording("loop", np.asarray(t, float), np.asarray(u, float), np.asarray(y, float),
                  source)
    span = float(np.ptp(loop.u))
    scale = span / PAPER_SPAN_V
    prog.step("fitting the conventional PI and the multislope PI with the paper's "
              f"thresholds (scaled to the {span:.4g} V input span)")
    models = fit_paper_models(loop, paper_method=False, scale=scale)
    prog.step("fitting pihyst's automatic best")
    models["best"] = fit_best(loop)
    prog.step("computing the operators and the metrics")
    full = {k: fm.model.predict(loop.u) for k, fm in models.items()}
    # a record that does not start at rest: its first sweep only settles the operator
    # states (identification leaves it out), so it is not judged either
    settle = int(models["best"].fit_report.to_dict()["data"]["settle_samples"])
    record = loop
    loop = Recording("loop", record.t[settle:], record.u[settle:], record.y[settle:], source)
    predictions = {"loop": {k: y[settle:] for k, y in full.items()}, "record": full}
    lo, hi = float(loop.u.min()), float(loop.u.max())
    operators = operator_curves(models, lo, hi, step=(hi - lo) / 300)
    fits = {k: fit_metrics(loop, predictions["loop"][k]) for k in models}
    metrics = {
        "pihyst_version": __version__,
        "mode": "report",
        "source": source,
        "loop": {"samples": int(record.u.size), "settle_samples": settle,
                 "input_range": [lo, hi], "range_um": loop.span_y},
        "threshold_scale": scale,
        "models": {k: _model_entry(fm) for k, fm in models.items()},
        "fit": fits,
        "improvement_pct": _improvement(fits["classical"]["mean_abs"],
                                        fits["multislope"]["mean_abs"]),
        "paper": PAPER,
    }
    study = Study("report", "Hysteresis models fitted to a measured loop", source, loop,
                  models, predictions, operators, metrics, records={"record": record})
    metrics["timing_s"] = {"steps": dict(prog.timings)}
    metrics["timing_s"]["total_computation"] = prog.done()
    metrics["timing_s"]["steps"].update(prog.timings)
    return study
