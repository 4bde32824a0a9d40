"""The ``pihyst`` command line. Only wires arguments to the public functions.

One module per command in this package, each with ``register(subparsers)`` that adds
its parser and sets ``run``. Every command reports bad input as one line
``pihyst: error: FILE:LINE:COLUMN: ...`` on stderr with exit status 2, and writes no
partial output file: it raises one of ``USER_ERRORS`` and ``main`` reports it through
:func:`pihyst.cli.errors.run_command` (docs/errors.md: statuses 0, 2, 70, 130, --debug).

The Python API of this package is :func:`main` and :func:`build_parser`; the command
modules are the command line's wiring, whose interface is the command line itself
(``pihyst COMMAND --help``, docs/).

Examples
--------
>>> from pihyst.cli import main
>>> main(["predict", "no-such-model.json", "no-such-record.csv"])
2
"""

import argparse
import os
import sys
from collections.abc import Sequence

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

__all__ = ["build_parser", "main"]

COMMANDS = [predict, fit, validate, fit_many, simulate, compensate, track, learn, demo, report,
            export, rig]


def build_parser() -> argparse.ArgumentParser:
    """The parser of the ``pihyst`` command line, every command registered.

    Returns
    -------
    argparse.ArgumentParser
        The parser; a parsed command's ``run`` attribute runs it (see :func:`main`).

    Examples
    --------
    >>> from pihyst.cli import build_parser
    >>> args = build_parser().parse_args(["predict", "model.json", "loop.csv", "-o", "y.csv"])
    >>> args.command, callable(args.run)
    ('predict', True)
    """
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


def main(argv: Sequence[object] | None = None) -> int:
    """Run ``pihyst ARGV`` and return the exit status.

    Parameters
    ----------
    argv : sequence or None
        The arguments after ``pihyst`` (each turned to str); None: ``sys.argv[1:]``.

    Returns
    -------
    int
        0, 2 (bad input, one line on stderr), 70 (a bug in pihyst), 130 (Ctrl-C) or
        143 (SIGTERM); ``--help`` and ``--version`` return 0 after printing.

    Examples
    --------
    >>> from pihyst.cli import main
    >>> main(["--version"])           # doctest: +ELLIPSIS
    pihyst ...
    0
    """
    words = sys.argv[1:] if argv is None else [str(a) for a in argv]
    debug = "--debug" in words or os.environ.get("PIHYST_DEBUG", "") not in ("", "0")
    words = [a for a in words if a != "--debug"]
    try:
        args = build_parser().parse_args(words)
    except SystemExit as done:  # --help, --version, or a usage error already reported
        return done.code if isinstance(done.code, int) else 2
    return run_command(args.run, args, debug=debug)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
