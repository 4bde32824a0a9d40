"""pihyst fit-many DIR -o MODELS_DIR [--scheduler ADDRESS|local] [--workers N] [fit options]

Fits every record of DIR (``*.csv``) as ``pihyst fit`` fits one, writes one model file
per fitted record and a summary (``summary.json``, ``summary.csv``); exit status 2 if any
record failed. Without ``--scheduler`` the records are fitted one after the other in
this process; with it, in parallel on a Dask cluster (docs/fleets.md).
"""

import os
import sys

from pihyst._version import __version__
from pihyst.cli.errors import UsageError
from pihyst.cli.fit import _delay, _holdout, _thresholds, add_size_options
from pihyst.fleet import fit_many, summary_csv, summary_json
from pihyst.identify import FAMILY_NAMES, INITIAL_STATES
from pihyst.io import save_model

SUMMARY_STEM = "summary"


class RecordsFailed(UsageError):
    """Some records could not be fitted (the others were written): exit status 2."""


def register(sub):
    p = sub.add_parser(
        "fit-many", help="fit a model to every record of a folder (a fleet), in parallel "
                         "on a Dask cluster if asked",
        description="Fit PI-type models to every record (*.csv with voltage_V and "
                    "displacement_um) of DIR, each exactly as 'pihyst fit' would, and "
                    "write MODELS_DIR/RECORD.json for each plus MODELS_DIR/summary.json "
                    "and summary.csv (record, status, error, family, operators, "
                    "held-back RMS, time). A record that cannot be read or fitted is "
                    "reported in the summary and does not stop the others; the exit "
                    "status is then 2.",
        epilog="examples: pihyst fit-many records/ -o models/   (serial); "
               "pihyst fit-many records/ -o models/ --scheduler local   (all cores); "
               "pihyst fit-many records/ -o models/ --scheduler tcp://head:8786   "
               "(a running Dask cluster; needs pip install 'pihyst[dask]')")
    p.add_argument("folder", metavar="DIR", help="folder of records (*.csv)")
    p.add_argument("-o", "--output", metavar="MODELS_DIR", required=True,
                   help="folder for the model files and the summary (created if needed)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="'local' (a Dask cluster on this machine's cores) or the address "
                        "of a Dask scheduler (tcp://host:8786); default: fit in this "
                        "process, one record after the other")
    p.add_argument("--workers", metavar="N", type=int,
                   help="with --scheduler local: number of worker processes (default: "
                        "one per core)")
    p.add_argument("--model", metavar="FAMILY", choices=FAMILY_NAMES,
                   help=f"fit only this family ({', '.join(FAMILY_NAMES)}); default: all, "
                        f"the most accurate on held-back cycles is saved")
    add_size_options(p)                # as pihyst fit: the same limits, the same errors
    p.add_argument("--holdout", metavar="HOW", default="alternate",
                   help="held-back cycles: 'alternate' (default), a fraction, or 'none'")
    p.add_argument("--initial-state", choices=INITIAL_STATES, default="auto",
                   help="operator state at the first sample (default auto)")
    p.add_argument("--through-top", action="store_true",
                   help="pass exactly through the measured point at the highest input")
    p.add_argument("--no-offset", action="store_true",
                   help="do not fit an output offset")
    p.add_argument("--delay", metavar="N", default="auto",
                   help="samples by which the displacement lags the voltage, or 'auto' "
                        "(default: per record, adopted only when clearly better); each "
                        "model carries its delay")
    p.set_defaults(run=run)


def _records(folder):
    if not os.path.isdir(folder):
        raise UsageError(f"{folder}: not a folder (expected a folder of *.csv records)")
    names = sorted(n for n in os.listdir(folder) if n.lower().endswith(".csv")
                   and os.path.isfile(os.path.join(folder, n)))
    if not names:
        raise UsageError(f"{folder}: no records (*.csv files) in the folder")
    model_files, seen = {}, {}
    for name in names:
        stem = os.path.splitext(name)[0]
        model = f"{stem}.json"
        if stem.lower() == SUMMARY_STEM:
            raise UsageError(f"{os.path.join(folder, name)}: a record cannot be named "
                             f"'{SUMMARY_STEM}' (its model file would be the fleet's "
                             f"summary); rename it")
        if model.lower() in seen:
            raise UsageError(f"{os.path.join(folder, name)}: same model file {model} as "
                             f"{seen[model.lower()]}; rename one of them")
        seen[model.lower()] = name
        model_files[name] = model
    return [os.path.join(folder, n) for n in names], model_files


def _options(args):
    thresholds = _thresholds(args.thresholds)
    holdout = _holdout(args.holdout)
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be at least 1, got {args.workers}")
    if args.workers is not None and args.scheduler != "local":
        raise UsageError("--workers applies to --scheduler local only (a running "
                         "cluster has its own workers)")
    return dict(family=args.model, thresholds=thresholds, n_operators=args.n_operators,
                n_candidates=args.candidates, holdout=holdout,
                initial_state=args.initial_state,
                through="top" if args.through_top else None, offset=not args.no_offset,
                delay=_delay(args.delay))


class _Dask:
    """The Dask client of ``--scheduler`` (and the local cluster it started), closed on
    exit."""

    def __init__(self, scheduler, workers):
        self.cluster = self.client = None
        if scheduler is None:
            return
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise UsageError("--scheduler needs Dask: pip install 'pihyst[dask]'") from None
        try:
            if scheduler == "local":
                self.cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1,
                                            threads_per_worker=1, processes=True,
                                            dashboard_address=":0")
                self.client = Client(self.cluster)
            else:
                self.client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as err:
            self.close()
            raise UsageError(f"--scheduler {scheduler}: cannot connect: "
                             f"{str(err).splitlines()[0] if str(err) else type(err).__name__}"
                             ) from None

    def close(self):
        if self.client is not None:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def _progress(outcome):
    if outcome.ok:
        rms = outcome.held_back_rms
        rms = f", held-back RMS {rms:.4g} um" if rms is not None else ""
        print(f"  {outcome.record}: {outcome.family}, {outcome.model.n_operators} operators"
              f"{rms} ({outcome.seconds:.2f} s)", flush=True)
    else:
        print(f"  {outcome.record}: FAILED: {outcome.error}", flush=True)


