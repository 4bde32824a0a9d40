"""The ``pihyst`` command line. Only wires arguments to the public functions.

One module per command in this package, each with ``register(subparsers)`` that adds
its parser and sets ``run``. Every command reports bad input as one line
``pihyst: error: FILE:LINE:COLUMN: ...`` on stderr with exit status 2, and writes no
partial output file: it raises one of ``USER_ERRORS`` and ``main`` reports it.
"""

import argparse
import sys

from pihyst._version import __version__
from pihyst.cli import (
    compensate,
    demo,
    export,
    fit,
    fit_many,
    predict,
    report,
    rig,
    simulate,
    track,
)
from pihyst.cli.errors import USER_ERRORS

COMMANDS = [predict, fit, fit_many, simulate, compensate, track, demo, report, export, rig]


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

    for command in COMMANDS:
        command.register(sub)
    return parser


def main(argv=None):
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        args.run(args)
    except USER_ERRORS as err:
        print(f"pihyst: error: {err}", file=sys.stderr)
        return 2
    except OSError as err:  # e.g. the output folder does not exist
        print(f"pihyst: error: {err.filename or ''}: {err.strerror}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
