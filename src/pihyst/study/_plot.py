"""Figures of the report: ``<what>_plot(...)`` functions that draw given arrays and
return a :class:`matplotlib.figure.Figure` (no computation here, no global pyplot state;
rendered with the Agg backend).

Series are passed as dicts ``{key: array}``; keys in :data:`STYLE` (``"measured"``,
``"desired"``, ``"none"``, ``"classical"``, ``"multislope"``, ``"best"``) get the report's
colours, ``labels`` maps keys to legend text.

Examples
--------
>>> import numpy as np
>>> u = np.r_[np.linspace(0, 150, 151), np.linspace(149, 0, 150)]
>>> fig = loop_plot(u, 0.3 * u, {"classical": 0.3 * u + 0.1})
>>> png = figure_png(fig)
>>> png[:4] == b"\\x89PNG"
True
"""

import io

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

STYLE = {
    "measured": {"color": "0.2", "lw": 3.2, "alpha": 0.45},
    "desired": {"color": "0.15", "lw": 1.4, "ls": "--"},
    "none": {"color": "0.55", "lw": 1.2},
    "classical": {"color": "#d62728", "lw": 1.3},
    "multislope": {"color": "#1f77b4", "lw": 1.3},
    "best": {"color": "#2ca02c", "lw": 1.3},
}
LABELS = {
    "measured": "measured",
    "desired": "desired",
    "none": "without compensation",
    "classical": "conventional PI",
    "multislope": "multislope PI",
    "best": "pihyst's best",
}
DPI = 110


def _figure(width=7.0, height=4.2, **kw):
    fig = Figure(figsize=(width, height), dpi=DPI, layout="constrained", **kw)
    FigureCanvasAgg(fig)
    return fig


def _style(key):
    return dict(STYLE.get(key, {"lw": 1.2}))


def _label(key, labels):
    return (labels or {}).get(key, LABELS.get(key, key))


def figure_png(fig):
    """The figure as PNG bytes."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    return buf.getvalue()


def loop_plot(u, y, fits, *, labels=None, title="Measured loop and fitted models",
              xlabel="voltage (V)", ylabel="displacement (µm)"):
    """Measured y against u with each model's prediction (paper Fig. 7)."""
    fig = _figure(6.4, 4.8)
    ax = fig.subplots()
    ax.plot(u, y, label=_label("measured", labels), **_style("measured"))
    for key, y_hat in fits.items():
        ax.plot(u, y_hat, label=_label(key, labels), **_style(key))
    ax.set(title=title, xlabel=xlabel, ylabel=ylabel)
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)   # below the rising branch: empty
    return fig


def fit_error_plot(t, u, errors, *, labels=None, title="Fitting error (measured - model)",
                   xlabel_t="time (s)", xlabel_u="voltage (V)", ylabel="error (µm)",
                   marks=None):
    """Errors against time (left) and input (right) (paper Fig. 8). ``marks`` are
    (x_input, error, text) points to annotate on the right (e.g. the paper's extremes)."""
    fig = _figure(9.0, 3.9)
    ax_t, ax_u = fig.subplots(1, 2, sharey=True)
    for key, e in errors.items():
        ax_t.plot(t, e, label=_label(key, labels), **_style(key))
        ax_u.plot(u, e, label=_label(key, labels), **_style(key))
    for x, e, text in marks or ():
        ax_u.plot([x], [e], marker="x", color="k", ms=7, ls="none")
        ax_u.annotate(text, (x, e), textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax_t.set(xlabel=xlabel_t, ylabel=ylabel)
    ax_u.set(xlabel=xlabel_u)
    for ax in (ax_t, ax_u):
        ax.axhline(0, color="k", lw=0.6)
        ax.grid(alpha=0.3)
    ax_t.legend(fontsize=9)
    fig.suptitle(title)
    return fig


def operators_plot(u, outputs, thresholds, *, title, xlabel="voltage (V)",
                   ylabel="operator output (V)", annotations=()):
    """Each operator's output against its input over a cycle (paper Figs. 4 and 5).

    ``outputs`` is the N x K operator matrix, one column per threshold;
    ``annotations`` are (x, y, text) labels."""
    fig = _figure(6.0, 4.6)
    ax = fig.subplots()
    for k, r in enumerate(thresholds):
        ax.plot(u, outputs[:, k], lw=1.3, label=f"r = {r:g}")
    right = u.min() + 0.7 * (u.max() - u.min())
    for x, y, text in annotations:
        ax.plot([x], [y], marker="o", ms=4, color="k")
        if text:
            ax.annotate(text, (x, y), textcoords="offset points", fontsize=8,
                        xytext=(-6, 8) if x > right else (6, -12),
                        ha="right" if x > right else "left")
    ax.plot([u.min(), u.max()], [u.min(), u.max()], color="0.7", lw=0.8, ls=":",
            label="y = u")
    ax.set(title=title, xlabel=xlabel, ylabel=ylabel)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=9, loc="upper left")
    return fig


