"""pihyst learn [--model MODEL.json] (--scan HZ | --desired DESIRED.csv) -o RUN.csv

Learning feedforward (pihyst.learn.learn_periodic) on a simulated stage: a beam's
hysteresis and creep, then lightly damped modes, a converter delay and an amplifier
slew limit at a fixed clock (pihyst.sim.make_stage). The stage first settles on the
starting drive (as if it had scanned for hours). Writes every trial's period; prints
the error per trial.
"""

import argparse
import math

import numpy as np

from pihyst.cli.errors import UsageError, check_output, count, number, positive_number, seed
from pihyst.io import load_model, read_columns, read_model_dict, write_columns
from pihyst.sim import PLANT_NAMES

#: Longest period learned (samples): a 1 Hz scan at 100 kHz.
MAX_PERIOD = 100_000


def add_learning_options(p):
    """--trials, --bandwidth: shared with pihyst rig learn."""
    p.add_argument("--trials", type=count(1, 1000), default=10, metavar="N",
                   help="learning trials after trial 0, the starting feedforward (default 10)")
    p.add_argument("--bandwidth", type=positive_number, default=None, metavar="HZ",
                   help="learn only harmonics up to HZ (default: all the trials can measure)")


def register(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    p = sub.add_parser(
        "learn", help="learn the feedforward of a repeated scan on a simulated stage",
        description="Iterative learning of one period of voltages (pihyst.learn): each "
                    "trial plays a period on a simulated stage (hysteresis and creep of "
                    "--plant, then --mode resonances, --delay ticks of converter delay and "
                    "an amplifier --slew limit, at --clock), measures one, and updates the "
                    "next through the model's exact inverse and the response per harmonic "
                    "the trials measure. Writes trial, probe, accepted, rms_um, time_s, "
                    "voltage_V, desired_um, displacement_um for every trial's period; "
                    "prints the RMS error per trial.",
        epilog="example: pihyst learn --model model.json --scan 100 --mode 800,0.04 "
               "-o run.csv")
    p.add_argument("--model", metavar="MODEL.json", default=None,
                   help="model to start from and to invert: a static model, or a SISO "
                        "Hammerstein model (pihyst.dynamics; its dynamics inverted too) "
                        "(default: none, the voltages themselves are learned)")
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--scan", type=positive_number, metavar="HZ",
                      help="a band-limited triangle at HZ lines per second (harmonics below "
                           "half the first mode) over 80 %% of the stage's range")
    what.add_argument("--desired", metavar="DESIRED.csv",
                      help="one period of displacement_um, one value per clock tick (or "
                           "with time_s, resampled at the clock)")
    p.add_argument("-o", "--output", metavar="RUN.csv", required=True, help="output CSV")
    p.add_argument("--plant", choices=PLANT_NAMES, default="paper-beam",
                   help="the beam whose hysteresis and creep the stage has (default "
                        "paper-beam)")
    p.add_argument("--mode", action="append", type=_mode, default=[], metavar="HZ[,DAMPING]",
                   help="a lightly damped mode (default 800,0.04); repeatable")
    p.add_argument("--clock", type=positive_number, default=20_000.0, metavar="HZ",
                   help="controller clock (default 20000)")
    p.add_argument("--delay", type=count(0, 100), default=1, metavar="TICKS",
                   help="converter delay (default 1)")
    p.add_argument("--slew", type=positive_number, default=None, metavar="V/S",
                   help="amplifier slew limit and the learning's (default: none)")
    p.add_argument("--noise", type=_noise, default=0.005, metavar="UM",
                   help="sensor noise, standard deviation (default 0.005)")
    p.add_argument("--seed", type=seed, default=0, metavar="N", help="noise seed (default 0)")
    p.add_argument("--u-min", type=float, default=0.0, metavar="V", help="default 0")
    p.add_argument("--u-max", type=float, default=150.0, metavar="V", help="default 150")
    add_learning_options(p)
    p.set_defaults(run=run)


def _mode(text):
    parts = text.split(",")
    try:
        values = [float(v) for v in parts]
    except ValueError:
        values = []
    if len(values) not in (1, 2) or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"expected HZ or HZ,DAMPING, got {text!r}")
    hz, damping = values[0], values[1] if len(values) == 2 else 0.04
    if not (hz > 0 and 0 < damping < 1):
        raise argparse.ArgumentTypeError(f"need HZ > 0 and 0 < DAMPING < 1, got {text!r}")
    return (hz, damping)


def _noise(text):
    value = number(text)
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must be a number >= 0 (µm), got {text!r}")
    return value


# ----------------------------------------------------------------------------- shared
def load_learning_model(path):
    """A static model file or a Hammerstein one (``"family": "hammerstein"``)."""
    d = read_model_dict(path)
    if isinstance(d, dict) and d.get("family") == "hammerstein":
        from pihyst.dynamics import load_hammerstein
        return load_hammerstein(path)
    return load_model(path)


def starting_voltages(model, desired, u_min, u_max):
    """Trial 0's drive for settling the stage: the model's inverse (a Hammerstein model's
    with its dynamics inverted per harmonic), or the middle of the range."""
    from pihyst.dynamics import HammersteinModel, compensate_hammerstein
    from pihyst.inverse import compensate
    if model is None:
        return np.full(desired.size, (u_min + u_max) / 2)
    if isinstance(model, HammersteinModel):
        return compensate_hammerstein(model, desired, u_min=u_min, u_max=u_max,
                                      periodic=True)[0]
    return compensate(model, desired, u_min=u_min, u_max=u_max).voltage


