"""pihyst rig check|record|track|learn|emulate --config RIG.toml

Runs the experiment on the instruments of a rig configuration: the real supply and
sensor, or the emulated ones (ports ``pihystsim://...``: started in this process, in
virtual time unless --real-time).
"""

import argparse
import math
import sys
from typing import TYPE_CHECKING

import numpy as np

from pihyst.cli.errors import UsageError, count, number, positive_number
from pihyst.cli.frames import add_frame_options, check_reach, frame
from pihyst.cli.model_inputs import delay_for_run
from pihyst.io import load_model
from pihyst.model._units import output_unit
from pihyst.rig._per_tick import column_per_tick
from pihyst.sim.signals import MAX_SAMPLES as MAX_TICKS

if TYPE_CHECKING:
    from pihyst.rig import RunResult

SIGNALS = ("triangle", "sine", "decaying-triangles", "random-ramps", "staircase")


def _common(p, output=True):
    p.add_argument("--config", metavar="RIG.toml", required=True,
                   help="rig configuration (see examples/rig/)")
    p.add_argument("--plant", default=None, metavar="NAME",
                   help="emulated instruments only: the simulated beam (default: [emulator] "
                        "plant of the configuration)")
    p.add_argument("--real-time", action="store_true",
                   help="emulated instruments only: run in wall-clock time (default: virtual "
                        "time, as fast as the computation goes)")
    _fault_option(p)
    if output:
        p.add_argument("-o", "--output", metavar="LOG.csv", required=True,
                       help="run log, written as the run goes: CSV that 'pihyst fit' reads, "
                            "or HDF5 for a name ending in .h5 (needs pihyst[hdf5])")
        p.add_argument("--fsync", action="store_true",
                       help="force every log row to the disk (survives a power cut)")


