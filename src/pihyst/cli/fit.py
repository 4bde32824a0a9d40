"""pihyst fit DATA.csv [--model FAMILY] [--thresholds LIST] [--n-operators N]
[--validate OTHER.csv] [--delay N|auto] [--max-operators N] [--max-latency SECONDS] [--json]
-o MODEL.json"""

import argparse
import math
import sys
import warnings

import numpy as np

from pihyst._arguments import MAX_CANDIDATES
from pihyst._version import __version__
from pihyst.cli.errors import UsageError, check_output, count, positive_number, step_printer
from pihyst.cli.record_options import (
    add_record_options,
    open_from_args,
    options_text,
    progress_bar,
    read_from_args,
)
from pihyst.exceptions import FitError, InvalidModelError, PihystWarning, RecordError
from pihyst.identify import FAMILY_NAMES, INITIAL_STATES, fit
from pihyst.io import save_model
from pihyst.model._delay import MAX_DELAY_SAMPLES

_QUANTITIES = {"input": "voltage", "output": "displacement"}


def register(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    p = sub.add_parser(
        "fit", help="fit hysteresis models to a measured loop",
        description="Fit PI-type models to the voltage_V and displacement_um columns of "
                    "DATA.csv, judge them on held-back cycles (and on another record with "
                    "--validate), save the smallest, fastest of those within 2 % of the "
                    "best as MODEL.json and print a report (errors per kind of held-back "
                    "data, compensator latency, why each threshold was chosen, what the "
                    "data could not determine).",
        epilog="example: pihyst fit loop.csv -o model.json   "
               "(then: pihyst predict model.json loop.csv -o predicted.csv)")
    p.add_argument("data", metavar="DATA", help="record with the voltage and the displacement "
                   "(voltage_V and displacement_um, or name them: --voltage, --displacement)")
    p.add_argument("-o", "--output", metavar="MODEL.json", required=True,
                   help="model file to write (loads with pihyst.load_model)")
    p.add_argument("--model", metavar="FAMILY", choices=FAMILY_NAMES,
                   help=f"fit only this family ({', '.join(FAMILY_NAMES)}); default: all, "
                        f"the most accurate on held-back cycles is saved")
    add_size_options(p)
    p.add_argument("--holdout", metavar="HOW", default="alternate",
                   help="held-back cycles: 'alternate' (default), a fraction such as 0.5 "
                        "(the last half of the record), or 'none'")
    p.add_argument("--initial-state", choices=INITIAL_STATES, default="auto",
                   help="operator state at the first sample: 'cycled' (at rest after a full "
                        "cycle), 'settle' (the first sweep settles it), 'zero', 'rise' / "
                        "'fall' (at rest at the first input after a rise from the bottom / "
                        "a fall from the top); 'auto' (default): chosen from the record "
                        "(docs/theory/identification.md)")
    p.add_argument("--through-top", action="store_true",
                   help="make the model pass exactly through the measured point at the "
                        "highest input")
    p.add_argument("--no-offset", action="store_true",
                   help="do not fit an output offset (default: fitted, the sensor's zero "
                        "is arbitrary)")
    p.add_argument("--json", action="store_true",
                   help="print the report as JSON instead of a table")
    p.add_argument("--validate", metavar="OTHER.csv",
                   help="a second record (read with the same record options), judged but "
                        "not fitted: every family's error on it is reported and counts in "
                        "the choice")
    p.add_argument("--delay", metavar="N", default="auto",
                   help="samples by which the displacement lags the voltage (the model "
                        "maps u[k] to y[k+N] and carries the delay), or 'auto' (default): "
                        "chosen on held-back cycles, adopted only when clearly better "
                        "(else 0); the report says which delay was used and why")
    p.add_argument("--max-operators", metavar="N", type=count(1),
                   help="choose only among models with at most N operators")
    p.add_argument("--max-latency", metavar="SECONDS", type=positive_number,
                   help="choose only among models whose compensator takes at most SECONDS "
                        "per sample in the worst case (estimated from the model's "
                        "structure), e.g. 5e-7 for 0.5 µs (seconds, as pihyst.fit's "
                        "max_latency)")
    p.add_argument("--no-creep", action="store_true",
                   help="do not fit creep (default: with a time column, or --rate, creep is "
                        "fitted and kept when the held-back cycles say it helps)")
    p.add_argument("--input-range", metavar="LO,HI",
                   help="the model's input range: the drive's real limits, e.g. 0,150 "
                        "(default: the span of the record); must contain that span")
    add_record_options(p, "DATA")
    p.set_defaults(run=run)


def add_size_options(p):
    """--thresholds, --n-operators and --candidates, with their limits (shared by fit
    and fit-many: the same values are refused, with the same message, before anything
    is read)."""
    p.add_argument("--thresholds", metavar="LIST",
                   help="comma-separated thresholds to use as they are (input units, from "
                        "the bottom of the input range), e.g. 0,10,30")
    p.add_argument("--n-operators", metavar="N", type=count(1, MAX_CANDIDATES),
                   help="number of operators to choose from the candidates (default: "
                        "chosen from the data)")
    p.add_argument("--candidates", metavar="N", type=count(2, MAX_CANDIDATES), default=16,
                   help=f"size of the candidate threshold grid (default 16, as the paper; "
                        f"at most {MAX_CANDIDATES})")


def _thresholds(text):
    if text is None:
        return None
    values = []
    for item in text.split(","):
        try:
            values.append(float(item))
        except ValueError:
            raise UsageError(f"--thresholds: {item.strip()!r} is not a number "
                             f"(expected a comma-separated list such as 0,10,30)") from None
        if not (math.isfinite(values[-1]) and values[-1] >= 0):
            raise UsageError(f"--thresholds: {item.strip()} is not a finite number >= 0")
        if len(values) > 1 and not values[-1] > values[-2]:
            raise UsageError(f"--thresholds must increase strictly: {values[-2]:g} is "
                             f"followed by {values[-1]:g}")
    if len(values) > MAX_CANDIDATES:
        raise UsageError(f"--thresholds: {len(values)} thresholds, at most {MAX_CANDIDATES}")
    return values


def _holdout(text):
    if text in ("alternate",):
        return text
    if text in ("none", "0"):
        return None
    try:
        f = float(text)
    except ValueError:
        raise UsageError(f"--holdout: expected 'alternate', 'none' or a fraction, got "
                         f"{text!r}") from None
    if not 0 < f < 1:
        raise UsageError(f"--holdout: a fraction must be between 0 and 1, got {text}")
    return f


def _delay(text):
    if text == "auto":
        return text
    try:
        d = int(text)
    except ValueError:
        d = -1
    if d < 0:
        raise UsageError(f"--delay: expected a number of samples >= 0 or 'auto', got {text!r}")
    if d > MAX_DELAY_SAMPLES:
        raise UsageError(f"--delay: must be at most {MAX_DELAY_SAMPLES:,} samples (the "
                         f"longest input delay pihyst holds), got {text}")
    return d


def _input_range(text):
    if text is None:
        return None
    try:
        lo, hi = (float(v) for v in text.split(","))
    except ValueError:
        raise UsageError(f"--input-range: expected LO,HI such as 0,150, got {text!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise UsageError(f"--input-range: expected finite LO < HI, got {text!r}")
    return lo, hi


def _with_input_range(model, wanted, record):
    """The model with the user's input range, which must contain the record's span."""
    u = record.voltage
    lo, hi = wanted
    outside = np.flatnonzero((u < lo) | (u > hi))
    if outside.size:
        i = int(outside[0])
        raise record.error(i, "voltage", f"voltage_V = {u[i]:g} is outside --input-range "
                           f"{lo:g},{hi:g}: the range must contain the record's span "
                           f"[{u.min():g}, {u.max():g}]")
    try:
        return model.replace(input_range=(lo, hi))
    except InvalidModelError as err:
        raise UsageError(f"--input-range {lo:g},{hi:g}: the {model.family} model cannot be "
                         f"extended to it ({err})") from None


def _error(err, record):
    """A FitError as a one-line file:line:column error."""
    quantity = _QUANTITIES.get(err.column)
    if err.index is not None and 0 <= err.index < len(record):
        return record.error(err.index, quantity or "voltage", str(err))
    if quantity:
        return record.error(0, quantity, str(err))
    return UsageError(f"{record.source}: {err}")


def run(args: argparse.Namespace) -> None:
    check_output(args.output)
    thresholds = _thresholds(args.thresholds)
    holdout = _holdout(args.holdout)
    if args.n_operators is not None and args.n_operators > args.candidates:
        raise UsageError(f"--n-operators {args.n_operators} is more than the --candidates "
                         f"{args.candidates} to choose from")
    if args.max_operators is not None and args.max_operators < 1:
        raise UsageError(f"--max-operators must be at least 1, got {args.max_operators}")
    if args.max_latency is not None and not args.max_latency > 0:
        raise UsageError(f"--max-latency must be a positive number of seconds, got "
                         f"{args.max_latency:g}")
    delay = _delay(args.delay)
    input_range = _input_range(args.input_range)
    record, t, time_note = read_for_fit(args, args.data, say=not args.json)
    u, y = record.voltage, record.displacement
    other = validate = None
    if args.validate is not None:
        other = read_from_args(args, args.validate, need=("voltage", "displacement"),
                               say=not args.json, optional=())
        validate = (other.voltage, other.displacement)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PihystWarning)
        try:
            result = fit(u, y, family=args.model, thresholds=thresholds,
                         n_operators=args.n_operators, n_candidates=args.candidates,
                         holdout=holdout, initial_state=args.initial_state,
                         through="top" if args.through_top else None,
                         offset=not args.no_offset, validate=validate, delay=delay,
                         max_operators=args.max_operators,
                         max_latency=args.max_latency, t=t,
                         progress=step_printer("pihyst fit"))
        except FitError as err:
            if other is not None and str(err).startswith("validate:"):
                raise _error(err, other) from None
            raise _error(err, record) from None
    model = result.model
    if model.delay:
        model = model.replace(sample_period=sample_period(args))
    if input_range is not None:
        model = _with_input_range(model, input_range, record)
    model = model.replace(metadata={
        **model.metadata,
        "source": {"data": args.data, "command": f"pihyst {__version__} fit "
                                                 + options_text(args),
                   "record": plain_metadata(record.metadata)}})
    save_model(model, args.output)
    if time_note is not None:
        print(f"pihyst: warning: {time_note}", flush=True, file=sys.stderr)
    # with creep the record is fitted twice (with and without the creep estimate), and
    # both fits may say the same thing about it
    for message in dict.fromkeys(str(w.message) for w in caught):
        print(f"pihyst: warning: {message}", flush=True, file=sys.stderr)
    print(result.report.to_json() if args.json else result.report)
    if not args.json:
        lag = f", input delay {model.delay} samples" if model.delay else ""
        size = ("state (u, z)" if model.family == "bouc-wen" else
                f"{model.n_operators} operator{'s' if model.n_operators != 1 else ''}")
        print(f"\nwrote {args.output}: {result.report.chosen} model, {size}{lag} "
              f"(pihyst predict {args.output} INPUT.csv -o OUT.csv)")


def read_for_fit(args, path, say=True):
    """(record, times, note): what ``pihyst fit`` (and ``fit-many``, for each file)
    fits: the record read with the record options of ``args``, its times for creep
    (None without a usable time column, or with --no-creep) and the warning to print
    once the fit succeeds when the time column is unusable. With ``say``, prints the one
    line saying what was read, the time column included."""
    record, line = _read_described(args, path, optional=(), warn=say)
    # an unusable time column is said after the fit: a fit that fails says one line
    t, note, timed_line = (None, None, None) if getattr(args, "no_creep", False) else \
        _times_for_creep(args, path, say)
    if say:
        print(timed_line or line, flush=True)
    return record, t, note


def _read_described(args, path, optional, warn):
    """(record, the line describing what was read) of ``path`` with the options of
    ``args``."""
    with open_from_args(args, path, ("voltage", "displacement"), optional,
                        say_warnings=warn) as reader, \
            progress_bar(f"reading {path}") as bar:
        return reader.read(progress=bar), reader.describe()


def _times_for_creep(args, path=None, say=False):
    """(times, note, line): the record's sample times for creep="auto", or None: a
    record without a time column is fitted without creep, and so is one whose time
    column is unusable (the note, a warning to print once the fit succeeds, says where;
    the fit itself needs no time); ``line`` describes the read, time column included
    (None when the time could not be read)."""
    path = args.data if path is None else path
    try:
        # (the time is optional here: a record without one is fitted without creep)
        times, line = _read_described(args, path, optional=("time",), warn=say)
    except UsageError:
        return None, None, None
    except RecordError as err:
        return None, _unused_time(err), None
    t = times.time
    if t is None:
        return None, None, line
    bad = np.flatnonzero(~np.isfinite(t) | np.r_[False, np.diff(t) < 0])
    if bad.size:
        k = int(bad[0])
        what = "is not finite" if not np.isfinite(t[k]) else "runs backwards"
        return None, _unused_time(times.error(k, "time", f"time {what} at sample {k}")), line
    return t, None, line + "; time used for creep"


def _unused_time(err):
    return (f"{err}: the time column is not used, creep is not tried (fix it, or give "
            f"--no-creep)")


def sample_period(args, path=None):
    """The record's sample period (s), which a fitted delay holds at: the median step of
    its time, its time column's or the one --rate defines (read only now: a fit without
    a delay needs none); None when the record has no usable time."""
    if args.rate is not None:       # no time column (the reader refuses both): k / rate
        return 1.0 / args.rate
    try:
        times = read_from_args(args, args.data if path is None else path, need=("time",),
                               say=False, optional=())
    except (RecordError, UsageError):
        return None
    steps = np.diff(times.time) if times.time is not None else np.empty(0)
    steps = steps[np.isfinite(steps) & (steps > 0)]
    return float(np.median(steps)) if steps.size else None


def plain_metadata(meta):
    """The record's metadata as JSON-ready values."""
    return {k: (v if isinstance(v, (str, int, float, bool, type(None))) else
                {str(a): str(b) for a, b in v.items()} if isinstance(v, dict) else str(v))
            for k, v in meta.items()}
