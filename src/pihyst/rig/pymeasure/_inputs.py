"""What the Procedures read from files, per tick of the rig: the model (its delay in
ticks) and a desired displacement resampled at the tick rate; and the record signals.
The same rules as ``pihyst rig track`` and ``record`` (docs/rig.md, Commands), from the
layers below the rig (the command line's own helpers sit above it)."""

from typing import Any

import numpy as np

from pihyst.exceptions import InvalidArgumentError
from pihyst.io import load_model
from pihyst.rig._per_tick import column_per_tick
from pihyst.sim import signals

SIGNALS = ("triangle", "sine", "decaying-triangles", "random-ramps", "staircase")


def model_at_tick(path: str, rate_hz: float) -> Any:
    """The model of ``path`` with its input delay in ticks of ``rate_hz`` (converted when
    exact; InvalidArgumentError naming the file otherwise)."""
    model = load_model(path)
    if not model.delay or model.sample_period is None:
        return model
    period = 1.0 / rate_hz
    try:
        delay = model.delay_at(period)
    except InvalidArgumentError as err:
        raise InvalidArgumentError(f"{path}: {err}") from None
    return model.replace(delay=delay, sample_period=period)


def desired_per_tick(path: str, rate_hz: float) -> np.ndarray:
    """The ``displacement_um`` column of ``path``, one value per tick: resampled at the
    tick rate when the file has ``time_s`` (which must increase), else as it is."""
    return column_per_tick(path, "displacement_um", rate_hz)


def signal_voltages(kind: str, u_min: float, u_max: float, period_s: float, cycles: int,
                    dt: float) -> np.ndarray:
    """One voltage per tick of the record signal ``kind`` (one of :data:`SIGNALS`), with
    ``pihyst rig record``'s defaults for the options it does not take."""
    if kind == "triangle":
        return signals.triangle(period_s=period_s, n_cycles=cycles, u_min=u_min, u_max=u_max,
                                dt=dt)[1]
    if kind == "sine":
        return signals.sine(period_s=period_s, n_cycles=cycles, u_min=u_min, u_max=u_max,
                            dt=dt)[1]
    if kind == "decaying-triangles":
        return signals.decaying_triangles(period_s=period_s, n_triangles=5, ratio=0.7,
                                          u_min=u_min, u_max=u_max, dt=dt)[1]
    if kind == "random-ramps":
        return signals.random_ramps(n_ramps=20, rate=None, seed=0, u_min=u_min, u_max=u_max,
                                    dt=dt)[1]
    if kind == "staircase":
        return signals.staircase(n_steps=10, step_s=10.0, u_min=u_min, u_max=u_max, dt=dt)[1]
    raise InvalidArgumentError(f"signal {kind!r} is not one of {', '.join(SIGNALS)}")
