"""A file's column one value per tick of the rig: resampled at the tick rate when the
file has ``time_s`` (which must increase), else as it is (``pihyst rig record --voltages``
and ``track``, and the PyMeasure Procedures: docs/rig.md)."""

import math

import numpy as np

from pihyst.exceptions import CSVError, ResourceLimitError
from pihyst.io import column_number, read_columns
from pihyst.sim.signals import MAX_SAMPLES as MAX_TICKS


def column_per_tick(path, column, rate_hz):
    """The values of ``column`` of the CSV ``path`` at the ticks of a ``rate_hz`` rig:
    linearly interpolated on its ``time_s`` column when it has one (a CSVError naming
    the line where time does not increase; a ResourceLimitError beyond the ticks of a
    run), else one per row as they are."""
    columns, lines = read_columns(path, [column], optional=["time_s"])
    v = columns[column]
    if "time_s" not in columns:
        return v
    t = columns["time_s"]
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        i = back[0] + 1
        raise CSVError(path, int(lines[i]), column_number(path, "time_s"),
                       f"time_s = {t[i]:g} does not increase (previous {t[i - 1]:g})")
    n = math.floor((t[-1] - t[0]) * rate_hz + 1e-9) + 1
    if n > MAX_TICKS:
        raise ResourceLimitError(f"{path}: time_s spans {t[-1] - t[0]:g} s, {n:,} ticks at "
                                 f"{rate_hz:g} Hz: more than the {MAX_TICKS:,} ticks of a run")
    return np.interp(t[0] + np.arange(n) / rate_hz, t, v)
