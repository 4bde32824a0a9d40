"""pihyst simulate --plant NAME --signal KIND [options] -o DATA.csv"""

import argparse

from pihyst._version import __version__
from pihyst.cli.errors import (
    UsageError,
    check_output,
    count,
    number,
    open_fraction,
    positive_number,
)
from pihyst.cli.plant_options import add_plant_options, plant_from_options
from pihyst.io import write_columns
from pihyst.sim import signals

SIGNALS = ("triangle", "sine", "decaying-triangles", "random-ramps", "staircase")


def register(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    p = sub.add_parser(
        "simulate", help="record a loop from a simulated piezo beam",
        description="Drive a simulated beam (not a PI model: Preisach or Bouc-Wen hysteresis "
                    "with creep, sensor noise and 10 mV supply steps) with a voltage signal "
                    "and write time_s, voltage_V and the measured displacement_um. The beam "
                    "starts at rest at 0 V after a full 0 -> 150 -> 0 V cycle.",
        epilog="examples: pihyst simulate -o loop.csv  (the paper's 0-150 V, 300 s triangle "
               "on the paper-beam);  pihyst simulate --plant remanent --signal random-ramps "
               "--ramps 30 --seed 2 -o ramps.csv")
    p.add_argument("--signal", choices=SIGNALS, default="triangle",
                   help="drive signal (default: triangle)")
    p.add_argument("--min", type=number, default=0.0, metavar="V", dest="u_min",
                   help="lowest voltage (default 0)")
    p.add_argument("--max", type=number, default=None, metavar="V", dest="u_max",
                   help="highest voltage (default: the beam's 150 V)")
    p.add_argument("--period", type=positive_number, default=signals.PAPER_PERIOD_S, metavar="S",
                   help="period of triangle and sine, and of the first decaying triangle "
                        "(default 300 s)")
    p.add_argument("--cycles", type=count(1, signals.MAX_SAMPLES), default=1, metavar="N",
                   help="cycles of triangle or sine (default 1)")
    p.add_argument("--dt", type=positive_number, default=signals.DEFAULT_DT, metavar="S",
                   help="sample interval (default 0.1 s)")
    p.add_argument("--triangles", type=count(1, signals.MAX_SAMPLES), default=5, metavar="N",
                   help="decaying-triangles: number of triangles (default 5)")
    p.add_argument("--ratio", type=open_fraction, default=0.7, metavar="R",
                   help="decaying-triangles: peak ratio of successive triangles (default 0.7)")
    p.add_argument("--ramps", type=count(1, signals.MAX_SAMPLES), default=20, metavar="N",
                   help="random-ramps: number of ramps (default 20)")
    p.add_argument("--rate", type=positive_number, default=None, metavar="V/S",
                   help="random-ramps: ramp rate (default: the triangle's, 1 V/s for "
                        "0-150 V in 300 s)")
    p.add_argument("--steps", type=count(1, signals.MAX_SAMPLES), default=10, metavar="N",
                   help="staircase: steps up (and as many down) (default 10)")
    p.add_argument("--step-time", type=positive_number, default=10.0, metavar="S",
                   help="staircase: time per step, rounded to whole samples and at least "
                        "--dt (default 10 s)")
    p.add_argument("-o", "--output", metavar="DATA.csv", required=True, help="output CSV")
    add_plant_options(p, seed_help="seed of the sensor noise and of random-ramps' levels "
                                   "(default 0)")
    p.set_defaults(run=run)


# the options that shape each signal (named in its errors)
_OPTIONS_OF_SIGNAL = {
    "triangle": ("--period", "--cycles"), "sine": ("--period", "--cycles"),
    "decaying-triangles": ("--period", "--triangles", "--ratio"),
    "random-ramps": ("--ramps", "--rate"), "staircase": ("--steps", "--step-time")}


def make_signal(args, u_max):
    """(t, u) of the chosen signal; bad options (and too long a signal, checked before
    it is made) raise UsageError naming the options."""
    kind = args.signal
    common = {"u_min": args.u_min, "u_max": u_max, "dt": args.dt}
    values = {o: getattr(args, o[2:].replace("-", "_")) for o in _OPTIONS_OF_SIGNAL[kind]
              + ("--dt",)}
    options = ", ".join(f"{o} {v:g}" for o, v in values.items() if v is not None)
    try:
        if kind == "triangle":
            return signals.triangle(period_s=args.period, n_cycles=args.cycles, **common)
        if kind == "sine":
            return signals.sine(period_s=args.period, n_cycles=args.cycles, **common)
        if kind == "decaying-triangles":
            return signals.decaying_triangles(period_s=args.period, n_triangles=args.triangles,
                                              ratio=args.ratio, **common)
        if kind == "random-ramps":
            return signals.random_ramps(n_ramps=args.ramps, rate=args.rate, seed=args.seed,
                                        **common)
        return signals.staircase(n_steps=args.steps, step_s=args.step_time, **common)
    except ValueError as err:
        raise UsageError(f"--signal {kind} with {options}: {err}") from None


def run(args: argparse.Namespace) -> None:
    check_output(args.output)
    plant = plant_from_options(args)
    u_max = plant.u_max if args.u_max is None else args.u_max
    if not (plant.u_min <= args.u_min < u_max <= plant.u_max):
        raise UsageError(f"--min {args.u_min:g} and --max {u_max:g}: must lie in the beam's "
                         f"drive range [{plant.u_min:g}, {plant.u_max:g}] V with --min below "
                         f"--max")
    t, u = make_signal(args, u_max)
    y = plant.run(u, t)
    options = ", ".join(f"{k}={v}" for k, v in sorted(vars(args).items())
                        if k not in ("run", "output", "command"))
    write_columns(args.output, {"time_s": t, "voltage_V": u, "displacement_um": y},
                  comments=[f"pihyst {__version__} simulate ({options})", plant.describe()])
    print(f"wrote {u.size} samples ({t[-1]:g} s) to {args.output}: {args.signal} "
          f"{args.u_min:g}..{u_max:g} V on {plant.name}, displacement "
          f"{y.min():.4g} .. {y.max():.4g} µm")
