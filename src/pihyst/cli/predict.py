"""pihyst predict MODEL.json INPUT -o OUT.csv [record options] [--initial-state MODE]

Streams the record block by block (an hour at 10 kHz in bounded memory), except with
--initial-state settle, which needs the record's range first."""

import argparse

import numpy as np

from pihyst._version import __version__
from pihyst.cli.errors import UsageError, check_output
from pihyst.cli.model_inputs import (
    InputRange,
    add_initial_state_option,
    creep_times,
    delay_for_run,
    initial_state,
    settle_end,
)
from pihyst.cli.record_options import (
    NO_DISPLACEMENT,
    add_record_options,
    open_from_args,
    progress_bar,
    refuse_unused,
)
from pihyst.io import ColumnWriter, load_model
from pihyst.model._units import output_unit


def register(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    p = sub.add_parser("predict", help="displacement a model predicts for a voltage signal",
                       description="Run MODEL.json on the voltage of INPUT (voltage_V, or "
                                   "--voltage COL) and write time_s, voltage_V and the "
                                   "predicted displacement_um.",
                       epilog="example: pihyst predict examples/paper_table1_multislope.json "
                              "examples/triangle_0_150V.csv -o out.csv")
    p.add_argument("model", metavar="MODEL.json", help="model file (see pihyst.load_model)")
    p.add_argument("input", metavar="INPUT", help="record with the voltage (time copied if "
                   "present)")
    p.add_argument("-o", "--output", metavar="OUT.csv", required=True, help="output CSV")
    add_initial_state_option(p)
    add_record_options(p, "INPUT", unused=NO_DISPLACEMENT)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> None:
    refuse_unused(args, 'predict', 'INPUT', NO_DISPLACEMENT)
    check_output(args.output)
    model = load_model(args.model)
    limits = InputRange(model)
    state = initial_state(model, args.initial_state)
    names = ["time_s", "voltage_V", "displacement_um"]
    if args.initial_state == "settle":
        names.append("settling")
    lo = hi = None
    writer = None
    with open_from_args(args, args.input, need=("voltage",)) as reader, \
            progress_bar(f"predict {args.input}") as bar:
        chunks = reader.chunks(progress=bar)
        if args.initial_state == "settle":
            chunks = [reader.read(progress=bar)]
            end = settle_end(chunks[0].voltage)
        pending = None            # a delayed model's inputs carried to the next chunk
        lags = t_last = None      # with creep: the lag state and time carried likewise
        run_model = limits.run_model
        try:
            for rec in chunks:
                u = limits.check(rec.voltage, rec)
                if pending is None:
                    # the delay at the record's sample period: converted or refused
                    run_model = delay_for_run(run_model, args.input, t=rec.time)
                creep = getattr(run_model, "creep", None) is not None
                response = run_model.simulate(u, initial_state=state, pending_input=pending,
                                              **creep_times(run_model, rec, t_last),
                                              **({"creep_state": lags} if creep else {}))
                state, pending = response.final_state, response.pending_input
                if creep:
                    lags = response.final_creep_state
                    t_last = rec.time[-1] if rec.time is not None and len(rec) else t_last
                t = rec.time if rec.time is not None else \
                    np.arange(rec.start, rec.start + len(rec), dtype=float)
                if writer is None:
                    note = ([] if rec.time is not None else
                            [f"{args.input} has no time: time_s is the sample index"])
                    writer = ColumnWriter(args.output, names, comments=[
                        f"pihyst {__version__} predict {args.model} {args.input}", *note])
                out = {"time_s": t, "voltage_V": rec.voltage,
                       "displacement_um": response.output}
                if args.initial_state == "settle":
                    out["settling"] = (np.arange(len(rec)) < end).astype(float)
                writer.write(out)
                y = response.output
                lo = y.min() if lo is None else min(lo, y.min())
                hi = y.max() if hi is None else max(hi, y.max())
        except BaseException:
            if writer is not None:
                writer.abort()
            raise
        if writer is None:      # the readers refuse a record without samples first
            raise UsageError(f"{args.input}: no samples")
        writer.close()
        print(reader.describe())
    if limits.note():
        print(f"note: {limits.note()}")
    print(f"wrote {writer.rows} samples to {args.output} "
          f"(displacement {lo:.4g} .. {hi:.4g} {output_unit(model)})")