def register(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    p = sub.add_parser(
        "rig", help="run the experiment on the instruments (or emulated ones)",
        description="Drive the high-voltage supply and read the laser displacement sensor "
                    "of a rig configuration at a fixed rate: check the instruments, record "
                    "a loop, track a trajectory (feedforward, optionally with feedback), or "
                    "start emulated instruments on pseudo-terminals. Every run starts at 0 V "
                    "and ends at 0 V with the output off, whatever stops it.",
        epilog="example (emulated instruments): pihyst rig record --config "
               "examples/rig/emulated.toml -o loop.csv && pihyst fit loop.csv --model "
               "multislope -o model.json && pihyst rig track model.json "
               "examples/rig/desired_triangle.csv --config examples/rig/emulated.toml "
               "--feedback 1,10 -o run.csv")
    rig_sub = p.add_subparsers(dest="rig_command", metavar="ACTION", required=True)

    c = rig_sub.add_parser("check", help="open both instruments, one reading, supply at 0 V",
                           description="Open the supply and the sensor, command 0 V, read "
                                       "the supply back (if configured) and take one sensor "
                                       "reading. The supply is left at 0 V, output off.")
    _common(c, output=False)
    c.set_defaults(run=run_check)

    r = rig_sub.add_parser(
        "record", help="drive a voltage signal and log the loop",
        description="Drive a voltage signal, one sample per tick (default: the paper's "
                    "0-150-0 V triangle, 300 s period), and log every tick.")
    r.add_argument("--signal", choices=SIGNALS, default="triangle",
                   help="drive signal (default: triangle)")
    r.add_argument("--voltages", metavar="FILE.csv",
                   help="drive the voltage_V column of a CSV instead (resampled at the tick "
                        "rate if it has time_s, else one value per tick)")
    r.add_argument("--min", type=number, default=None, metavar="V", dest="u_min",
                   help="lowest voltage (default: [rig] u_min)")
    r.add_argument("--max", type=number, default=None, metavar="V", dest="u_max",
                   help="highest voltage (default: [rig] u_max)")
    r.add_argument("--period", type=positive_number, default=300.0, metavar="S",
                   help="period of triangle and sine (default 300 s)")
    r.add_argument("--cycles", type=count(1, MAX_TICKS), default=1, metavar="N",
                   help="cycles (default 1)")
    _common(r)
    r.set_defaults(run=run_record)

    t = rig_sub.add_parser(
        "track", help="track a desired displacement (feedforward, optional feedback)",
        description="Compensate the desired displacement_um of DESIRED.csv (resampled at "
                    "the tick rate) with the exact inverse of MODEL.json and send the "
                    "voltages; with --feedback, add PID feedback on the measured error. "
                    "Prints the tracking errors.")
    t.add_argument("model", metavar="MODEL.json")
    t.add_argument("desired", metavar="DESIRED.csv", help="CSV with time_s, displacement_um")
    t.add_argument("--feedback", metavar="KP,KI[,KD]", default=None,
                   help="PID gains on the error in µm (KP in V/µm, KI in V/(µm s), KD in V s/µm), "
                        "e.g. 1,10")
    add_frame_options(t)
    _common(t)
    t.set_defaults(run=run_track)

    le = rig_sub.add_parser(
        "learn", help="learn the feedforward of a repeated trajectory (iterative learning)",
        description="Learn one period of voltages for the periodic desired displacement_um "
                    "of DESIRED.csv (resampled at the tick rate; one period) by iterative "
                    "learning from MODEL.json (pihyst.learn): each trial is one run of the "
                    "rig that plays the period --periods times and measures the last one; "
                    "the next trial's period is updated through the model's exact inverse. "
                    "Every trial starts at 0 V and ends at 0 V with the output off, whatever "
                    "stops it; voltages stay within [rig] u_min..u_max and slew_V_per_s. "
                    "Writes every trial's period to RUN.csv (trial, probe, accepted, rms_um, "
                    "time_s, voltage_V, desired_um, displacement_um) and each trial's tick "
                    "log beside it (RUN.trial-NN.csv); prints the error per trial.")
    le.add_argument("model", metavar="MODEL.json")
    le.add_argument("desired", metavar="DESIRED.csv",
                    help="one period: CSV with time_s, displacement_um")
    le.add_argument("--periods", type=_periods, default=2, metavar="P",
                    help="periods played per trial, the last one measured (default 2)")
    from pihyst.cli.learn import add_learning_options
    add_learning_options(le)
    _common(le)
    le.set_defaults(run=run_learn)

    e = rig_sub.add_parser(
        "emulate", help="emulated instruments on pseudo-terminals or TCP ports",
        description="Start the emulated supply and sensor of the configuration on "
                    "pseudo-terminals (or, with --tcp, on TCP ports of 127.0.0.1) and print "
                    "their device paths (or URLs); any program can then talk to them as to "
                    "the real instruments. Runs until Ctrl-C.")
    e.add_argument("--config", metavar="RIG.toml", required=True)
    e.add_argument("--tcp", type=_tcp_port, default=None, metavar="PORT",
                   help="serve on TCP instead: the supply on 127.0.0.1:PORT, the sensor on "
                        "PORT+1 (0: two free ports), for pyserial's socket://127.0.0.1:PORT "
                        "and PyVISA's TCPIP::127.0.0.1::PORT::SOCKET")
    e.add_argument("--plant", default=None, metavar="NAME", help="the simulated beam")
    _fault_option(e)
    e.add_argument("--duration", type=_duration, default=None, metavar="S",
                   help="stop after S seconds (default: run until Ctrl-C)")
    e.set_defaults(run=run_emulate)


# ----------------------------------------------------------------------------- helpers
def _duration(text):
    """--duration: a positive number of seconds a wait can take (threading's limit)."""
    import threading
    seconds = positive_number(text)
    if seconds > threading.TIMEOUT_MAX:
        raise argparse.ArgumentTypeError(f"must be at most {threading.TIMEOUT_MAX:g} s, got "
                                         f"{text!r}")
    return seconds


def _tcp_port(text):
    """--tcp: 0 (free ports) or a port whose successor is a port too."""
    return count(0, 65534)(text)


def _periods(text):
    from pihyst.cli.errors import count
    return count(2, 1000)(text)


def _fault_option(p):
    p.add_argument("--fault", action="append", default=[], metavar="DEVICE:KIND[:START[:N]]",
                   help="emulated instruments only: inject a fault, e.g. sensor:over-range:5 "
                        "(from 5 s on) or supply:no-reply:10:3 (3 replies from 10 s on); "
                        "kinds: no-reply, late-reply, truncated, garbled, bad-crc, "
                        "error-code, stuck, over-range, vanish. Repeatable.")


def _faults(args):
    from pihyst.rig import Fault
    faults = []
    for text in args.fault:
        parts = text.split(":")
        try:
            if not 2 <= len(parts) <= 4:
                raise ValueError("expected DEVICE:KIND[:START[:N]]")
            start = float(parts[2]) if len(parts) > 2 else 0.0
            count = int(parts[3]) if len(parts) > 3 else None
            faults.append(Fault(parts[1], parts[0], start_s=start, count=count))
        except ValueError as err:
            raise UsageError(f"--fault {text}: {err}") from None
    return faults


def _config(args):
    from pihyst.rig import ConfigError, load_config
    from pihyst.rig._plants import PLANT_NAMES
    try:
        config = load_config(args.config)
    except ConfigError as err:
        raise UsageError(str(err)) from None
    if getattr(args, "plant", None) is not None and args.plant not in PLANT_NAMES:
        raise UsageError(f"--plant {args.plant}: choose one of {', '.join(PLANT_NAMES)}")
    return config


def _open(args, config):
    from pihyst.rig import Rig, RigError, is_emulated
    faults = _faults(args)
    if faults and not is_emulated(config):
        raise UsageError("--fault: only for emulated instruments (pihystsim:// ports)")
    try:
        return Rig(config, real_time=args.real_time, plant=args.plant, faults=faults)
    except RigError as err:
        raise UsageError(f"{args.config}: {err}") from None


def _check_output(path):
    import os
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise UsageError(f"-o {path}: the folder {folder} does not exist")
    if path.lower().endswith((".h5", ".hdf5")):
        try:
            import h5py  # noqa: F401
        except ImportError:
            raise UsageError(f"-o {path}: HDF5 logs need h5py: pip install "
                             "'pihyst[hdf5]'") from None


def _run(rig, args, program, **options):
    """``rig.run`` into ``args.output``; rig limits the supply may not be sent are a
    UsageError naming the configuration (before the log is opened)."""
    from pihyst.exceptions import InvalidArgumentError
    from pihyst.rig._controller import check_limits
    try:
        check_limits(rig.supply, rig.config.rig)
    except InvalidArgumentError as err:
        raise UsageError(f"{args.config}: {err}") from None
    return rig.run(program, args.output, **options)


def _report(result, args, rig):
    t = result.timing()
    say = print
    say(f"{rig.describe()}: {t['ticks']} ticks at {1 / result.period_s:g} Hz; "
        f"busy {t.get('busy_mean_ms', 0):.1f} ms per tick (max {t.get('busy_max_ms', 0):.1f}); "
        f"start jitter mean {t.get('jitter_mean_ms', 0):.2f} ms, max "
        f"{t.get('jitter_max_ms', 0):.2f} ms; overruns {t['overruns']}")
    final = "0 V, output off" if result.zeroed else "WARNING: the supply could not be zeroed"
    say(f"stopped: {result.reason}; {final}; log in {args.output}")
    if not result.completed:
        print(f"pihyst rig: error: the run stopped early: {result.reason}", file=sys.stderr)
        raise SystemExit(1)
    if not result.zeroed:
        print(f"pihyst rig: error: the supply could not be zeroed at the end (see the log "
              f"{args.output}): the beam may still be charged", file=sys.stderr)
        raise SystemExit(1)


# ----------------------------------------------------------------------------- actions
def run_check(args: argparse.Namespace) -> None:
    config = _config(args)
    from pihyst.rig import RigError
    with _open(args, config) as rig:
        try:
            rig.supply.set_voltage(0.0)
            rig.supply.output_off()
            readback = rig.supply.read_voltage()
            reading = rig.sensor.read()
        except OSError as err:
            raise UsageError(f"{args.config}: {err}") from None
        finally:
            try:
                rig.supply.set_voltage(0.0)
                rig.supply.output_off()
            except (OSError, RigError):
                pass
    print(f"supply: {rig.supply.describe()}: 0 V sent, output off"
          + ("" if readback is None else f", readback {readback:.3f} V"))
    value = f"{reading.value:.4f} µm" if reading.valid else f"no value ({reading.status})"
    print(f"sensor: {rig.sensor.describe()}: {value}")


def run_record(args: argparse.Namespace) -> None:
    from pihyst.rig import VoltageProgram
    config = _config(args)
    r = config.rig
    u_min = r.u_min if args.u_min is None else args.u_min
    u_max = r.u_max if args.u_max is None else args.u_max
    if not r.u_min <= u_min < u_max <= r.u_max:
        raise UsageError(f"--min/--max {u_min:g}..{u_max:g} V must lie within the rig's "
                         f"limits [{r.u_min:g}, {r.u_max:g}] V with min < max")
    if args.voltages:
        u = column_per_tick(args.voltages, "voltage_V", r.rate_hz)
        bad = np.flatnonzero((u < r.u_min) | (u > r.u_max))
        if bad.size:
            raise UsageError(f"{args.voltages}: voltage {u[bad[0]]:g} V (tick {bad[0]}) is "
                             f"outside the rig's limits [{r.u_min:g}, {r.u_max:g}] V")
        description = f"voltages of {args.voltages}"
    else:
        from pihyst.cli.simulate import make_signal
        options = argparse.Namespace(signal=args.signal, u_min=u_min, dt=1.0 / r.rate_hz,
                                     period=args.period, cycles=args.cycles, triangles=5,
                                     ratio=0.7, ramps=20, rate=None, seed=0, steps=10,
                                     step_time=10.0)
        try:
            _, u = make_signal(options, u_max)
        except UsageError as err:
            # make_signal names pihyst simulate's options (--dt, --steps ...); say the
            # rig's: the tick period is the configuration's
            detail = str(err).split(": ", 1)[-1]
            shown = {"triangle": f" --period {args.period:g} --cycles {args.cycles}",
                     "sine": f" --period {args.period:g} --cycles {args.cycles}",
                     "decaying-triangles": f" --period {args.period:g}"}.get(args.signal, "")
            raise UsageError(f"--signal {args.signal}{shown} at {r.rate_hz:g} Hz ({args.config}"
                             f" [rig] rate_hz): {detail}") from None
        description = (f"{args.signal} {u_min:g}-{u_max:g} V, period {args.period:g} s, "
                       f"{args.cycles} cycle(s)")
    _check_output(args.output)
    program = VoltageProgram(u, description)
    with _open(args, config) as rig:
        result = _run(rig, args, program, fsync=args.fsync)
    y = result.column("displacement_um", phase="run")
    y = y[np.isfinite(y)]
    if y.size:
        print(f"recorded {y.size} ticks: displacement {y.min():.4g} .. {y.max():.4g} µm")
    _report(result, args, rig)


def _gains(text):
    try:
        gains = [float(g) for g in text.split(",")]
    except ValueError:
        gains = []
    if len(gains) not in (2, 3) or not all(math.isfinite(g) and g >= 0 for g in gains):
        raise UsageError(f"--feedback {text}: expected KP,KI or KP,KI,KD (numbers >= 0)")
    return gains + [0.0] * (3 - len(gains))


def run_track(args: argparse.Namespace) -> None:
    from pihyst import metrics
    from pihyst.rig import FeedbackProgram, FeedforwardProgram
    config = _config(args)
    r = config.rig
    model = load_model(args.model)
    # the delay in the rig's ticks: converted when exact, else a one-line error
    model = delay_for_run(model, args.config, period=1.0 / r.rate_hz)
    gains = _gains(args.feedback) if args.feedback is not None else None
    desired = column_per_tick(args.desired, "displacement_um", r.rate_hz)
    # in the model's frame (the sensor's, which the model was fitted on): --relative
    # targets are from the model's rest point at its lowest voltage
    offset, frame_line = frame(args, model)
    print(frame_line, flush=True)
    desired = desired + offset
    max_step = None if r.slew_V_per_s is None else r.slew_V_per_s / r.rate_hz
    try:
        if gains is None:
            program = FeedforwardProgram(model, desired, r.u_min, r.u_max, max_step,
                                         description=args.desired)
        else:
            kp, ki, kd = gains
            program = FeedbackProgram(model, desired, r.u_min, r.u_max, 1.0 / r.rate_hz,
                                      kp, ki, kd, max_step=max_step, description=args.desired)
    except ValueError as err:
        raise UsageError(f"{args.model}: {err}") from None
    _check_output(args.output)
    reach, n_out = _reach_note(model, desired, *program.limits)
    # refused before the supply is touched
    check_reach(args, n_out, desired.size, args.desired,
                "a trajectory from the actuator's rest point: --relative"
                if not args.relative else "narrow the trajectory")
    if reach is not None:
        print(reach, flush=True)
    with _open(args, config) as rig:
        result = _run(rig, args, program, notes=[f"model: {args.model}: {model!r}", frame_line]
                      + ([] if reach is None else [reach]), fsync=args.fsync)
    y = result.column("displacement_um", phase="run")
    ref = result.column("reference", phase="run")
    ok = np.isfinite(y)
    if ok.any():
        span = float(np.ptp(desired))
        s = metrics.error_summary(ref[ok], y[ok], span)
        pct = f" = {s['mean_abs_pct']:.2f} % of the range {span:.4g} µm" if span > 0 else ""
        mode = "with feedback" if gains else "open loop"
        print(f"tracking error {mode} (measured - desired, {int(ok.sum())} ticks): mean "
              f"absolute {s['mean_abs']:.4g} µm{pct}; RMS {s['rms']:.4g} µm; max "
              f"{s['max_abs']:.4g} µm")
    _report(result, args, rig)


def _reach_note(model, desired, lo, hi):
    """What the model cannot reach within the voltages [lo, hi] of the run (None: all in
    reach): the feedforward's voltages for those ticks saturate, and the tracking errors
    alone do not say why. Counted on the compensator's own run of the trajectory, as the
    reach at a tick depends on the voltages before it."""
    from pihyst.cli.compensate import reach_hint, reachable
    from pihyst.inverse import compensate
    run = compensate(model, desired, u_min=lo, u_max=hi)
    if not run.n_saturated:
        return None, 0
    y_lo, y_hi = reachable(model, model.initial_state, lo, hi)
    unit = output_unit(model)
    return ((f"note: {run.n_saturated} of {desired.size} ticks of the desired displacement "
            f"(span [{desired.min():.4g}, {desired.max():.4g}] {unit}) are out of the "
            f"model's reach with the voltage in [{lo:g}, {hi:g}] V (at most [{y_lo:.4g}, "
            f"{y_hi:.4g}] {unit}): their voltage saturates; "
            + reach_hint(model, y_lo, y_hi, float(desired.min()), float(desired.max()))),
            run.n_saturated)


def run_emulate(args: argparse.Namespace) -> None:
    import signal
    import threading

    config = _config(args)
    if args.tcp is None:
        from pihyst.rig._pty import PtyEmulators

        def start():
            return PtyEmulators(config, plant=args.plant, faults=_faults(args))
    else:
        from pihyst.rig._tcp import TcpEmulators

        def start():
            try:
                return TcpEmulators(config, port=args.tcp, plant=args.plant,
                                    faults=_faults(args))
            except OSError as err:
                why = (err.strerror or str(err)).split(" (while attempting")[0]
                raise UsageError(f"--tcp {args.tcp}: cannot listen on 127.0.0.1: {why}") \
                    from None
    stop = threading.Event()

    def _stop(signum, frame):
        stop.set()
    old = signal.signal(signal.SIGTERM, _stop)
    try:
        with start() as emu:
            for what, path in emu.paths.items():
                c = getattr(config, what)
                visa = f"{emu.visa[what]}; " if args.tcp is not None else ""
                print(f"{what}: {path}  ({visa}{c.protocol}, {c.baudrate} baud)", flush=True)
            print(f"simulated beam: {emu.emulators.plant.name}; Ctrl-C to stop", flush=True)
            try:
                stop.wait(args.duration)
            except KeyboardInterrupt:
                pass
            st = emu.emulators.supply_state
            print(f"stopped; supply: {emu.emulators.supply.requests} requests, last setpoint "
                  f"{st.last_setpoint_V:g} V, output {'on' if st.output_on else 'off'}; "
                  f"sensor: {emu.emulators.sensor.requests} requests", flush=True)
    finally:
        signal.signal(signal.SIGTERM, old)


class _TrialStopped(Exception):
    """A trial's rig run stopped early (the controller has zeroed the supply)."""


def _trial_log(output, trial):
    import os
    stem, ext = os.path.splitext(output)
    return f"{stem}.trial-{trial:02d}{ext or '.csv'}"


def run_learn(args: argparse.Namespace) -> None:
    """Each trial one rig run (module notes of pihyst.learn: ``run_period``)."""
    from pihyst.cli.learn import desired_period, print_learning, write_learning
    from pihyst.learn import learn_periodic
    from pihyst.rig import VoltageProgram
    config = _config(args)
    r = config.rig
    model = delay_for_run(load_model(args.model), args.config, period=1.0 / r.rate_hz)
    desired = desired_period(args.desired, r.rate_hz)
    if desired.size * args.periods > MAX_TICKS:
        raise UsageError(f"{args.desired}: {desired.size} ticks x --periods {args.periods} is "
                         f"more than the {MAX_TICKS:,} ticks of a run")
    if args.output.lower().endswith((".h5", ".hdf5")):
        raise UsageError(f"-o {args.output}: pihyst rig learn writes CSV")
    _check_output(args.output)
    trials: "list[RunResult]" = []
    with _open(args, config) as rig:
        def run_period(u):
            trial = len(trials)
            program = VoltageProgram(np.tile(u, args.periods),
                                     f"learning trial {trial}: {args.periods} periods of "
                                     f"{u.size} ticks for {args.desired}")
            result = rig.run(program, _trial_log(args.output, trial),
                             notes=[f"model: {args.model}: {model!r}"], fsync=args.fsync)
            trials.append(result)
            if not result.completed or not result.zeroed:
                raise _TrialStopped(result)
            y = result.column("displacement_um", phase="run")[-u.size:]
            if y.size != u.size or not np.all(np.isfinite(y)):
                raise _TrialStopped(result)
            return y

        from pihyst.exceptions import InvalidArgumentError
        from pihyst.rig._controller import check_limits
        try:
            check_limits(rig.supply, r)
        except InvalidArgumentError as err:
            raise UsageError(f"{args.config}: {err}") from None
        try:
            res = learn_periodic(run_period, desired, 1.0 / r.rate_hz, model=model,
                                 u_min=r.u_min, u_max=r.u_max, slew_rate=r.slew_V_per_s,
                                 trials=args.trials, bandwidth_hz=args.bandwidth,
                                 keep_trials=True)
        except _TrialStopped as stop:
            result = stop.args[0]
            log = _trial_log(args.output, len(trials) - 1)
            if not result.zeroed:
                print(f"pihyst rig: error: learning trial {len(trials) - 1}: the supply could "
                      f"not be zeroed (see the log {log}): the beam may still be charged",
                      file=sys.stderr)
            else:
                why = (result.reason if not result.completed
                       else "no valid reading on some tick of the measured period")
                print(f"pihyst rig: error: learning trial {len(trials) - 1} stopped: {why}; "
                      f"0 V, output off; log in {log}", file=sys.stderr)
            raise SystemExit(1) from None
    write_learning(args.output, res, desired, 1.0 / r.rate_hz,
                   comments=[f"pihyst rig learn: {rig.describe()}", f"model: {args.model}",
                             f"desired: {args.desired}"])
    print(f"{rig.describe()}: {len(trials)} trials at {r.rate_hz:g} Hz, {args.periods} "
          f"periods of {desired.size} ticks each; every trial ended at 0 V, output off")
    print_learning(res)
    print(f"wrote {args.output} (every trial's period) and the trials' tick logs "
          f"{_trial_log(args.output, 0)} ..")
