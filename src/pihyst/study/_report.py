"""Write a study (:mod:`pihyst.study`) as a report folder.

``write_report(study, out_dir)`` writes:

- ``report.html``: self-contained (figures embedded as base64 PNG data URIs, CSS inline),
  opens from disk in any browser; every metric beside the paper's number;
- ``fig*.png``: the same figures as files;
- ``metrics.json``: every number of the report;
- ``*.csv``: the records, predictions and tracking runs (docs/interfaces.md columns);
- ``model_classical.json``, ``model_multislope.json``, ``model_best.json``: the fitted
  models (:func:`pihyst.load_model` reads them).

Every file is written complete or not at all.
"""

import base64
import datetime
import html
import io
import json
import os
import re
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from pihyst._atomic import write_atomically
from pihyst.io import save_model, write_columns
from pihyst.io._csv import sidecar_path
from pihyst.study import _plot as plot

if TYPE_CHECKING:
    from pihyst.study._paper_study import Study

MODEL_ORDER = ("classical", "multislope", "best")


# ----------------------------------------------------------------------------- files
def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return [_jsonable(v) for v in x.tolist()]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if np.isfinite(x) else None
    return x


# ----------------------------------------------------------------------------- formatting
def _f(x, digits=4):
    """A number for a table cell ('-' when missing)."""
    if x is None:
        return "&ndash;"
    if isinstance(x, str):
        return html.escape(x)
    return f"{x:.{digits}g}"


def _signed(x, digits=3):
    return "&ndash;" if x is None else f"{x:+.{digits}g}"


