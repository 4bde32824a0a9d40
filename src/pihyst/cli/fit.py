"""pihyst fit DATA.csv [--model FAMILY] [--thresholds LIST] [--n-operators N]
[--validate OTHER.csv] [--delay N|auto] [--max-operators N] [--max-latency US] [--json]
-o MODEL.json"""

import sys
import warnings

from pihyst._version import __version__
from pihyst.cli.errors import UsageError
from pihyst.exceptions import FitError, PihystWarning
from pihyst.identify import FAMILY_NAMES, INITIAL_STATES, fit
from pihyst.io import CSVError, column_number, read_columns, save_model

_COLUMNS = {"input": "voltage_V", "output": "displacement_um"}


def register(sub):
    p = sub.add_parser(
        "fit", help="fit hysteresis models to a measured loop",
        description="Fit PI-type models to the voltage_V and displacement_um columns of "
                    "DATA.csv, judge them on held-back cycles (and on another record with "
                    "--validate), save the smallest, fastest of those within 2 %% of the "
                    "best as MODEL.json and print a report (errors per kind of held-back "
                    "data, compensator latency, why each threshold was chosen, what the "
                    "data could not determine).",
        epilog="example: pihyst fit loop.csv -o model.json   "
               "(then: pihyst predict model.json loop.csv -o predicted.csv)")
    p.add_argument("data", metavar="DATA.csv", help="CSV with voltage_V and displacement_um")
    p.add_argument("-o", "--output", metavar="MODEL.json", required=True,
                   help="model file to write (loads with pihyst.load_model)")
    p.add_argument("--model", metavar="FAMILY", choices=FAMILY_NAMES,
                   help=f"fit only this family ({', '.join(FAMILY_NAMES)}); default: all, "
                        f"the most accurate on held-back cycles is saved")
    p.add_argument("--thresholds", metavar="LIST",
                   help="comma-separated thresholds to use as they are (input units, from "
                        "the bottom of the input range), e.g. 0,10,30")
    p.add_argument("--n-operators", metavar="N", type=int,
                   help="number of operators to choose from the candidates (default: "
                        "chosen from the data)")
    p.add_argument("--candidates", metavar="N", type=int, default=16,
                   help="size of the candidate threshold grid (default 16, as the paper)")
    p.add_argument("--holdout", metavar="HOW", default="alternate",
                   help="held-back cycles: 'alternate' (default), a fraction such as 0.5 "
                        "(the last half of the record), or 'none'")
    p.add_argument("--initial-state", choices=INITIAL_STATES, default="auto",
                   help="operator state at the first sample: 'cycled' (at rest after a full "
                        "cycle), 'settle' (the first sweep settles it), 'zero'; 'auto' "
                        "(default): cycled if the record starts at its lowest input")
    p.add_argument("--through-top", action="store_true",
                   help="make the model pass exactly through the measured point at the "
                        "highest input")
    p.add_argument("--no-offset", action="store_true",
                   help="do not fit an output offset (default: fitted, the sensor's zero "
                        "is arbitrary)")
    p.add_argument("--validate", metavar="OTHER.csv",
                   help="a second record (same columns), judged but not fitted: every "
                        "family's error on it is reported and counts in the choice")
    p.add_argument("--delay", metavar="N", default="0",
                   help="samples by which the displacement lags the voltage (the model "
                        "maps u[k] to y[k+N]), or 'auto' to choose it on held-back cycles "
                        "(default 0; the report says which delay the record favours)")
    p.add_argument("--max-operators", metavar="N", type=int,
                   help="choose only among models with at most N operators")
    p.add_argument("--max-latency", metavar="US", type=float,
                   help="choose only among models whose compensator takes at most US "
                        "microseconds per sample in the worst case (measured)")
    p.add_argument("--json", action="store_true",
                   help="print the report as JSON instead of a table")
    p.set_defaults(run=run)


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
    return d


def _error(err, path, lines):
    """A FitError as a one-line file:line:column error."""
    col = column_number(path, _COLUMNS[err.column]) if err.column in _COLUMNS else 0
    if err.index is not None and 0 <= err.index < len(lines):
        return CSVError(path, int(lines[err.index]), col, str(err))
    if col:
        return CSVError(path, int(lines[0]), col, str(err))
    return UsageError(f"{path}: {err}")


def run(args):
    thresholds = _thresholds(args.thresholds)
    holdout = _holdout(args.holdout)
    if args.n_operators is not None and args.n_operators < 1:
        raise UsageError(f"--n-operators must be at least 1, got {args.n_operators}")
    if args.candidates < 2:
        raise UsageError(f"--candidates must be at least 2, got {args.candidates}")
    if args.max_operators is not None and args.max_operators < 1:
        raise UsageError(f"--max-operators must be at least 1, got {args.max_operators}")
    if args.max_latency is not None and not args.max_latency > 0:
        raise UsageError(f"--max-latency must be a positive number of microseconds, got "
                         f"{args.max_latency:g}")
    delay = _delay(args.delay)
    columns, lines = read_columns(args.data, list(_COLUMNS.values()))
    u, y = columns["voltage_V"], columns["displacement_um"]
    validate = validate_lines = None
    if args.validate is not None:
        other, validate_lines = read_columns(args.validate, list(_COLUMNS.values()))
        validate = (other["voltage_V"], other["displacement_um"])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PihystWarning)
        try:
            result = fit(u, y, family=args.model, thresholds=thresholds,
                         n_operators=args.n_operators, n_candidates=args.candidates,
                         holdout=holdout, initial_state=args.initial_state,
                         through="top" if args.through_top else None,
                         offset=not args.no_offset, validate=validate, delay=delay,
                         max_operators=args.max_operators,
                         max_latency=(None if args.max_latency is None
                                      else 1e-6 * args.max_latency))
        except FitError as err:
            if str(err).startswith("validate:"):
                raise _error(err, args.validate, validate_lines) from None
            raise _error(err, args.data, lines) from None
    model = result.model.replace(metadata={
        **result.model.metadata,
        "source": {"data": args.data, "command": f"pihyst {__version__} fit"}})
    save_model(model, args.output)
    for w in caught:
        print(f"pihyst: warning: {w.message}", flush=True, file=sys.stderr)
    print(result.report.to_json() if args.json else result.report)
    if not args.json:
        print(f"\nwrote {args.output}: {result.report.chosen} model, {model.n_operators} "
              f"operators (pihyst predict {args.output} INPUT.csv -o OUT.csv)")
