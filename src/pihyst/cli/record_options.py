"""The options every command that reads a record shares (fit, predict, compensate,
validate, report, track): which columns, which units, the sensor lag, where to start,
and the progress bar for long reads. docs/records.md."""

import sys
import warnings

from pihyst.cli.errors import UsageError, count
from pihyst.exceptions import InvalidArgumentError, PihystWarning
from pihyst.io import open_record

UNITS = ("m", "mm", "um", "nm")


def add_record_options(p, what="the record", unused=None):
    """The record options; those in ``unused`` (NO_VOLTAGE, NO_DISPLACEMENT) say in their
    help that the command refuses them (run() calls :func:`refuse_unused`)."""
    g = p.add_argument_group(
        f"reading {what}",
        "Delimited text (comma, semicolon, tab or whitespace; header or not; a units row; "
        "'#' comments; decimal comma; PI GCSArray data-recorder files), LabVIEW .lvm, "
        ".tdms, .xlsx, .npy, .npz, .mat, .h5, .parquet. Columns by name or 1-based "
        "number (in array files: a variable, NAME:K or K).")
    unused = unused or {}

    def add(option, **kwargs):
        if option in unused:
            kwargs["help"] = (f"not used by {p.prog}, an error if given: "
                              + unused[option].format(what=what))
        g.add_argument(option, **kwargs)
    add("--voltage", metavar="COL",
                   help="voltage column (default: voltage_V)")
    add("--displacement", metavar="COL",
                   help="displacement column (default: displacement_um)")
    add("--time", metavar="COL",
                   help="time column in seconds (default: time_s if present; 'none' to "
                        "ignore it)")
    add("--rate", metavar="HZ", type=float,
                   help="sample rate, for a record without a time column")
    add("--displacement-unit", choices=UNITS, metavar="UNIT",
                   help="unit of the displacement column: m, mm, um, nm (default: from "
                        "the column name, else µm)")
    add("--voltage-gain", metavar="G", type=float,
                   help="the actuator's voltage is G x the voltage column (a record of an "
                        "amplifier's input)")
    add("--displacement-gain", metavar="G", type=float,
                   help="the displacement is G x the displacement column (-1: a sensor "
                        "that counts the other way, such as a distance to the target)")
    add("--lag", metavar="N", type=count(0), default=0,
                   help="the displacement sensor answers N samples late: displacement[k+N] "
                        "goes with voltage[k] (default 0)")
    add("--skip-until", metavar="SECONDS", type=float,
                   help="drop the samples before this time (e.g. a step at the start)")
    add("--separator", metavar="SEP",
                   choices=(",", ";", "tab", "whitespace", "comma", "semicolon", "space"),
                   help="field separator of a text file: ',', ';', tab, whitespace "
                        "(default: found from the file)")
    add("--decimal-comma", action="store_true", default=None,
                   help="numbers are written 1,5 (default: found from the file)")
    add("--units-row", dest="units_row", action="store_true", default=None,
        help="the line under the header holds the columns' units (default: found from the "
             "file when every field of that line is a unit)")
    add("--no-units-row", dest="units_row", action="store_false",
        help="the line under the header is data, not units")
    add("--sheet", metavar="NAME|N",
                   help="the sheet of an Excel workbook, by name or 1-based number "
                        "(default: the first)")
    add("--reader", metavar="MODULE:FUNCTION",
                   help="read the file with your Python function (MODULE:FUNCTION or "
                        "FILE.py:FUNCTION), called with the file's path and returning a "
                        "dict of arrays voltage, displacement, time and a metadata dict")


OPTIONS = (("voltage", "--voltage"), ("displacement", "--displacement"), ("time", "--time"),
           ("rate", "--rate"), ("displacement_unit", "--displacement-unit"),
           ("voltage_gain", "--voltage-gain"), ("displacement_gain", "--displacement-gain"),
           ("lag", "--lag"),
           ("skip_until", "--skip-until"), ("separator", "--separator"),
           ("sheet", "--sheet"), ("reader", "--reader"))


def options_text(args):
    """The reading options given, as they would be typed (for reports and metadata)."""
    words = [f"{flag} {value:g}" if isinstance(value, float) else f"{flag} {value}"
             for name, flag in OPTIONS
             if (value := getattr(args, name)) is not None and value != 0]
    if args.decimal_comma:
        words.append("--decimal-comma")
    if getattr(args, "units_row", None) is not None:
        words.append("--units-row" if args.units_row else "--no-units-row")
    return " ".join(words)


# the record options that only mean something when a command reads both the voltage and
# the measured displacement of a record (fit, validate, report)
NO_VOLTAGE = {
    "--voltage": "it reads no voltage from {what}",
    "--voltage-gain": "it reads no voltage from {what} and writes the actuator's voltage "
                      "(voltage_V); for an amplifier's input, divide it by the amplifier's "
                      "gain",
    "--lag": "{what} has no measured displacement to pair with a voltage (a model's own "
             "input-output delay is in the model file, delay_samples)",
}
NO_DISPLACEMENT = {
    "--displacement": "it reads no displacement from {what}",
    "--displacement-unit": "it reads no displacement from {what}",
    "--displacement-gain": "it reads no displacement from {what}",
    "--lag": "it reads no measured displacement from {what} to pair with the voltage (a "
             "model's own input-output delay is in the model file, delay_samples)",
}


def refuse_unused(args, command, what, unused):
    """A UsageError for the first of the ``unused`` record options given (a mapping of
    option to why ``command`` has no use for it): an option is never silently ignored."""
    for option, why in unused.items():
        value = getattr(args, option[2:].replace("-", "_"))
        if value is not None and not (option == "--lag" and value == 0):
            raise UsageError(f"argument {option}: not used by pihyst {command}: "
                             + why.format(what=what))


def open_from_args(args, path, need, optional=("time",), say_warnings=True):
    """A :class:`pihyst.io.RecordReader` for ``path`` with the options of ``args``;
    ``optional`` quantities are read when the record has them."""
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", PihystWarning)
            reader = open_record(path, **record_kwargs(args), need=need, optional=optional)
    except InvalidArgumentError as err:      # an option that does not fit this record
        raise UsageError(f"{path}: {err}") from None
    if say_warnings:
        for w in caught:
            print(f"pihyst: warning: {w.message}", file=sys.stderr, flush=True)
    return reader


def record_kwargs(args):
    """The keyword arguments of :func:`pihyst.io.read_record` the record options of
    ``args`` give (the one translation of the options, for every command)."""
    return dict(voltage=args.voltage, displacement=args.displacement, time=args.time,
                rate=args.rate, displacement_unit=args.displacement_unit,
                voltage_gain=args.voltage_gain,
                displacement_gain=getattr(args, "displacement_gain", None), lag=args.lag,
                skip_until=args.skip_until,
                separator=args.separator, decimal_comma=args.decimal_comma,
                sheet=getattr(args, "sheet", None), reader=args.reader,
                units_row=getattr(args, "units_row", None))


def read_from_args(args, path, need, say=True, optional=("time",), warn=None):
    """All of a record (a :class:`pihyst.io.Record`) with the options of ``args``;
    prints what was read (unless ``say`` is False) and the reader's warnings (unless
    ``warn``, by default ``say``, is False)."""
    warn = say if warn is None else warn
    with open_from_args(args, path, need, optional, say_warnings=warn) as reader, \
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
