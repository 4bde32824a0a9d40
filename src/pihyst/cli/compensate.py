"""pihyst compensate MODEL.json DESIRED -o OUT.csv [--u-min V] [--u-max V] [--slew-rate V/S]
[--strict] [--initial-state MODE] [record options]

Streams the record block by block; --slew-rate first reads the times once to find the
smallest step."""

import argparse

import numpy as np

from pihyst._version import __version__
from pihyst.cli.errors import UsageError, check_output, number, positive_number
from pihyst.cli.frames import add_frame_options, check_reach, frame
from pihyst.cli.model_inputs import (
    add_initial_state_option,
    creep_times,
    delay_for_run,
    initial_state,
)
from pihyst.cli.record_options import (
    NO_VOLTAGE,
    add_record_options,
    open_from_args,
    progress_bar,
    refuse_unused,
)
from pihyst.inverse import PreviewRun, compensator_for
from pihyst.io import ColumnWriter, load_model
from pihyst.model._units import output_unit


def register(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    p = sub.add_parser(
        "compensate", help="voltages that make a model follow a desired displacement",
        description="Invert MODEL.json exactly, sample by sample, on the desired "
                    "displacement of DESIRED (displacement_um, or --displacement COL) and "
                    "write time_s, voltage_V and the displacement_um the model predicts for "
                    "those voltages, with a 'saturated' column (1 where the desired value was "
                    "out of reach within the limits; with --slew-rate also 'slew_limited'). "
                    "Prints the displacement range the model can reach. The voltage starts "
                    "at 0 V (or the nearer limit) with the model's initial state; with "
                    "--initial-state bottom / top at that end of the input range.",
        epilog="example: pihyst compensate examples/paper_table1_multislope.json "
               "desired.csv -o voltages.csv --slew-rate 10")
    p.add_argument("model", metavar="MODEL.json", help="model file (see pihyst.load_model)")
    p.add_argument("desired", metavar="DESIRED", help="record with the desired displacement "
                   "(time copied if present)")
    p.add_argument("-o", "--output", metavar="OUT.csv", required=True, help="output CSV")
    add_limit_options(p, default_range="the model's input range")
    p.add_argument("--strict", action="store_true",
                   help="a desired displacement out of reach is an error (exit status 2, no "
                        "output file) instead of a saturated sample")
    add_initial_state_option(p, modes=("model", "bottom", "top", "zero"))
    add_frame_options(p)
    add_record_options(p, "DESIRED", unused=NO_VOLTAGE)
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


def check_slew_rate(slew_rate, path):
    if not (np.isfinite(slew_rate) and slew_rate > 0):
        raise UsageError(f"--slew-rate must be a positive number of volts per second, got "
                         f"{slew_rate:g}")


def smallest_step(records, path):
    """The smallest time step over blocks of a record; an error where time does not
    increase."""
    smallest, previous = np.inf, None
    for rec in records:
        t = rec.time
        if t is None:
            raise UsageError(f"--slew-rate needs a time_s column in {path} (or --time COL, "
                             "or --rate HZ)")
        full = t if previous is None else np.r_[previous, t]
        dt = np.diff(full)
        bad = np.flatnonzero(~(dt > 0))
        if bad.size:
            i = int(bad[0]) + (0 if previous is None else -1) + 1
            raise rec.error(i, "time", f"time_s = {t[i]:g} does not increase (previous "
                            f"{full[bad[0]]:g}): --slew-rate needs increasing times")
        if dt.size:
            smallest = min(smallest, float(dt.min()))
        previous = t[-1]
    return smallest


def reachable(model, state, lo, hi):
    """(lowest, highest) displacement the model reaches with voltages in [lo, hi]: at lo
    after coming down from hi, and at hi after going up from lo."""
    # without the delay: a delayed model's output would still be the held first input
    model = model.replace(delay=0)
    down = model.simulate(np.array([hi, lo]), initial_state=state).output[-1]
    up = model.simulate(np.array([lo, hi]), initial_state=state).output[-1]
    return float(down), float(up)


def reach_hint(model, y_lo, y_hi, d_lo=None, d_hi=None):
    """Why a desired displacement may be out of reach, and (given the trajectory's span)
    whether a shift would bring it in."""
    unit = output_unit(model)
    hint = (f"the displacement's zero is the sensor zero of the record the model was fitted "
            f"on (model offset {model.offset:.4g} {unit})")
    if d_lo is None:
        return hint
    if d_hi - d_lo <= y_hi - y_lo:
        shift = y_lo - d_lo if d_lo < y_lo else y_hi - d_hi
        hint += f"; shifted by {shift:+.4g} {unit} the trajectory would be in reach"
    else:
        hint += (f"; the trajectory spans {d_hi - d_lo:.4g} {unit}, more than the "
                 f"{y_hi - y_lo:.4g} {unit} the model reaches")
    return hint


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


def run(args: argparse.Namespace) -> None:
    refuse_unused(args, 'compensate', 'DESIRED', NO_VOLTAGE)
    check_output(args.output)
    model = load_model(args.model)
    check_limits(args.u_min, args.u_max, model, args.model)
    with open_from_args(args, args.desired, need=("displacement",)) as reader, \
            progress_bar(f"compensate {args.desired}") as bar:
        max_step = period = None
        if args.slew_rate is not None:
            check_slew_rate(args.slew_rate, args.desired)
            period = smallest_step(reader.chunks(), args.desired)
            period = period if np.isfinite(period) else None
            max_step = None if period is None else args.slew_rate * period
        if model.delay:
            # the delay at the record's sample period (its first block's, as predict):
            # converted or refused
            blocks = reader.chunks()
            first = next(blocks, None)
            blocks.close()
            model = delay_for_run(model, args.desired,
                                  t=None if first is None else first.time)
        state = initial_state(model, args.initial_state)
        try:
            compensator = compensator_for(model, u_min=args.u_min, u_max=args.u_max,
                                          slew_rate=None if period is None else args.slew_rate,
                                          sample_period=period, initial_state=state,
                                          initial_voltage=_rest_voltage(args, model))
        except ValueError as err:
            raise UsageError(f"{args.model}: {err}") from None
        lo, hi = compensator.limits
        offset, frame_line = frame(args, model)
        y_lo, y_hi = reachable(model, state, lo, hi)
        # in the user's frame: what is printed and written
        y_lo, y_hi = y_lo - offset, y_hi - offset
        unit = output_unit(model)
        stats = _Stats(compensator.delay)
        writer = None
        # a delayed model: voltages with preview (pihyst.compensate), written d samples
        # behind the targets read, the last d at the end
        preview = PreviewRun(compensator, compensator.delay) if compensator.delay else None
        times = np.empty(0)
        t_last = None             # with creep: the previous chunk's last sample time
        try:
            for rec in reader.chunks(progress=bar):
                y_d = rec.displacement + offset if offset else rec.displacement
                at = creep_times(model, rec, t_last)    # a model with creep: its times
                if at and len(rec):
                    t_last = rec.time[-1]
                t = rec.time if rec.time is not None else \
                    np.arange(rec.start, rec.start + len(rec), dtype=float)
                if preview is None:
                    result = ahead = compensator.run(y_d, **at)
                    skip = 0
                else:
                    result = preview.feed(y_d, at.get("t"))
                    ahead, skip = preview.ahead, preview.skip
                    times = np.concatenate([times, t])
                    t, times = times[:len(result.voltage)], times[len(result.voltage):]
                if args.strict and ahead.n_saturated:
                    i = skip + int(np.flatnonzero(ahead.saturated)[0])
                    raise rec.error(i, "displacement",
                                    f"displacement_um = {y_d[i] - offset:g} is out of reach: "
                                    f"the "
                                    f"model reaches [{y_lo:.4g}, {y_hi:.4g}] {unit} with the "
                                    f"voltage in [{lo:g}, {hi:g}] V; "
                                    + reach_hint(model, y_lo, y_hi))
                if writer is None:
                    writer = _open_writer(args, rec, max_step, lo, hi, y_lo, y_hi, unit,
                                          frame_line)
                _write(writer, t, result, max_step, offset)
                stats.add(result, result.desired, offset)
            if preview is not None and writer is not None:
                result = preview.feed([], last=True)
                _write(writer, times, result, max_step, offset)
                stats.add(result, result.desired, offset)
            check_reach(args, stats.saturated, stats.n, args.desired,
                        f"the model reaches [{y_lo:.4g}, {y_hi:.4g}] {unit}, the desired "
                        f"displacement spans [{stats.d_lo:.4g}, {stats.d_hi:.4g}] {unit}"
                        + ("" if getattr(args, "relative", False) else
                           "; a trajectory from the actuator's rest point: --relative"))
        except BaseException:
            if writer is not None:
                writer.abort()
            raise
        if writer is None:      # the readers refuse a record without samples first
            raise UsageError(f"{args.desired}: no samples")
        writer.close()
        print(reader.describe())
    print(frame_line)
    n = stats.n
    print(f"wrote {n} samples to {args.output} (voltage {stats.u_lo:.4g} .. {stats.u_hi:.4g} V)")
    print(f"reachable displacement: [{y_lo:.4g}, {y_hi:.4g}] {unit} with the voltage in "
          f"[{lo:g}, {hi:g}] V")
    # with a slew limit an out-of-reach sample may still be on its way to the limit
    at = "at" if max_step is None else "at or toward"
    print(f"saturated: {stats.saturated} of {n} samples ({stats.low} {at} {lo:g} V, "
          f"{stats.high} {at} {hi:g} V)"
          + ("" if max_step is None else f"; slew-limited: {stats.slew}"))
    if stats.saturated:
        print(f"the desired displacement spans [{stats.d_lo:.4g}, {stats.d_hi:.4g}] {unit}: "
              f"{stats.outside} samples lie outside the reachable range; "
              + reach_hint(model, y_lo, y_hi, stats.d_lo, stats.d_hi)
              + " (--strict makes this an error)")
    if stats.err_max is not None:
        print(f"reached samples: largest |predicted - desired| {stats.err_max:.3g} {unit}")


def _rest_voltage(args, model):
    """The voltage before the first sample for --initial-state bottom / top: the end of the
    input range the actuator rests at (within --u-min / --u-max); None (the compensator's
    default) for the other modes."""
    ends = {"bottom": 0, "top": 1}
    if args.initial_state not in ends:
        return None
    lo, hi = model.input_range
    lo = lo if args.u_min is None else args.u_min
    hi = hi if args.u_max is None else args.u_max
    return min(max(model.input_range[ends[args.initial_state]], lo), hi)


def _write(writer, t, result, max_step, offset=0.0):
    out = {"time_s": t, "voltage_V": result.voltage,
           "displacement_um": result.displacement - offset if offset else result.displacement,
           "saturated": result.saturated.astype(float)}
    if max_step is not None:
        out["slew_limited"] = result.slew_limited.astype(float)
    writer.write(out)


def _open_writer(args, rec, max_step, lo, hi, y_lo, y_hi, unit, frame_line):
    names = ["time_s", "voltage_V", "displacement_um", "saturated"]
    if max_step is not None:
        names.append("slew_limited")
    note = ([] if rec.time is not None else
            [f"{args.desired} has no time: time_s is the sample index"])
    return ColumnWriter(args.output, names, comments=[
        f"pihyst {__version__} compensate {args.model} {args.desired}",
        f"voltage limits [{lo:g}, {hi:g}] V"
        + ("" if max_step is None else f", slew limit {args.slew_rate:g} V/s "
           f"({max_step:g} V per sample of {max_step / args.slew_rate:g} s)"),
        f"reachable displacement [{y_lo:.6g}, {y_hi:.6g}] {unit}", frame_line, *note])


class _Stats:
    """What compensate prints, accumulated block by block."""

    def __init__(self, delay=0):
        self.n = self.saturated = self.low = self.high = self.slew = self.outside = 0
        self.u_lo = self.d_lo = np.inf
        self.u_hi = self.d_hi = -np.inf
        self.err_max = None
        self.delay = delay

    def add(self, result, y_d, offset=0.0):
        if not len(y_d):
            return
        y_d = y_d - offset if offset else y_d
        first = self.n             # samples before d of a delayed model: not reachable
        self.n += len(y_d)
        self.saturated += result.n_saturated
        self.low += int(result.saturated_low.sum())
        self.high += int(result.saturated_high.sum())
        self.slew += result.n_slew_limited
        self.outside += result.n_saturated
        self.u_lo = min(self.u_lo, float(result.voltage.min()))
        self.u_hi = max(self.u_hi, float(result.voltage.max()))
        self.d_lo = min(self.d_lo, float(y_d.min()))
        self.d_hi = max(self.d_hi, float(y_d.max()))
        reached = result.reached & (np.arange(first, self.n) >= self.delay)
        if reached.any():
            e = float(np.abs(result.displacement - offset - y_d)[reached].max())
            self.err_max = e if self.err_max is None else max(self.err_max, e)
