"""pihyst fit-many DIR -o MODELS_DIR [--scheduler ADDRESS|local] [--workers N] [fit options]
[record options] [--manifest FILE.json] [--pattern GLOB]

Fits every record of DIR as ``pihyst fit`` fits one (read with the same record options,
for each file, or per file from a manifest), writes one model file per fitted record and
a summary (``summary.json``, ``summary.csv``); exit status 2 if any record failed. Every
file of DIR that is not fitted is named with the reason. Without ``--scheduler`` the
records are fitted one after the other in this process; with it, in parallel on a Dask
cluster (docs/fleets.md).
"""

import argparse
import errno
import fnmatch
import json
import os
import stat
import sys

from pihyst._version import __version__
from pihyst.cli.errors import UsageError
from pihyst.cli.fit import (
    _delay,
    _holdout,
    _thresholds,
    add_size_options,
    plain_metadata,
    read_for_fit,
    sample_period,
)
from pihyst.cli.record_options import OPTIONS, add_record_options, options_text
from pihyst.exceptions import RecordError
from pihyst.fleet import fit_many, summary_csv, summary_json
from pihyst.identify import FAMILY_NAMES, INITIAL_STATES
from pihyst.io import save_model
from pihyst.io._records import EXTENSIONS, LAB_EXTENSIONS

SUMMARY_STEM = "summary"
# the files of a folder taken as records: delimited text and the formats pihyst reads
TEXT_SUFFIXES = (".csv", ".tsv", ".txt", ".dat", ".asc")
RECORD_SUFFIXES = TEXT_SUFFIXES + tuple(EXTENSIONS) + tuple(LAB_EXTENSIONS)


class RecordsFailed(UsageError):
    """Some records could not be fitted (the others were written): exit status 2."""