def desired_period(path, rate_hz):
    """One period of displacement_um from ``path``, at ``rate_hz`` (resampled when the
    file has time_s: the period is then its time span plus one step)."""
    columns, _ = read_columns(path, ["displacement_um"], optional=["time_s"])
    y = columns["displacement_um"]
    if "time_s" in columns:
        t = columns["time_s"]
        if np.any(np.diff(t) <= 0):
            raise UsageError(f"{path}: time_s must increase")
        step = float(np.median(np.diff(t))) if t.size > 1 else 1.0 / rate_hz
        n = int(round((t[-1] - t[0] + step) * rate_hz))
        if not 4 <= n <= MAX_PERIOD:
            raise UsageError(f"{path}: a period of {n} ticks at {rate_hz:g} Hz; need 4 .. "
                             f"{MAX_PERIOD:,}")
        ticks = t[0] + np.arange(n) / rate_hz
        y = np.interp(ticks, t, y, period=t[-1] - t[0] + step)
    if not 4 <= y.size <= MAX_PERIOD:
        raise UsageError(f"{path}: {y.size} samples in the period; need 4 .. {MAX_PERIOD:,}")
    return y


def write_learning(path, res, desired, sample_period, comments=()):
    """Every trial's period as rows: trial, probe (1: the probe trial), accepted, rms_um,
    time_s, voltage_V, desired_um, displacement_um."""
    n = desired.size
    k = res.trials
    columns = {
        "trial": np.repeat(np.arange(k), n),
        "probe": np.repeat(np.array([kind == "probe" for kind in res.kinds], dtype=int), n),
        "accepted": np.repeat(res.accepted.astype(int), n),
        "rms_um": np.repeat(res.rms, n),
        "time_s": np.tile(np.arange(n) * sample_period, k),
        "voltage_V": np.concatenate(res.voltages),
        "desired_um": np.tile(desired, k),
        "displacement_um": np.concatenate(res.displacements),
    }
    write_columns(path, columns, comments=comments)


def print_learning(res, noise_um=None):
    """The error per trial, the best trial and why the learning stopped."""
    noise = res.noise_um if noise_um is None else noise_um
    for j, (e, ok, kind) in enumerate(zip(res.rms, res.accepted, res.kinds)):
        mark = "" if ok else "  (undone)"
        print(f"trial {j:3d} {kind:<5} RMS error {e:.4g} µm = {e / noise:.2f} x noise"
              f"{mark}")
    print(f"best: trial {res.best_trial}, {res.rms[res.best_trial]:.4g} µm ("
          f"{res.rms[0] / res.rms[res.best_trial]:.1f} x below trial 0); noise estimated "
          f"{res.noise_um:.3g} µm; stopped: {res.reason}")


# ----------------------------------------------------------------------------- run
def _scan(args, stage_range, fmode):
    from pihyst.sim.signals import band_limited_triangle
    lo, hi = stage_range
    span = hi - lo
    if not args.scan < fmode / 2:
        raise UsageError(f"--scan {args.scan:g}: the scan rate must be below half the first "
                         f"mode ({fmode / 2:g} Hz) for a band-limited triangle")
    n = round(args.clock / args.scan)
    if not 4 <= n <= MAX_PERIOD:
        raise UsageError(f"--scan {args.scan:g} at --clock {args.clock:g}: {n} ticks per "
                         f"period; need 4 .. {MAX_PERIOD:,}")
    _, y = band_limited_triangle(lo + 0.1 * span, lo + 0.9 * span, period_s=n / args.clock,
                                 max_hz=fmode / 2, dt=1 / args.clock)
    return y


def run(args: argparse.Namespace) -> None:
    from pihyst.learn import learn_periodic
    from pihyst.sim import make_stage
    if not args.u_min < args.u_max or not (0 <= args.u_min and args.u_max <= 150):
        raise UsageError(f"--u-min {args.u_min:g} and --u-max {args.u_max:g} must lie in the "
                         f"stage's drive range [0, 150] V with --u-min below --u-max")
    modes = args.mode or [(800.0, 0.04)]
    if max(hz for hz, _ in modes) >= args.clock / 2:
        raise UsageError(f"--mode: every mode must be below half the --clock "
                         f"({args.clock / 2:g} Hz)")
    model = load_learning_model(args.model) if args.model else None
    check_output(args.output)

    def stage(noise=args.noise, creep=True):
        return make_stage(args.plant, modes=modes, rate_hz=args.clock,
                          delay_samples=args.delay, slew_V_per_s=args.slew, noise_um=noise,
                          creep=creep, seed=args.seed)
    if args.scan is not None:
        rise = stage(0.0, False).run(np.linspace(args.u_min, args.u_max, 3001))
        desired = _scan(args, (float(rise[0]), float(rise[-1])), min(hz for hz, _ in modes))
    else:
        desired = desired_period(args.desired, args.clock)
    plant = stage()
    plant.settle_on(starting_voltages(model, desired, args.u_min, args.u_max))
    res = learn_periodic(plant.run_periodic, desired, 1 / args.clock, model=model,
                         u_min=args.u_min, u_max=args.u_max, slew_rate=args.slew,
                         trials=args.trials, bandwidth_hz=args.bandwidth, seed=args.seed,
                         keep_trials=True)
    write_learning(args.output, res, desired, 1 / args.clock,
                   comments=[f"pihyst learn on a simulated stage: {plant.describe()}",
                             f"model: {args.model or 'none'}"])
    print(f"{plant.describe()}")
    print_learning(res, args.noise or None)
    print(f"wrote {args.output}: {res.trials} trials x {desired.size} samples")
