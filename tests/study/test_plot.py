"""Figures (pihyst.study._plot): they draw what they are given and nothing else."""

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from pihyst.study import _plot as plot

U = np.r_[np.linspace(0, 150, 151), np.linspace(149, 0, 150)]
T = np.arange(U.size, dtype=float)


def _lines(ax):
    return [line for line in ax.get_lines() if line.get_label() and
            not line.get_label().startswith("_")]


def test_loop_plot_draws_measured_and_each_model():
    fig = plot.loop_plot(U, 0.3 * U, {"classical": 0.3 * U + 1, "best": 0.3 * U - 1},
                         labels={"best": "my best"})
    assert isinstance(fig, Figure)
    (ax,) = fig.axes
    labels = [line.get_label() for line in _lines(ax)]
    assert labels == ["measured", "conventional PI", "my best"]
    np.testing.assert_array_equal(_lines(ax)[1].get_ydata(), 0.3 * U + 1)
    assert ax.get_xlabel() == "voltage (V)"


def test_fit_error_plot_has_time_and_voltage_panels():
    fig = plot.fit_error_plot(T, U, {"multislope": np.sin(T)}, marks=[(0, -3.09, "paper")])
    ax_t, ax_u = fig.axes
    np.testing.assert_array_equal(_lines(ax_t)[0].get_xdata(), T)
    np.testing.assert_array_equal(_lines(ax_u)[0].get_xdata(), U)
    assert any(t.get_text() == "paper" for t in ax_u.texts)


def test_operators_plot_one_line_per_threshold_and_annotations():
    phi = np.column_stack([U, np.maximum(U - 20, 0)])
    fig = plot.operators_plot(U, phi, [0, 20], title="ops",
                              annotations=[(95, 44, "kink"), (150, 110, "")])
    (ax,) = fig.axes
    assert [line.get_label() for line in _lines(ax)] == ["r = 0", "r = 20", "y = u"]
    assert [t.get_text() for t in ax.texts] == ["kink"]


def test_tracking_voltage_bars_and_grid_plots():
    fig = plot.tracking_plot(T, U / 3, {"multislope": U / 3 + 0.1},
                             {"multislope": np.full(T.size, 0.1)})
    assert len(fig.axes) == 2
    fig = plot.voltage_plot(T, {"none": U, "multislope": U * 0.9})
    assert len(_lines(fig.axes[0])) == 2
    fig = plot.error_bars_plot(["a", "b"], {"classical": [1, 2], "best": [0.1, 0.2]},
                               title="bars")
    assert len(fig.axes[0].patches) == 4
    fig = plot.loops_grid_plot({"x": (U, U), "y": (U, 2 * U)})
    assert len(fig.axes) == 2


def test_png_bytes_and_no_pyplot_state():
    before = plt.get_fignums()
    png = plot.figure_png(plot.loop_plot(U, U, {}))
    assert png.startswith(b"\x89PNG\r\n\x1a\n") and len(png) > 2000
    assert plt.get_fignums() == before
