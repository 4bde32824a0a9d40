"""The options every command that reads a record shares (fit, predict, compensate,
validate, report, track): which columns, which units, the sensor lag, where to start,
and the progress bar for long reads. docs/records.md."""

import sys

from pihyst.cli.errors import UsageError
from pihyst.io import open_record

UNITS = ("m", "mm", "um", "nm")


def add_record_options(p, what="the record"):
    g = p.add_argument_group(
        f"reading {what}",
        "Delimited text (comma, semicolon, tab or whitespace; header or not; '#' comments; "
        "decimal comma), .npy, .npz, .mat, .h5, .parquet. Columns by name or 1-based "
        "number (in array files: a variable, NAME:K or K).")
    g.add_argument("--voltage", metavar="COL",
                   help="voltage column (default: voltage_V)")
    g.add_argument("--displacement", metavar="COL",
                   help="displacement column (default: displacement_um)")
    g.add_argument("--time", metavar="COL",
                   help="time column in seconds (default: time_s if present; 'none' to "
                        "ignore it)")
    g.add_argument("--rate", metavar="HZ", type=float,
                   help="sample rate, for a record without a time column")
    g.add_argument("--displacement-unit", choices=UNITS, metavar="UNIT",
                   help="unit of the displacement column: m, mm, um, nm (default: from "
                        "the column name, else um)")
    g.add_argument("--voltage-gain", metavar="G", type=float,
                   help="the actuator's voltage is G x the voltage column (a record of an "
                        "amplifier's input)")
    g.add_argument("--lag", metavar="N", type=int, default=0,
                   help="the displacement sensor answers N samples late: displacement[k+N] "
                        "goes with voltage[k] (default 0)")
    g.add_argument("--skip-until", metavar="SECONDS", type=float,
                   help="drop the samples before this time (e.g. a step at the start)")
    g.add_argument("--separator", metavar="SEP",
                   choices=(",", ";", "tab", "whitespace", "comma", "semicolon", "space"),
                   help="field separator of a text file: ',', ';', tab, whitespace "
                        "(default: found from the file)")
    g.add_argument("--decimal-comma", action="store_true", default=None,
                   help="numbers are written 1,5 (default: found from the file)")
    g.add_argument("--reader", metavar="MODULE:FUNCTION",
                   help="read the file with your Python function (MODULE:FUNCTION or "
                        "FILE.py:FUNCTION), called with the file's path and returning a "
                        "dict of arrays voltage, displacement, time and a metadata dict")


OPTIONS = (("voltage", "--voltage"), ("displacement", "--displacement"), ("time", "--time"),
           ("rate", "--rate"), ("displacement_unit", "--displacement-unit"),
           ("voltage_gain", "--voltage-gain"), ("lag", "--lag"),
           ("skip_until", "--skip-until"), ("separator", "--separator"),
           ("reader", "--reader"))


def options_text(args):
    """The reading options given, as they would be typed (for reports and metadata)."""
    words = [f"{flag} {value:g}" if isinstance(value, float) else f"{flag} {value}"
             for name, flag in OPTIONS
             if (value := getattr(args, name)) is not None and value != 0]
    if args.decimal_comma:
        words.append("--decimal-comma")
    return " ".join(words)


def open_from_args(args, path, need, optional=("time",)):
    """A :class:`pihyst.io.RecordReader` for ``path`` with the options of ``args``;
    ``optional`` quantities are read when the record has them."""
    try:
        return open_record(path, voltage=args.voltage, displacement=args.displacement,
                           time=args.time, rate=args.rate,
                           displacement_unit=args.displacement_unit,
                           voltage_gain=args.voltage_gain, lag=args.lag,
                           skip_until=args.skip_until, separator=args.separator,
                           decimal_comma=args.decimal_comma, reader=args.reader, need=need,
                           optional=optional)
    except ValueError as err:
        if isinstance(err, UsageError) or type(err) is not ValueError:
            raise
        raise UsageError(f"{path}: {err}") from None


def read_from_args(args, path, need, say=True, optional=("time",)):
    """All of a record (a :class:`pihyst.io.Record`) with the options of ``args``;
    prints what was read (unless ``say`` is False)."""
    with open_from_args(args, path, need, optional) as reader, \
            progress_bar(f"reading {path}") as bar:
        record = reader.read(progress=bar)
        if say:
            print(reader.describe(), flush=True)
    return record


class progress_bar:
    """A progress callback ``bar(done, total)``: a tqdm bar on stderr when stderr is a
    terminal (and tqdm is installed), else nothing; use as a context manager."""

    def __init__(self, label, unit="B"):
        self.label, self.unit = label, unit
        self._bar = None

    def __enter__(self):
        return self

    def __call__(self, done, total):
        if self._bar is None:
            if not (hasattr(sys.stderr, "isatty") and sys.stderr.isatty()):
                self._bar = False
            else:
                try:
                    from tqdm import tqdm
                except ImportError:
                    self._bar = False
                else:
                    self._bar = tqdm(total=total, desc=self.label, unit=self.unit,
                                     unit_scale=True, leave=False, file=sys.stderr)
        if self._bar:
            self._bar.update(done - self._bar.n)

    def __exit__(self, *exc):
        if self._bar:
            self._bar.close()
