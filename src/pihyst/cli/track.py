"""pihyst track MODEL.json DESIRED.csv --plant NAME -o OUT.csv

Feedforward tracking on a simulated beam: desired displacement -> compensator (the exact
inverse of MODEL.json) -> voltages -> simulated beam -> measured displacement.
"""

import argparse

import numpy as np

from pihyst._version import __version__
from pihyst.cli.compensate import (
    add_limit_options,
    check_limits,
    check_slew_rate,
    smallest_step,
)
from pihyst.cli.errors import UsageError, check_output
from pihyst.cli.frames import add_frame_options, check_reach, frame
from pihyst.cli.model_inputs import creep_times, delay_for_run
from pihyst.cli.plant_options import add_plant_options, plant_from_options
from pihyst.cli.record_options import (
    NO_VOLTAGE,
    add_record_options,
    read_from_args,
    refuse_unused,
)
from pihyst.inverse import PreviewRun, compensator_for
from pihyst.io import load_model, write_columns
from pihyst.sim.signals import MAX_SAMPLES


def register(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    p = sub.add_parser(
        "track", help="track a desired displacement on a simulated beam by feedforward",
        description="Compensate the desired displacement_um of DESIRED.csv with the exact "
                    "inverse of MODEL.json, drive a simulated beam with the voltages and "
                    "write time_s, desired_um, voltage_V, the measured displacement_um, "
                    "the model's predicted_um, error_um (measured - desired) and "
                    "saturated. Prints the tracking errors. The beam and the compensator "
                    "start at rest at 0 V (the beam after a full 0 -> max -> 0 V cycle).",
        epilog="example: pihyst simulate --signal decaying-triangles -o rec.csv && "
               "pihyst fit rec.csv -o model.json && pihyst track model.json desired.csv "
               "--plant paper-beam -o tracked.csv")
    p.add_argument("model", metavar="MODEL.json", help="model file (see pihyst.load_model)")
    p.add_argument("desired", metavar="DESIRED",
                   help="record with the desired displacement and its time (time_s, "
                        "or --rate HZ for a record without one)")
    p.add_argument("-o", "--output", metavar="OUT.csv", required=True, help="output CSV")
    add_limit_options(p, default_range="the model's and the beam's range")
    add_plant_options(p, seed_help="seed of the beam's sensor noise (default 0)")
    add_frame_options(p)
    add_record_options(p, "DESIRED", unused=NO_VOLTAGE)
    p.set_defaults(run=run)


def _limits(args, model, plant):
    """Voltage limits: the user's, else the overlap of the model's and the beam's range."""
    lo = max(model.input_range[0], plant.u_min) if args.u_min is None else args.u_min
    hi = min(model.input_range[1], plant.u_max) if args.u_max is None else args.u_max
    if not (plant.u_min <= lo < hi <= plant.u_max):
        raise UsageError(f"voltage limits --u-min {lo:g} and --u-max {hi:g} must lie in the "
                         f"beam's drive range [{plant.u_min:g}, {plant.u_max:g}] V with "
                         f"--u-min below --u-max")
    return lo, hi


def run(args: argparse.Namespace) -> None:
    refuse_unused(args, 'track', 'DESIRED', NO_VOLTAGE)
    check_output(args.output)
    model = load_model(args.model)
    check_limits(args.u_min, args.u_max, model, args.model)
    rec = read_from_args(args, args.desired, need=("time", "displacement"))
    offset, frame_line = frame(args, model)
    t, y_d = rec.time, rec.displacement
    if y_d.size > MAX_SAMPLES:  # the beam's state per sample would not fit in memory
        raise UsageError(f"{args.desired}: {y_d.size:,} samples, more than the "
                         f"{MAX_SAMPLES:,} a simulated beam runs at once: split the file")
    back = np.flatnonzero(np.diff(t) < 0)
    if back.size:
        i = int(back[0]) + 1
        raise rec.error(i, "time", f"time_s = {t[i]:g} goes back in time (previous "
                        f"{t[i - 1]:g})")
    plant = plant_from_options(args)
    u_min, u_max = _limits(args, model, plant)
    max_step = period = None
    if args.slew_rate is not None:
        check_slew_rate(args.slew_rate, args.desired)
        period = smallest_step([rec], args.desired)
        period = period if np.isfinite(period) else None
        max_step = None if period is None else args.slew_rate * period
    # a delayed model: its delay at the record's sample period, converted or refused
    model = delay_for_run(model, args.desired, t=t)
    try:
        compensator = compensator_for(model, u_min=u_min, u_max=u_max,
                                      slew_rate=None if period is None else args.slew_rate,
                                      sample_period=period)
    except ValueError as err:
        raise UsageError(f"{args.model}: {err}") from None
    # a delayed model: with preview, as pihyst.compensate
    # (a model with creep: at the record's sample times, as the beam runs)
    at = creep_times(model, rec, None)
    target = y_d + offset          # in the model's frame
    result = (PreviewRun(compensator, compensator.delay).feed(target, at.get("t"), last=True)
              if compensator.delay else compensator.run(target, **at))
    check_reach(args, result.n_saturated, y_d.size, args.desired,
                f"the desired displacement spans [{y_d.min():.4g}, {y_d.max():.4g}] µm"
                + ("" if args.relative else " in the model's frame; a trajectory from the "
                   "actuator's rest point: --relative"))
    # (the beam's and the model's output in the user's frame)
    measured = plant.run(result.voltage, t) - offset
    error = measured - y_d
    write_columns(args.output, {
        "time_s": t, "desired_um": y_d, "voltage_V": result.voltage,
        "displacement_um": measured, "predicted_um": result.displacement - offset,
        "error_um": error, "saturated": result.saturated.astype(float)},
        comments=[f"pihyst {__version__} track {args.model} {args.desired} --plant "
                  f"{args.plant} --seed {args.seed}", plant.describe(), frame_line])
    print(frame_line)
    span = float(y_d.max() - y_d.min())
    mae = float(np.mean(np.abs(error)))
    rms = float(np.sqrt(np.mean(error ** 2)))
    share = f" = {100 * mae / span:.2f} % of the desired range {span:.4g} µm" if span > 0 else ""
    print(f"wrote {y_d.size} samples to {args.output}: {args.plant} driven by the inverse of "
          f"{args.model} (voltage {result.voltage.min():.4g} .. {result.voltage.max():.4g} V)")
    print(f"tracking error (measured - desired): mean absolute {mae:.4g} µm{share}; "
          f"RMS {rms:.4g} µm; largest {float(np.max(np.abs(error))):.4g} µm")
    print(f"saturated: {result.n_saturated} of {y_d.size} samples"
          + ("" if max_step is None else f"; slew-limited: {result.n_slew_limited}"))