def _table(head, rows, cls="data"):
    out = [f'<table class="{cls}"><thead><tr>']
    out += [f"<th>{h}</th>" for h in head]
    out.append("</tr></thead><tbody>")
    for row in rows:
        out.append("<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def _list(values, digits=4):
    return ", ".join(f"{v:.{digits}g}" for v in values)


# ----------------------------------------------------------------------------- figures
class _Figures:
    """Figures in page order: (key, file name, title, caption, PNG bytes, paper's figure
    or None); ``extra`` holds each figure in the other formats asked for (SVG, PDF) by
    file name.

    Beside the paper (``paper``), a figure that reproduces one of the paper's carries
    its number ("Figure 7", ``fig7_loop.png`` for the paper's Fig. 7) and the others,
    pihyst's additions, are numbered A1, A2, ... in page order; without the paper, every
    figure is numbered 1, 2, ... in page order.
    """

    def __init__(self, formats=(), paper=True):
        self.items = []
        self.formats = tuple(formats)
        self.paper = paper
        self.extra = {}
        self._added = 0

    def _number(self, paper_figure):
        if not self.paper:
            return str(len(self.items) + 1)
        if paper_figure:
            return paper_figure.removeprefix("Fig. ")
        self._added += 1
        return f"A{self._added}"

    def add(self, key, title, caption, fig, paper_figure=None):
        n = self._number(paper_figure)
        name = f"fig{n}_{key}.png"
        if self.paper:
            title = title.removesuffix(" (pihyst)")
            title += (f" (the paper's {paper_figure}, reproduced)" if paper_figure
                      else " (added by pihyst; not in the paper)")
        self.items.append((key, name, f"Figure {n}. {title}", caption, plot.figure_png(fig),
                           paper_figure))
        for fmt in self.formats:
            buf = io.BytesIO()
            fig.savefig(buf, format=fmt, dpi=plot.DPI)
            self.extra[f"fig{n}_{key}.{fmt}"] = buf.getvalue()

    def has(self, key):
        return any(item[0] == key for item in self.items)

    def html(self, key):
        for k, fname, title, caption, png, _ in self.items:
            if k == key:
                data = base64.b64encode(png).decode("ascii")
                return (f'<figure id="{html.escape(fname)}"><img src="data:image/png;base64,'
                        f'{data}" alt="{html.escape(title)}"><figcaption><b>'
                        f'{html.escape(title, quote=False)}.</b> {caption}</figcaption>'
                        '</figure>')
        raise KeyError(key)


def _labels(study):
    return {k: fm.label for k, fm in study.models.items()}


def _make_figures(study, formats=(), paper=True):
    figs = _Figures(formats, paper)
    loop = study.loop
    labels = _labels(study)
    short = {"classical": "conventional PI", "multislope": "multislope PI",
             "best": "pihyst's best"}
    pred = study.predictions["loop"]
    figs.add("loop", "Measured loop and fitted models",
             "The record (black) and each model's prediction for the same voltages.",
             plot.loop_plot(loop.u, loop.y, {k: pred[k] for k in MODEL_ORDER},
                            labels=labels), "Fig. 7")
    errors = {k: loop.y - pred[k] for k in MODEL_ORDER}
    figs.add("fit_errors", "Fitting errors",
             "Measured minus model, against time and against voltage.",
             plot.fit_error_plot(loop.t, loop.u, errors, labels=short), "Fig. 8")
    ops = study.operators
    if "classical" in ops:
        c = ops["classical"]
        figs.add("classical_operators", "Play operators of the conventional PI",
                 "Output of each classical play operator of the fitted model over one "
                 "cycle of the input range, from the model's initial state.",
                 plot.operators_plot(c["u"], c["outputs"], c["thresholds"],
                                     title="Classical play operators"), "Fig. 4")
    if "multislope" in ops:
        m = ops["multislope"]
        figs.add("multislope_operators", "Multislope play operators",
                 "Output of each multislope operator (paper eq. 6) over one cycle; the "
                 "landmarks of the largest threshold are marked.",
                 plot.operators_plot(m["u"], m["outputs"], m["thresholds"],
                                     title="Multislope play operators",
                                     annotations=m["annotations"]), "Fig. 5")
    if study.mode == "demo":
        _demo_figures(study, figs, short)
    if study.learning is not None:
        from pihyst.study._learning import add_learning_figures
        add_learning_figures(study.learning, figs, plot)
    return figs


def _demo_figures(study, figs, short):
    """The demo's figures, added in the order the page shows them."""
    val = study.records["validation"]
    pv = study.predictions["validation"]
    figs.add("validation", "Errors on data no model was fitted on (pihyst)",
             "Random ramps with reversals inside the range (minor loops): measured minus "
             "model.",
             plot.fit_error_plot(val.t, val.u, {k: val.y - pv[k] for k in MODEL_ORDER},
                                 labels=short, title="Validation error (measured - model)"))
    tri = study.tracking["triangle"]
    figs.add("voltages", "Driving voltages",
             "Voltage commanded for the triangular trajectory: proportional to the desired "
             "displacement (without compensation) and from each inverse model.",
             plot.voltage_plot(tri["t"], {k: tri["voltage"][k] for k in
                                          ("none", "multislope", "classical", "best")},
                               labels=short | {"none": "without compensation"}), "Fig. 11")
    figs.add("tracking", "Tracking and tracking error",
             "Desired and measured displacement of the beam, and the tracking error "
             "(measured minus desired).",
             plot.tracking_plot(tri["t"], tri["desired"],
                                {k: tri["measured"][k] for k in ("none", "multislope")},
                                {k: tri["measured"][k] - tri["desired"] for k in
                                 ("none", "multislope", "best")},
                                labels=short), "Fig. 12")
    rev = study.tracking["reversals"]
    figs.add("tracking_reversals", "Tracking with reversals inside the range (pihyst)",
             "The paper tracks only a full-range triangle. Here the desired trajectory "
             "turns inside the range, where the models' minor loops matter.",
             plot.tracking_plot(rev["t"], rev["desired"],
                                {k: rev["measured"][k] for k in ("multislope", "best")},
                                {k: rev["measured"][k] - rev["desired"] for k in
                                 ("classical", "multislope", "best")},
                                labels=short, title="Tracking with reversals inside the range"))
    if study.variants:
        names = [r["plant"] for r in study.variants]
        figs.add("variants", "The comparison on every simulated beam (pihyst)",
                 "Mean absolute error on each beam's validation record (random ramps, "
                 "fitted by no model).",
                 plot.error_bars_plot(names, {k: [r["validation"][k] for r in study.variants]
                                              for k in MODEL_ORDER}, labels=short,
                                      title="Validation error per simulated beam"))
        figs.add("beams", "The simulated beams (pihyst)",
                 "Each beam's loop for the 0-150-0 V, 300 s triangle.",
                 plot.loops_grid_plot(study.variant_loops))
    if study.rig is not None:
        from pihyst.study._rig_study import rig_figure
        figs.add("rig_tracking", "Tracking through the rig (pihyst)",
                 "The triangle tracked through the emulated instruments, open loop and "
                 "with feedback; error = measured - desired.", rig_figure(study.rig))


# ----------------------------------------------------------------------------- tables
def _table1(study, paper_columns=True):
    paper = study.metrics["paper"]["table1"]
    models = study.metrics["models"]
    rows = []
    for key, name in (("classical", "conventional PI"), ("multislope", "multislope PI")):
        m = models[key]
        thresholds = m.get("thresholds") or []
        requested = m.get("requested_thresholds", thresholds)
        p = paper[key]
        for i, r in enumerate(requested):
            j = [k for k, t in enumerate(thresholds) if abs(t - r) <= 1e-9 * max(1.0, abs(r))]
            weight = _f(m["weights"][j[0]]) if j else "&ndash; (never moves: left out)"
            rows.append([name if i == 0 else "", _f(r), weight,
                         _f(p["thresholds"][i]) if i < len(p["thresholds"]) else "",
                         _f(p["weights"][i]) if i < len(p["weights"]) else ""])
    paper_head = "threshold, paper (V)" if study.mode == "demo" else \
        "threshold, paper (V, its 0-150 V beam)"
    if not paper_columns:
        return _table(["model", "threshold r (V)", "weight"], [r[:3] for r in rows])
    return _table(["model", "threshold r (V)", "weight, pihyst", paper_head, "weight, paper"],
                  rows)


def _fit_table(study, paper_columns=True):
    m = study.metrics
    paper = m["paper"]["fit"]
    rows = []
    for key in MODEL_ORDER:
        e = m["fit"][key]
        p = paper.get(key, {})
        pe = p.get("extremes", {})
        rows.append([html.escape(study.models[key].label), _f(e["mean_abs"]),
                     _f(p.get("mean_abs")) if study.mode == "demo" else
                     _f(p.get("mean_abs")) + " (paper's beam)",
                     _f(e["max_abs"]), _f(e["rms"]), f'{e["mean_abs_pct"]:.3g} %',
                     " / ".join(_signed(e["extremes"][k]) for k in ("low", "middle", "high")),
                     " / ".join(_signed(pe.get(k)) for k in ("low", "middle", "high"))
                     if pe else "&ndash;"])
    head = ["model", "mean |e| (µm)", "paper", "max |e| (µm)", "RMS (µm)",
            "mean |e| / range", "extremes low / mid / high (µm)", "paper"]
    if not paper_columns:
        keep = [0, 1, 3, 4, 5, 6]
        return _table([head[i] for i in keep], [[r[i] for i in keep] for r in rows])
    return _table(head, rows)


def _tracking_table(study, name, paper_row):
    tr = study.metrics["tracking"][name]["errors"]
    rows = []
    for key, label in (("none", "without compensation"), ("multislope", "multislope PI"),
                       ("classical", "conventional PI"), ("best", "pihyst's best")):
        e = tr[key]
        sat = e["saturated_samples"]
        p = study.metrics["paper"]["tracking"] if (paper_row and key == "multislope") else {}
        rows.append([label, _f(e["mean_abs"]), _f(p.get("mean_abs")), _f(e["rms"]),
                     _f(p.get("rms")), _f(e["max_abs"]), f'{e["mean_abs_pct"]:.3g} %',
                     "&ndash;" if sat is None else str(sat)])
    return _table(["compensation", "mean |e| (µm)", "paper", "RMS (µm)", "paper",
                   "max |e| (µm)", "mean |e| / range", "saturated samples"], rows)


def _validation_table(study):
    rows = []
    for key in MODEL_ORDER:
        e = study.metrics["validation"][key]
        rows.append([html.escape(study.models[key].label), _f(e["mean_abs"]), _f(e["max_abs"]),
                     _f(e["rms"]), f'{e["mean_abs_pct"]:.3g} %'])
    return _table(["model", "mean |e| (µm)", "max |e| (µm)", "RMS (µm)", "mean |e| / range"],
                  rows)


def _variants_table(study):
    rows = []
    for r in study.variants:
        rows.append([html.escape(r["plant"]), _f(r["range_um"], 3),
                     _f(r["loop"]["classical"]), _f(r["loop"]["multislope"]),
                     _f(r["improvement_pct"], 3) + " %", _f(r["validation"]["classical"]),
                     _f(r["validation"]["multislope"]), _f(r["validation"]["best"]),
                     html.escape(r["best_family"])])
    return _table(["beam", "range (µm)", "conventional, loop", "multislope, loop",
                   "multislope vs conventional", "conventional, validation",
                   "multislope, validation", "pihyst's best, validation",
                   "pihyst's best family"], rows)


def _summary(study, paper_columns=True):
    m = study.metrics
    fit = m["fit"]
    imp = m["improvement_pct"]
    p = m["paper"]
    rows = [
        ["conventional PI, mean |fitting error|", f'{_f(fit["classical"]["mean_abs"])} µm',
         f'{p["fit"]["classical"]["mean_abs"]} µm'],
        ["multislope PI, mean |fitting error|", f'{_f(fit["multislope"]["mean_abs"])} µm',
         f'{p["fit"]["multislope"]["mean_abs"]} µm'],
        ["multislope vs conventional", f"{_f(imp, 3)} % less",
         f'{p["fit"]["improvement_pct"]} % less'],
        ["conventional PI, extreme errors low / middle / high",
         " / ".join(f"{_signed(fit['classical']['extremes'][k])} µm"
                    for k in ("low", "middle", "high")),
         " / ".join(f"{_signed(p['fit']['classical']['extremes'][k])} µm"
                    for k in ("low", "middle", "high"))],
    ]
    if study.mode == "demo":
        tr = m["tracking"]["triangle"]["errors"]["multislope"]
        rows += [
            ["feedforward tracking (multislope), mean |error|", f'{_f(tr["mean_abs"])} µm',
             f'{p["tracking"]["mean_abs"]} µm'],
            ["feedforward tracking (multislope), RMS error", f'{_f(tr["rms"])} µm',
             f'{p["tracking"]["rms"]:.4f} µm (the paper\'s "MSE")'],
            ["tracking mean |error| / range", f'{tr["mean_abs_pct"]:.3g} %',
             f'{p["tracking"]["mean_abs_pct_of_range"]:.3g} % of '
             f'{p["beam"]["max_displacement_um"]:g} µm'],
        ]
    verdict = ("The multislope PI beats the conventional PI" if imp is not None and imp > 0
               else "The multislope PI does not beat the conventional PI")
    text = (f"<p class=\"verdict\">{verdict} here: {_f(imp, 3)} % less mean absolute fitting "
            f"error" + (f" (paper: {p['fit']['improvement_pct']} %)." if paper_columns else "."))
    if study.mode == "demo":
        best = m["validation"]["best"]["mean_abs"]
        text += (f" On data with reversals inside the range, which no model was fitted on, "
                 f"pihyst's automatic choice ({html.escape(m['models']['best']['title'])}) "
                 f"errs by {_f(best, 3)} µm on average, against "
                 f"{_f(m['validation']['multislope']['mean_abs'], 3)} µm for the multislope "
                 f"PI and {_f(m['validation']['classical']['mean_abs'], 3)} µm for the "
                 f"conventional PI.")
    text += "</p>"
    paper_head = "paper" if study.mode == "demo" else "paper (its own beam, for reference)"
    if not paper_columns:
        return text + _table(["quantity", "this record"], [r[:2] for r in rows])
    return text + _table(["quantity", "pihyst", paper_head], rows)


# ----------------------------------------------------------------------------- html
CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;max-width:1060px;
margin:2em auto;padding:0 1.2em;color:#1d1d1f;line-height:1.45}
h1{font-size:1.55em;margin-bottom:.2em}h2{font-size:1.2em;margin-top:2em;
border-bottom:1px solid #ddd;padding-bottom:.2em}
.meta{color:#666;font-size:.9em}.verdict{font-size:1.05em;background:#f3f7fb;
padding:.7em 1em;border-left:4px solid #1f77b4}
table.data{border-collapse:collapse;margin:.8em 0;font-size:.9em}
table.data th,table.data td{border:1px solid #ccc;padding:.3em .6em;text-align:right}
table.data th{background:#f4f4f4}table.data td:first-child{text-align:left}
figure{margin:1.2em 0}figure img{max-width:100%;border:1px solid #eee}
figcaption{font-size:.9em;color:#333;margin-top:.3em}code{background:#f4f4f4;padding:0 .2em}
ul.notes li{font-size:.9em;margin:.2em 0}
"""


def _notes(study):
    items = []
    for key in MODEL_ORDER:
        fm = study.models[key]
        for n in fm.notes:
            items.append(f"<li><b>{html.escape(fm.label)}</b>: {_prose(n)}</li>")
    return f'<ul class="notes">{"".join(items)}</ul>' if items else "<p>None.</p>"


def _best_section(study):
    fm = study.models["best"]
    entry = study.metrics["models"]["best"]
    rows = []
    for fam, e in entry.get("compared", {}).items():
        rows.append([html.escape(fam) + (" (chosen)" if fam == entry.get("chosen_family")
                                         else ""), _f(e["rms"]), _f(e["mean_abs"]),
                     _f(e["max_abs"])])
    text = (f"<p>{html.escape(fm.label)}: {entry['n_operators']} operators, chosen by "
            f"{html.escape(entry.get('criterion', ''))}. Every family pihyst fits, with its "
            f"errors on the cycles held back from its fit:</p>")
    report_text = _prose(str(fm.fit_report)) if fm.fit_report is not None else ""
    return (text + _table(["family", "RMS (µm)", "mean |e| (µm)", "max |e| (µm)"], rows)
            + f"<details><summary>full identification report</summary><pre>{report_text}"
              "</pre></details>")


_UM = re.compile(r"(?<![\w.])um\b")


def _prose(text):
    """Text from elsewhere (descriptions, notes, the fit report) for the page: escaped,
    micrometres written µm."""
    return _UM.sub("µm", html.escape(text, quote=False))


def _files_list(names):
    return "<ul>" + "".join(f"<li><code>{html.escape(n)}</code></li>" for n in names) + "</ul>"


def render_html(study, figs, files, command, paper=True):
    m = study.metrics
    stamp = datetime.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z")
    parts = [
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">",
        "<meta name=\"viewport\" content=\"width=device-width,initial-scale=1\">",
        f"<title>{html.escape(study.title)}</title><style>{CSS}</style></head><body>",
        f"<h1>{html.escape(study.title)}</h1>",
        f"<p class=\"meta\">pihyst {html.escape(m['pihyst_version'])}, {stamp}: "
        f"<code>{html.escape(command)}</code>; computed in "
        f"{m['timing_s']['total_computation']:.1f} s. Paper: {html.escape(m['paper']['source'])}."
        f"</p>",
        "<h2>Summary</h2>", _summary(study, paper),
        "<h2>The data</h2>", f"<p>{_prose(study.source)}</p>",
    ]
    if study.mode == "demo":
        lp = m["loop"]
        parts.append(f"<p>Recorded loop: {lp['samples']} samples, {lp['peak_um']:.4g} µm at "
                     f"150 V (paper's beam: {m['paper']['beam']['max_displacement_um']:g} µm), "
                     f"{lp['end_um']:+.3g} µm back at 0 V. "
                     f"Errors are measured minus model, the paper's sign.</p>")
    else:
        lp = m["loop"]
        if lp["settle_samples"]:
            parts.append(f"<p>The record does not start at rest: its first "
                         f"{lp['settle_samples']} samples (the first sweep of the input "
                         f"range) only settle the operators' states. They are in "
                         f"<code>record.csv</code> but neither fitted nor judged, nor "
                         f"plotted.</p>")
        parts.append(f"<p>{lp['samples']} samples, input {lp['input_range'][0]:.4g} .. "
                     f"{lp['input_range'][1]:.4g}, output range {lp['range_um']:.4g} µm. The "
                     f"paper's thresholds are scaled by {m['threshold_scale']:.4g} (input "
                     f"span / 150 V) and measured from the bottom of the input range; initial "
                     f"states are found from the data and an offset is fitted."
                     + (" The paper's numbers are for its own beam, shown for reference."
                        if paper else "") + "</p>")
    parts += ["<h2>Thresholds and weights" + (" (the paper's Table 1)" if paper else "")
              + "</h2>", _table1(study, paper),
              "<h2>Fitting the loop</h2>", _fit_table(study, paper),
              figs.html("loop"), figs.html("fit_errors"),
              "<h2>Operators</h2>"]
    for key in ("classical_operators", "multislope_operators"):
        if figs.has(key):
            parts.append(figs.html(key))
    if study.mode == "demo":
        parts += ["<h2>Models judged on data they were not fitted on</h2>",
                  f"<p>{_prose(study.records['validation'].description)}.</p>",
                  _validation_table(study), figs.html("validation"),
                  "<h2>Feedforward compensation</h2>",
                  "<p>Desired trajectory: "
                  f"{_prose(study.tracking['triangle']['description'])}. "
                  "Each model's exact inverse gives the voltage (within 0-150 V); without "
                  "compensation the voltage is proportional to the desired displacement.</p>",
                  _tracking_table(study, "triangle", True),
                  figs.html("voltages"), figs.html("tracking"),
                  "<h3>Reversals inside the range</h3>",
                  f"<p>{_prose(study.tracking['reversals']['description'])}.</p>",
                  _tracking_table(study, "reversals", False),
                  figs.html("tracking_reversals")]
        if study.variants:
            parts += ["<h2>Other simulated beams</h2>",
                      "<p>The same method on every simulated beam (loop: the paper's "
                      "triangle; validation: random ramps), mean absolute errors in µm.</p>",
                      _variants_table(study), figs.html("variants"),
                      figs.html("beams")]
    if study.rig is not None:
        from pihyst.study._rig_study import rig_html
        parts.append(rig_html(study.rig, figs.html("rig_tracking")))
    if study.learning is not None:
        from pihyst.study._learning import learning_html
        parts.append(learning_html(study.learning, figs))
    parts += ["<h2>pihyst's automatic choice</h2>", _best_section(study),
              "<h2>Notes</h2>", _notes(study),
              "<h2>Files</h2>", _files_list(files), "</body></html>"]
    return "\n".join(parts)


# ----------------------------------------------------------------------------- entry
def write_report(study: "Study", out_dir: "str | os.PathLike[str]", *, command: str = "",
                 progress: Callable[[str], object] | None = None,
                 figure_formats: Sequence[str] = (), paper: bool | None = None) -> list[str]:
    """Write the report folder ``out_dir`` (created if needed) for a
    :class:`pihyst.study.Study`; returns the names of the files written.

    Figures are numbered in page order and written as PNG, and also in each of
    ``figure_formats`` ("svg", "pdf"). ``paper``: show the paper's numbers beside the
    study's (default: for the demo, not for a user's record).

    Parameters
    ----------
    study : Study
        What :func:`pihyst.study.paper_study` or :func:`pihyst.study.loop_study`
        returned.
    out_dir : str or os.PathLike
        The report folder.
    command : str
        The command that made the study, shown in the report.
    progress : callable, optional
        Receives one line per step.
    figure_formats : sequence of str
        Also write every figure in these formats (``"svg"``, ``"pdf"``).
    paper : bool, optional
        Show the paper's numbers (default: for the demo only).

    Returns
    -------
    list of str
        The names of the files written, in ``out_dir``.

    Raises
    ------
    OSError
        If the folder or a file cannot be written.

    Examples
    --------
    >>> import tempfile
    >>> from pihyst.study import paper_study
    >>> study = paper_study(dt=2.0, variants=False, progress=None)
    >>> with tempfile.TemporaryDirectory() as out:
    ...     files = write_report(study, out, command="example")
    >>> "report.html" in files and "metrics.json" in files
    True
    """
    os.makedirs(out_dir, exist_ok=True)
    say = progress or (lambda line: None)
    say("drawing the figures ...")
    paper = study.mode == "demo" if paper is None else paper
    figs = _make_figures(study, figure_formats, paper)
    files = []
    for _, name, _, _, png, _ in figs.items:
        write_atomically(os.path.join(out_dir, name), png)
        files.append(name)
    for name, data in figs.extra.items():
        write_atomically(os.path.join(out_dir, name), data)
        files.append(name)
    say("writing data, models and metrics ...")
    files += _write_data(study, out_dir)
    for key in MODEL_ORDER:
        name = f"model_{key}.json"
        save_model(study.models[key].model, os.path.join(out_dir, name))
        files.append(name)
    write_atomically(os.path.join(out_dir, "metrics.json"),
                     json.dumps(_jsonable(study.metrics), indent=2, allow_nan=False) + "\n")
    files.append("metrics.json")
    files.append("report.html")
    write_atomically(os.path.join(out_dir, "report.html"),
                     render_html(study, figs, files, command, paper))
    return files


def _write_data(study, out_dir):
    names = []
    for rec_name, rec in study.records.items():
        cols = {"time_s": rec.t, "voltage_V": rec.u, "displacement_um": rec.y}
        for key, y_hat in study.predictions.get(rec_name, {}).items():
            cols[f"{key}_um"] = y_hat
        name = f"{rec_name}.csv"
        write_columns(os.path.join(out_dir, name), cols,
                      comments=[rec.description] if rec.description else ())
        names.append(name)
        if rec.description:             # its description, in the CSV's sidecar
            names.append(sidecar_path(name))
    for exp_name, tr in study.tracking.items():
        cols = {"time_s": tr["t"], "desired_um": tr["desired"]}
        for key in tr["voltage"]:
            cols[f"voltage_V_{key}"] = tr["voltage"][key]
            cols[f"displacement_um_{key}"] = tr["measured"][key]
        name = f"tracking_{exp_name}.csv"
        write_columns(os.path.join(out_dir, name), cols,
                      comments=[f"desired trajectory: {tr['description']}; voltages and "
                                "measured displacements per compensation (none = voltage "
                                "proportional to the desired displacement)"])
        names += [name, sidecar_path(name)]
    if study.rig is not None:
        names += study.rig.write_logs(out_dir)
    return names
