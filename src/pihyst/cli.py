"""The ``pihyst`` command line. Only wires arguments to the public functions.

Every command reports bad input as one line ``pihyst: error: FILE:LINE:COLUMN: ...`` on
stderr with exit status 2, and writes no partial output file.
"""

import argparse
import sys

import numpy as np

from pihyst import __version__
from pihyst.csvio import CSVError, read_columns, write_columns
from pihyst.io import load_model
from pihyst.model import InputRangeError, InvalidModelError

USER_ERRORS = (CSVError, InvalidModelError)


class UsageError(Exception):
    """Bad input detected by a command; the message is shown as is."""


def _in_range_or_error(model, u, lines, path, column):
    lo, hi = model.input_range
    bad = np.flatnonzero(~((u >= lo) & (u <= hi)))
    if bad.size:
        i = bad[0]
        raise CSVError(path, int(lines[i]), column,
                       f"voltage_V = {u[i]:g} is outside the model's input range "
                       f"[{lo:g}, {hi:g}]")


def _column_number(path, name):
    """1-based position of ``name`` in the header of ``path`` (for error messages)."""
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.strip() and not line.lstrip().startswith("#"):
                fields = [h.strip() for h in line.split(",")]
                return fields.index(name) + 1 if name in fields else 0
    return 0


def cmd_predict(args):
    model = load_model(args.model)
    (u,), lines = read_columns(args.input, ["voltage_V"])
    _in_range_or_error(model, u, lines, args.input, _column_number(args.input, "voltage_V"))
    try:
        (t,), _ = read_columns(args.input, ["time_s"])
        note = []
    except CSVError:
        t = np.arange(u.size, dtype=float)
        note = [f"{args.input} has no time_s column: time_s is the sample index"]
    y = model.predict(u)
    write_columns(args.output, {"time_s": t, "voltage_V": u, "displacement_um": y},
                  comments=[f"pihyst {__version__} predict {args.model} {args.input}", *note])
    print(f"wrote {u.size} samples to {args.output} "
          f"(displacement {y.min():.4g} .. {y.max():.4g} {model.units.get('output', 'um')})")


def build_parser():
    parser = argparse.ArgumentParser(
        prog="pihyst",
        description="Prandtl-Ishlinskii hysteresis models for piezoelectric actuators: "
                    "predict displacement from voltage, fit models to measured loops, "
                    "compensate hysteresis by feedforward.",
        epilog="CSV files: one header row, columns found by name (time_s, voltage_V, "
               "displacement_um), extra columns ignored, '#' lines are comments. "
               "Run 'pihyst COMMAND --help' for the options of a command.")
    parser.add_argument("--version", action="version", version=f"pihyst {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    p = sub.add_parser("predict", help="displacement a model predicts for a voltage signal",
                       description="Run MODEL.json on the voltage_V column of INPUT.csv and "
                                   "write time_s, voltage_V and the predicted displacement_um.",
                       epilog="example: pihyst predict model.json input.csv -o out.csv")
    p.add_argument("model", metavar="MODEL.json", help="model file (see pihyst.load_model)")
    p.add_argument("input", metavar="INPUT.csv", help="CSV with a voltage_V column")
    p.add_argument("-o", "--output", metavar="OUT.csv", required=True, help="output CSV")
    p.set_defaults(run=cmd_predict)
    return parser


def main(argv=None):
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        args.run(args)
    except (*USER_ERRORS, UsageError, InputRangeError) as err:
        print(f"pihyst: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
