"""pihyst predict MODEL.json INPUT.csv -o OUT.csv"""

import numpy as np

from pihyst._version import __version__
from pihyst.cli.errors import check_output
from pihyst.io import CSVError, column_number, load_model, read_columns, write_columns


def register(sub):
    p = sub.add_parser("predict", help="displacement a model predicts for a voltage signal",
                       description="Run MODEL.json on the voltage_V column of INPUT.csv and "
                                   "write time_s, voltage_V and the predicted displacement_um.",
                       epilog="example: pihyst predict examples/paper_table1_multislope.json "
                              "examples/triangle_0_150V.csv -o out.csv")
    p.add_argument("model", metavar="MODEL.json", help="model file (see pihyst.load_model)")
    p.add_argument("input", metavar="INPUT.csv", help="CSV with a voltage_V column "
                   "(time_s copied if present)")
    p.add_argument("-o", "--output", metavar="OUT.csv", required=True, help="output CSV")
    p.set_defaults(run=run)


def _in_range_or_error(model, u, lines, path, column):
    lo, hi = model.input_range
    bad = np.flatnonzero(~((u >= lo) & (u <= hi)))
    if bad.size:
        i = bad[0]
        raise CSVError(path, int(lines[i]), column,
                       f"voltage_V = {u[i]:g} is outside the model's input range "
                       f"[{lo:g}, {hi:g}]")


def run(args):
    check_output(args.output)
    model = load_model(args.model)
    columns, lines = read_columns(args.input, ["voltage_V"], optional=["time_s"])
    u = columns["voltage_V"]
    _in_range_or_error(model, u, lines, args.input, column_number(args.input, "voltage_V"))
    note = []
    t = columns.get("time_s")
    if t is None:
        t = np.arange(u.size, dtype=float)
        note = [f"{args.input} has no time_s column: time_s is the sample index"]
    y = model.predict(u)
    write_columns(args.output, {"time_s": t, "voltage_V": u, "displacement_um": y},
                  comments=[f"pihyst {__version__} predict {args.model} {args.input}", *note])
    print(f"wrote {u.size} samples to {args.output} "
          f"(displacement {y.min():.4g} .. {y.max():.4g} {model.units.get('output', 'um')})")