def register(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    p = sub.add_parser(
        "fit-many", help="fit a model to every record of a folder (a fleet), in parallel "
                         "on a Dask cluster if asked",
        description="Fit PI-type models to every record of DIR (files ending "
                    f"{', '.join(RECORD_SUFFIXES)}; --pattern to choose), each read with "
                    "the record options and fitted exactly as 'pihyst fit' would, and "
                    "write MODELS_DIR/RECORD.json for each plus MODELS_DIR/summary.json "
                    "and summary.csv (record, status, error, family, operators, "
                    "held-back RMS, time). A record that cannot be read or fitted is "
                    "reported in the summary and does not stop the others; the exit "
                    "status is then 2.",
        epilog="examples: pihyst fit-many records/ -o models/   (serial); "
               "pihyst fit-many records/ -o models/ --scheduler local   (all cores); "
               "pihyst fit-many records/ -o models/ --scheduler tcp://head:8786   "
               "(a running Dask cluster; needs pip install 'pihyst[dask]')")
    p.add_argument("folder", metavar="DIR", help="folder of records")
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
    p.add_argument("--no-creep", action="store_true",
                   help="do not fit creep (as pihyst fit --no-creep)")
    p.add_argument("--pattern", metavar="GLOB",
                   help="fit only the files of DIR whose names match GLOB, e.g. '*.dat' "
                        "(default: every file of a record format)")
    p.add_argument("--manifest", metavar="FILE.json",
                   help="record options per file: a JSON object {\"FILE\": {\"voltage\": 1, "
                        "\"displacement\": 5, \"rate\": 200, ...}}; a file's options there "
                        "replace those of the command line for that file")
    add_record_options(p, "each record")
    p.set_defaults(run=run)


def _why_not(path, name, pattern):
    """Why a file of the folder is not a record to fit, or None."""
    if pattern is not None and not fnmatch.fnmatch(name, pattern):
        return f"does not match --pattern {pattern}"
    try:
        st = os.stat(path)
    except OSError as err:
        if err.errno == errno.ELOOP:
            return "a symlink loop"
        if err.errno == errno.ENOENT:
            return f"a broken symlink (to {os.readlink(path)})" if os.path.islink(path) \
                else "gone"
        return f"cannot be read ({err.strerror})"
    if stat.S_ISDIR(st.st_mode):
        return "a folder (fit-many does not descend into folders)"
    if not stat.S_ISREG(st.st_mode):
        kind = ("a FIFO" if stat.S_ISFIFO(st.st_mode) else "a socket"
                if stat.S_ISSOCK(st.st_mode) else "a device")
        return f"{kind}, not a regular file"
    if pattern is None and not name.lower().endswith(RECORD_SUFFIXES):
        return "not a record format (give --pattern to fit it)"
    return None


def _records(folder, pattern=None):
    """(paths, model file names, skipped): the records of ``folder`` and every other
    file with why it is not fitted."""
    if not os.path.isdir(folder):
        raise UsageError(f"{folder}: not a folder (expected a folder of records)")
    names, skipped = [], {}
    for n in sorted(os.listdir(folder)):
        why = _why_not(os.path.join(folder, n), n, pattern)
        if why is None:
            names.append(n)
        elif not (n.startswith(".") and why.startswith("not a record")):
            skipped[n] = why
    if not names:
        raise UsageError(f"{folder}: no records in the folder"
                         + (f" (skipped: {'; '.join(f'{n}: {w}' for n, w in skipped.items())})"
                            if skipped else ""))
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
    return [os.path.join(folder, n) for n in names], model_files, skipped


class _ManifestParser(argparse.ArgumentParser):
    def error(self, message):
        raise UsageError(f"{self.prog}: {message}")


_RECORD_DESTS = {name for name, _ in OPTIONS} | {"decimal_comma", "units_row"}


def _manifest(path, args, names):
    """{file name: argparse namespace}: the record options of each file the manifest
    names (parsed by the record options' own definitions, over the command line's)."""
    if path is None:
        return {}
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except OSError as err:
        raise UsageError(f"--manifest {path}: cannot read it ({err.strerror})") from None
    except (ValueError, UnicodeDecodeError) as err:
        raise UsageError(f"--manifest {path}: not JSON ({err})") from None
    if not isinstance(data, dict) or not all(isinstance(v, dict) for v in data.values()):
        raise UsageError(f"--manifest {path}: expected an object FILE -> {{option: value}}")
    out = {}
    for name, entry in data.items():
        if name not in names:
            raise UsageError(f"--manifest {path}: {name!r} is not a record of the folder "
                             f"({', '.join(names)})")
        argv = []
        for key, value in entry.items():
            dest = str(key).lstrip("-").replace("-", "_")
            if dest not in _RECORD_DESTS:
                raise UsageError(f"--manifest {path}: {name}: {key!r} is not a record "
                                 f"option ({', '.join(sorted(_RECORD_DESTS))})")
            flag = "--" + dest.replace("_", "-")
            if isinstance(value, bool):
                if value:
                    argv.append(flag)
                elif dest == "units_row":        # "units_row": false, there is none
                    argv.append("--no-units-row")
            elif value is not None:
                argv.append(f"{flag}={value}")
        parser = _ManifestParser(prog=f"--manifest {path}: {name}", add_help=False)
        add_record_options(parser)
        parser.set_defaults(**{d: getattr(args, d) for d in _RECORD_DESTS})
        file_args = argparse.Namespace(**vars(args))
        for dest, value in vars(parser.parse_args(argv)).items():
            setattr(file_args, dest, value)
        out[name] = file_args
    return out


def _read_all(paths, args, per_file):
    """{name: Record or error}: each file read as ``pihyst fit`` reads it (a file that
    cannot be read is its error, which fit_many reports), the arguments used and the
    warnings about unusable time columns."""
    records, used, notes = {}, {}, {}
    for path in paths:
        name = os.path.basename(path)
        file_args = per_file.get(name, args)
        used[name] = file_args
        try:
            record, t, note = read_for_fit(file_args, path, say=True)
        except RecordError as err:
            records[name] = err
            continue
        except UsageError as err:
            records[name] = ValueError(str(err))
            continue
        if t is not None:
            record = _with_time(record, t)
        records[name] = record
        if note is not None:
            notes[name] = note
    return records, used, notes


def _with_time(record, t):
    import dataclasses
    return dataclasses.replace(record, time=t)


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
        rms = f", held-back RMS {rms:.4g} µm" if rms is not None else ""
        print(f"  {outcome.record}: {outcome.family}, {outcome.model.n_operators} operators"
              f"{rms} ({outcome.seconds:.2f} s)", flush=True)
    else:
        print(f"  {outcome.record}: FAILED: {outcome.error}", flush=True)


def run(args: argparse.Namespace) -> None:
    options = _options(args)
    paths, model_files, skipped = _records(args.folder, args.pattern)
    per_file = _manifest(args.manifest, args, [os.path.basename(p) for p in paths])
    for name, why in skipped.items():
        print(f"  skipped {name}: {why}", flush=True)
    if os.path.exists(args.output) and not os.path.isdir(args.output):
        raise UsageError(f"-o {args.output}: exists and is not a folder")
    dask = _Dask(args.scheduler, args.workers)
    try:
        where = "in this process" if dask.client is None else \
            f"on {'a local cluster' if args.scheduler == 'local' else args.scheduler}"
        print(f"fitting {len(paths)} records of {args.folder} {where}"
              + (f" ({len(skipped)} other files skipped)" if skipped else ""), flush=True)
        records, used, notes = _read_all(paths, args, per_file)
        os.makedirs(args.output, exist_ok=True)
        result = fit_many(records, client=dask.client, progress=_progress, **options)
    finally:
        dask.close()

    written = {}
    command = f"pihyst {__version__} fit-many"
    for outcome in result.fitted:
        model = outcome.model
        file_args = used[outcome.record]
        if model.delay:     # the delay holds at the record's sample period, as pihyst fit's
            model = model.replace(sample_period=sample_period(
                file_args, os.path.join(args.folder, outcome.record)))
        record = records[outcome.record]
        model = model.replace(metadata={
            **model.metadata,
            "source": {"data": os.path.join(args.folder, outcome.record),
                       "command": f"{command} " + options_text(file_args),
                       "record": plain_metadata(record.metadata)}})
        save_model(model, os.path.join(args.output, model_files[outcome.record]))
        written[outcome.record] = model_files[outcome.record]
        if outcome.record in notes:
            print(f"pihyst: warning: {notes[outcome.record]}", file=sys.stderr)
        for w in outcome.warnings:
            print(f"pihyst: warning: {outcome.record}: {w}", file=sys.stderr)
    json_path = os.path.join(args.output, f"{SUMMARY_STEM}.json")
    csv_path = os.path.join(args.output, f"{SUMMARY_STEM}.csv")
    summary_json(result, json_path, model_files=written, pihyst_version=__version__,
                 command=command, folder=args.folder, options=options,
                 record_options=options_text(args), skipped=skipped)
    # (plain CSV: what wrote it, and everything else, is in summary.json)
    summary_csv(result, csv_path, model_files=written)
    n, bad = len(result), len(result.failed)
    line = (f"fitted {n - bad} of {n} records in {result.seconds:.1f} s "
            + (f"({len(skipped)} other files skipped) " if skipped else "") +
            f"({result.scheduler}); models and {SUMMARY_STEM}.json/.csv in {args.output}")
    if bad:
        print(f"{line}; {bad} FAILED: {', '.join(o.record for o in result.failed)}")
        raise RecordsFailed(f"{bad} of {n} records could not be fitted (errors in "
                            f"{csv_path})")
    print(line)
