"""The ``pihyst`` command line. Only wires arguments to the public functions.

One module per command in this package, each with ``register(subparsers)`` that adds
its parser and sets ``run``. Every command reports bad input as one line
``pihyst: error: FILE:LINE:COLUMN: ...`` on stderr with exit status 2, and writes no
partial output file: it raises one of ``USER_ERRORS`` and ``main`` reports it through
:func:`pihyst.cli.errors.run_command` (docs/errors.md: statuses 0, 2, 70, 130, --debug).
"""

import os
import sys

from pihyst._version import __version__
from pihyst.cli import (
    compensate,
    demo,
    export,
    fit,
    fit_many,
    learn,
    predict,
    report,
    rig,
    simulate,
    track,
    validate,
)
from pihyst.cli.errors import ArgumentParser, run_command

COMMANDS = [predict, fit, validate, fit_many, simulate, compensate, track, learn, demo, report,
            export, rig]


def build_parser():
    parser = ArgumentParser(
        prog="pihyst",
        description="Prandtl-Ishlinskii hysteresis models for piezoelectric actuators: "
                    "predict displacement from voltage, fit models to measured loops, "
                    "compensate hysteresis by feedforward.",
        epilog="Records: delimited text (any separator, header or not) or .npy/.npz/.mat/"
               ".h5/.parquet; columns time_s, voltage_V, displacement_um by default, or "
               "named with --voltage/--displacement/--time COL (docs/records.md). "
               "Run 'pihyst COMMAND --help' for the options of a command.")
    parser.add_argument("--version", action="version", version=f"pihyst {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="on an internal error, show the traceback (accepted anywhere "
                             "on the command line; also PIHYST_DEBUG=1)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    for command in COMMANDS:
        command.register(sub)
    return parser


def main(argv=None):
    """Run ``pihyst ARGV`` and return the exit status (0, 2, 70 or 130; --help and
    --version return 0 after printing)."""
    argv = sys.argv[1:] if argv is None else [str(a) for a in argv]
    debug = "--debug" in argv or os.environ.get("PIHYST_DEBUG", "") not in ("", "0")
    argv = [a for a in argv if a != "--debug"]
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as done:  # --help, --version, or a usage error already reported
        return done.code if isinstance(done.code, int) else 2
    return run_command(args.run, args, debug=debug)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
