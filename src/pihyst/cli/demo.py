"""pihyst demo [--out DIR]: the paper's study end to end on the simulated beam."""

import argparse
import os
import time

from pihyst._atomic import AtomicFolder
from pihyst.cli.errors import UsageError, seed
from pihyst.cli.report import add_figure_format_option
from pihyst.sim import PLANT_NAMES

DEFAULT_OUT = "pihyst-demo"


def register(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    p = sub.add_parser(
        "demo", help="the paper's study end to end on the simulated beam, as a report",
        description="Reproduce Xu et al. (2020) on pihyst's simulated piezo beam: record "
                    "the loop with the 0-150-0 V, 300 s triangle; fit the conventional PI "
                    "(thresholds 0, 10, 30, 150), the multislope PI (0, 20, 30, 40) and "
                    "pihyst's automatic best; invert them and track a triangular "
                    "displacement; repeat on the other simulated beams. Writes report.html "
                    "(self-contained), the figures as PNG, metrics.json, the data as CSV "
                    "and the models as JSON.",
        epilog="example: pihyst demo --out demo && open demo/report.html")
    p.add_argument("--out", metavar="DIR", default=DEFAULT_OUT,
                   help=f"output folder (created if needed; default {DEFAULT_OUT})")
    p.add_argument("--plant", choices=PLANT_NAMES, default="paper-beam",
                   help="simulated beam (default: paper-beam, calibrated to the paper)")
    p.add_argument("--seed", type=seed, default=0, metavar="N",
                   help="noise seed of the first record (default 0)")
    add_figure_format_option(p)
    p.add_argument("--no-variants", action="store_true",
                   help="skip the comparison on the other simulated beams")
    p.add_argument("--no-rig", action="store_true",
                   help="skip the experiment through the emulated instruments (pihyst rig)")
    p.set_defaults(run=run)


def _printer(prefix):
    def say(line):
        print(f"{prefix}: {line}", flush=True)
    return say


def run(args: argparse.Namespace) -> None:
    try:
        from pihyst.study import write_report
    except ImportError as err:                       # matplotlib is an optional dependency
        raise UsageError(f"pihyst demo needs matplotlib to draw the report ({err}); "
                         "install it with: pip install 'pihyst[plot]'") from None
    from pihyst.study import paper_study

    if os.path.exists(args.out) and not os.path.isdir(args.out):
        raise UsageError(f"--out {args.out}: exists and is not a folder")
    t0 = time.perf_counter()
    say = _printer("pihyst demo")
    study = paper_study(args.plant, seed=args.seed, variants=not args.no_variants,
                        rig=not args.no_rig, progress=say)
    command = f"pihyst demo --out {args.out} --plant {args.plant} --seed {args.seed}" + \
        (" --no-variants" if args.no_variants else "") + (" --no-rig" if args.no_rig else "")
    try:
        with AtomicFolder(args.out) as build:     # complete or not at all
            files = write_report(study, build, command=command, progress=say,
                                 figure_formats=args.figure_format)
    except OSError as err:
        raise UsageError(f"--out {args.out}: cannot write the report: {err.strerror}") from None
    h = study.metrics["headline"]
    paper = study.metrics["paper"]
    print(f"pihyst demo: wrote {len(files)} files to {args.out} in "
          f"{time.perf_counter() - t0:.1f} s; open {os.path.join(args.out, 'report.html')}")
    print(f"  fit mean |error|: conventional PI {h['fit_mean_abs_classical_um']:.4f} µm "
          f"(paper {paper['fit']['classical']['mean_abs']}), multislope PI "
          f"{h['fit_mean_abs_multislope_um']:.4f} µm (paper "
          f"{paper['fit']['multislope']['mean_abs']}): {h['fit_improvement_pct']:.1f} % less "
          f"(paper {paper['fit']['improvement_pct']} %)")
    print(f"  tracking with the multislope inverse: mean |error| "
          f"{h['tracking_mean_abs_multislope_um']:.4f} µm (paper "
          f"{paper['tracking']['mean_abs']}), RMS {h['tracking_rms_multislope_um']:.4f} µm "
          f"(paper {paper['tracking']['rms']:.4f}), {h['tracking_mean_abs_pct_of_range']:.2f} "
          f"% of the range")
    from pihyst.study._rig_study import RigStudy
    if isinstance(study.rig, RigStudy):       # the study's field is typed object
        rig = study.rig
        o, f = rig.tracking["open_loop"], rig.tracking["feedback"]
        print(f"  through the emulated instruments: mean |error| open loop {o['mean_abs']:.4f} "
              f"µm, with feedback {f['mean_abs']:.4f} µm; busy "
              f"{rig.timing['record']['busy_mean_ms']:.1f} ms per tick at "
              f"{rig.rate_hz:g} Hz")