def run(args):
    options = _options(args)
    paths, model_files = _records(args.folder)
    if os.path.exists(args.output) and not os.path.isdir(args.output):
        raise UsageError(f"-o {args.output}: exists and is not a folder")
    dask = _Dask(args.scheduler, args.workers)
    try:
        where = "in this process" if dask.client is None else \
            f"on {'a local cluster' if args.scheduler == 'local' else args.scheduler}"
        print(f"fitting {len(paths)} records of {args.folder} {where}", flush=True)
        os.makedirs(args.output, exist_ok=True)
        result = fit_many(paths, client=dask.client, progress=_progress, **options)
    finally:
        dask.close()

    written = {}
    command = f"pihyst {__version__} fit-many"
    for outcome in result.fitted:
        model = outcome.model.replace(metadata={
            **outcome.model.metadata,
            "source": {"data": outcome.source, "command": command}})
        save_model(model, os.path.join(args.output, model_files[outcome.record]))
        written[outcome.record] = model_files[outcome.record]
        for w in outcome.warnings:
            print(f"pihyst: warning: {outcome.record}: {w}", file=sys.stderr)
    json_path = os.path.join(args.output, f"{SUMMARY_STEM}.json")
    csv_path = os.path.join(args.output, f"{SUMMARY_STEM}.csv")
    summary_json(result, json_path, model_files=written, pihyst_version=__version__,
                 command=command, folder=args.folder, options=options)
    summary_csv(result, csv_path, model_files=written,
                comments=[f"{command} {args.folder}", f"scheduler: {result.scheduler}"])
    n, bad = len(result), len(result.failed)
    line = (f"fitted {n - bad} of {n} records in {result.seconds:.1f} s "
            f"({result.scheduler}); models and {SUMMARY_STEM}.json/.csv in {args.output}")
    if bad:
        print(f"{line}; {bad} FAILED: {', '.join(o.record for o in result.failed)}")
        raise RecordsFailed(f"{bad} of {n} records could not be fitted (errors in "
                            f"{csv_path})")
    print(line)
