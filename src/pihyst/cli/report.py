"""pihyst report DATA.csv [--out DIR]: fit and compare models on a measured loop."""

import argparse
import os
import time

import numpy as np

from pihyst._atomic import AtomicFolder
from pihyst.cli.errors import UsageError
from pihyst.cli.record_options import add_record_options, options_text, read_from_args


def register(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    p = sub.add_parser(
        "report", help="fit-and-compare report from a measured loop (no simulator)",
        description="Fit the conventional PI and the multislope PI with the paper's "
                    "thresholds (scaled to the record's input span) and pihyst's automatic "
                    "best to the voltage_V and displacement_um columns of DATA.csv, and "
                    "write the comparison as a report: report.html (self-contained), the "
                    "figures as PNG, metrics.json, the data with the predictions as CSV and "
                    "the models as JSON.",
        epilog="example: pihyst simulate -o loop.csv && pihyst report loop.csv --out rep")
    p.add_argument("data", metavar="DATA",
                   help="record with the voltage and the displacement (time optional)")
    p.add_argument("--out", metavar="DIR", default=None,
                   help="output folder (default: DATA-report next to DATA)")
    add_figure_format_option(p)
    p.add_argument("--paper", action="store_true",
                   help="show the paper's numbers (its own beam's) beside this record's")
    p.add_argument("--learning", metavar="RUN.csv", default=None,
                   help="also show a learning run of pihyst learn or pihyst rig learn: the "
                        "error per trial and the tracking before and after")
    add_record_options(p, "DATA")
    p.set_defaults(run=run)


def add_figure_format_option(p):
    """--figure-format svg|pdf (shared with pihyst demo)."""
    p.add_argument("--figure-format", metavar="FORMAT", action="append", default=[],
                   choices=("svg", "pdf"),
                   help="also write the figures as svg or pdf (repeatable); PNG always")


def run(args: argparse.Namespace) -> None:
    try:
        from pihyst.study import write_report
    except ImportError as err:
        raise UsageError(f"pihyst report needs matplotlib to draw the report ({err}); "
                         "install it with: pip install 'pihyst[plot]'") from None
    from pihyst.exceptions import FitError
    from pihyst.study import loop_study

    learning = None
    if args.learning is not None:
        from pihyst.study._learning import read_learning_run
        learning = read_learning_run(args.learning)
    rec = read_from_args(args, args.data, need=("voltage", "displacement"))
    u, y = rec.voltage, rec.displacement
    if np.ptp(u) <= 0:
        raise rec.error(0, "voltage", "voltage_V is constant: there is no loop to fit")
    t = rec.time if rec.time is not None else np.arange(u.size, dtype=float)
    out = args.out or os.path.splitext(args.data)[0] + "-report"
    if os.path.exists(out) and not os.path.isdir(out):
        raise UsageError(f"--out {out}: exists and is not a folder")
    t0 = time.perf_counter()

    def say(line):
        print(f"pihyst report: {line}", flush=True)

    try:
        source = rec.reader.describe().replace("read ", "Measured record ", 1)
        study = loop_study(t, u, y, source=source, progress=say)
    except FitError as err:
        raise UsageError(f"{args.data}: {err}") from None
    if learning is not None:
        study.learning = learning
        study.metrics["learning"] = learning.summary()
    try:
        given = options_text(args)
        learning_option = f" --learning {args.learning}" if args.learning else ""
        # built in a hidden folder beside OUT, renamed at the end: complete or not at all
        with AtomicFolder(out) as build:
            files = write_report(study, build,
                                 command=f"pihyst report {args.data} --out {out}"
                                         + learning_option
                                         + (f" {given}" if given else ""),
                                 figure_formats=args.figure_format, paper=args.paper,
                                 progress=say)
    except OSError as err:
        raise UsageError(f"--out {out}: cannot write the report: {err.strerror}") from None
    fit = study.metrics["fit"]
    print(f"pihyst report: wrote {len(files)} files to {out} in "
          f"{time.perf_counter() - t0:.1f} s; open {os.path.join(out, 'report.html')}")
    print("  mean |error|: " + ", ".join(
        f"{study.models[k].label} {fit[k]['mean_abs']:.4g} µm"
        for k in ("classical", "multislope", "best")))