def voltage_plot(t, voltages, *, labels=None, title="Driving voltages",
                 xlabel="time (s)", ylabel="voltage (V)"):
    """Voltages against time, with and without compensation (paper Fig. 11)."""
    fig = _figure(7.0, 4.0)
    ax = fig.subplots()
    for key, v in voltages.items():
        ax.plot(t, v, label=_label(key, labels), **_style(key))
    ax.set(title=title, xlabel=xlabel, ylabel=ylabel)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=9)
    return fig


def tracking_plot(t, desired, measured, errors, *, labels=None,
                  title="Tracking a desired displacement", xlabel="time (s)",
                  ylabel="displacement (µm)", error_label="tracking error (µm)"):
    """Desired and measured displacement (top) and the tracking errors (bottom)
    (paper Fig. 12)."""
    fig = _figure(7.6, 6.2)
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=[3, 2])
    top.plot(t, desired, label=_label("desired", labels), **_style("desired"))
    for key, y in measured.items():
        top.plot(t, y, label=_label(key, labels), **_style(key))
    for key, e in errors.items():
        bottom.plot(t, e, label=_label(key, labels), **_style(key))
    bottom.axhline(0, color="k", lw=0.6)
    top.set(title=title, ylabel=ylabel)
    bottom.set(xlabel=xlabel, ylabel=error_label)
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    top.legend(fontsize=9)
    bottom.legend(fontsize=8)
    return fig


def error_bars_plot(groups, values, *, labels=None, title, ylabel="mean |error| (µm)"):
    """Grouped bars: ``values[key]`` is one bar per group (e.g. per simulated beam)."""
    fig = _figure(7.6, 3.8)
    ax = fig.subplots()
    keys = list(values)
    width = 0.8 / max(1, len(keys))
    for i, key in enumerate(keys):
        x = [g + (i - (len(keys) - 1) / 2) * width for g in range(len(groups))]
        ax.bar(x, values[key], width=width, color=STYLE.get(key, {}).get("color"),
               label=_label(key, labels))
    ax.set_xticks(range(len(groups)), groups)
    ax.set(title=title, ylabel=ylabel)
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=9)
    return fig


def loops_grid_plot(loops, *, title="The simulated beams", xlabel="voltage (V)",
                    ylabel="displacement (µm)"):
    """Small multiples: ``loops[name] = (u, y)``."""
    n = len(loops)
    fig = _figure(2.6 * n, 2.9)
    axes = fig.subplots(1, n, squeeze=False)[0]
    for ax, (name, (u, y)) in zip(axes, loops.items()):
        ax.plot(u, y, **_style("measured"))
        ax.set(title=name, xlabel=xlabel)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel(ylabel)
    fig.suptitle(title)
    return fig


def learning_curve_plot(rms, accepted, probe, *, title="Learning curve"):
    """RMS error per trial on a log scale: kept trials filled, undone ones open, probe
    trials marked P."""
    fig = _figure(7.0, 3.8)
    ax = fig.subplots()
    trials = list(range(len(rms)))
    ax.semilogy(trials, rms, color="0.6", lw=1.0)
    kept = [j for j in trials if accepted[j]]
    undone = [j for j in trials if not accepted[j]]
    ax.semilogy(kept, [rms[j] for j in kept], "o", color="#2ca02c", label="kept")
    ax.semilogy(undone, [rms[j] for j in undone], "o", mfc="none", color="#d62728",
                label="undone")
    for j in trials:
        if probe[j]:
            ax.annotate("P", (j, rms[j]), textcoords="offset points", xytext=(4, 4),
                        fontsize=8)
    ax.set(title=title, xlabel="trial", ylabel="RMS tracking error (µm)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=9)
    return fig
