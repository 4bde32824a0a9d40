"""pihyst compensate MODEL.json DESIRED.csv -o OUT.csv [--u-min V] [--u-max V] [--slew-rate V/S]"""

import numpy as np

from pihyst._version import __version__
from pihyst.cli.errors import UsageError, check_output, number, positive_number
from pihyst.inverse import Compensator
from pihyst.io import CSVError, column_number, load_model, read_columns, write_columns


def register(sub):
    p = sub.add_parser(
        "compensate", help="voltages that make a model follow a desired displacement",
        description="Invert MODEL.json exactly, sample by sample, on the displacement_um "
                    "column of DESIRED.csv (the desired trajectory) and write time_s, "
                    "voltage_V and the displacement_um the model predicts for those "
                    "voltages, with a 'saturated' column (1 where the desired value was out "
                    "of reach within the limits; with --slew-rate also 'slew_limited'). "
                    "The voltage starts at 0 V (or the nearer limit) with the model's "
                    "initial state.",
        epilog="example: pihyst compensate examples/paper_table1_multislope.json "
               "desired.csv -o voltages.csv --slew-rate 10")
    p.add_argument("model", metavar="MODEL.json", help="model file (see pihyst.load_model)")
    p.add_argument("desired", metavar="DESIRED.csv", help="CSV with a displacement_um column "
                   "(time_s copied if present)")
    p.add_argument("-o", "--output", metavar="OUT.csv", required=True, help="output CSV")
    add_limit_options(p, default_range="the model's input range")
    p.set_defaults(run=run)


def add_limit_options(p, default_range):
    """--u-min, --u-max and --slew-rate (shared with pihyst track)."""
    p.add_argument("--u-min", type=number, default=None, metavar="V",
                   help=f"lowest voltage (default: {default_range})")
    p.add_argument("--u-max", type=number, default=None, metavar="V",
                   help=f"highest voltage (default: {default_range})")
    p.add_argument("--slew-rate", type=positive_number, default=None, metavar="V/S",
                   help="largest voltage rate in volts per second; needs time_s (applied as "
                        "rate x the smallest time step, per sample)")


def check_limits(u_min, u_max, model, model_path):
    """--u-min and --u-max inside the model's input range and in order (UsageError)."""
    lo, hi = model.input_range
    for option, v in (("--u-min", u_min), ("--u-max", u_max)):
        if v is not None and not lo <= v <= hi:
            raise UsageError(f"{model_path}: {option} {v:g} is outside the model's input "
                             f"range [{lo:g}, {hi:g}]")
    low = lo if u_min is None else u_min
    high = hi if u_max is None else u_max
    if not low < high:
        raise UsageError(f"{model_path}: --u-min {low:g} must be below --u-max {high:g} "
                         f"(the model's input range is [{lo:g}, {hi:g}])")


def max_step_per_sample(slew_rate, t, path, lines):
    """Volts per sample from volts per second: rate x the smallest time step, so that no
    interval of the file sees a faster change."""
    if t is None:
        raise UsageError(f"--slew-rate needs a time_s column in {path}")
    if not (np.isfinite(slew_rate) and slew_rate > 0):
        raise UsageError(f"--slew-rate must be a positive number of volts per second, got "
                         f"{slew_rate:g}")
    if t.size < 2:
        return np.inf
    dt = np.diff(t)
    bad = np.flatnonzero(~(dt > 0))
    if bad.size:
        i = bad[0] + 1
        raise CSVError(path, int(lines[i]), column_number(path, "time_s"),
                       f"time_s = {t[i]:g} does not increase (previous {t[i - 1]:g}): "
                       "--slew-rate needs increasing times")
    return slew_rate * float(dt.min())


def run(args):
    check_output(args.output)
    model = load_model(args.model)
    check_limits(args.u_min, args.u_max, model, args.model)
    columns, lines = read_columns(args.desired, ["displacement_um"], optional=["time_s"])
    y_desired = columns["displacement_um"]
    t = columns.get("time_s")
    max_step = None
    if args.slew_rate is not None:
        max_step = max_step_per_sample(args.slew_rate, t, args.desired, lines)
    note = []
    if t is None:
        t = np.arange(y_desired.size, dtype=float)
        note = [f"{args.desired} has no time_s column: time_s is the sample index"]
    try:
        compensator = Compensator(model, u_min=args.u_min, u_max=args.u_max,
                                  slew_rate=max_step)
    except ValueError as err:
        raise UsageError(f"{args.model}: {err}") from None
    result = compensator.run(y_desired)
    lo, hi = result.limits
    out = {"time_s": t, "voltage_V": result.voltage, "displacement_um": result.displacement,
           "saturated": result.saturated.astype(float)}
    if max_step is not None:
        out["slew_limited"] = result.slew_limited.astype(float)
    write_columns(args.output, out,
                  comments=[f"pihyst {__version__} compensate {args.model} {args.desired}",
                            f"voltage limits [{lo:g}, {hi:g}] V"
                            + ("" if max_step is None else
                               f", slew limit {max_step:g} V per sample"), *note])
    reached = result.reached
    err = np.abs(result.displacement - y_desired)[reached]
    unit = model.units.get("output", "um")
    print(f"wrote {y_desired.size} samples to {args.output} "
          f"(voltage {result.voltage.min():.4g} .. {result.voltage.max():.4g} V)")
    print(f"saturated: {result.n_saturated} of {y_desired.size} samples "
          f"({int(result.saturated_low.sum())} at {lo:g} V, "
          f"{int(result.saturated_high.sum())} at {hi:g} V)"
          + ("" if max_step is None else f"; slew-limited: {result.n_slew_limited}"))
    if err.size:
        print(f"reached samples: largest |predicted - desired| {err.max():.3g} {unit}")
