"""pihyst validate MODEL.json DATA [record options] [--initial-state MODE] [--figure FILE]
[--json]: a model judged on a second record."""

import argparse
import json
import os

import numpy as np

from pihyst.cli.errors import UsageError
from pihyst.cli.model_inputs import (
    InputRange,
    add_initial_state_option,
    creep_times,
    delay_for_run,
    initial_state,
    settle_end,
)
from pihyst.cli.record_options import add_record_options, read_from_args
from pihyst.io import validate_model
from pihyst.model._units import output_unit

FIGURE_FORMATS = (".png", ".svg", ".pdf")


def register(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    p = sub.add_parser(
        "validate", help="judge a model on a record: errors overall and per cycle",
        description="Predict the voltage of DATA with MODEL.json and compare with the "
                    "measured displacement: mean absolute, RMS and largest error in µm and "
                    "in % of the measured range, overall, with the output offset re-fitted "
                    "to this record's sensor zero, and per input cycle.",
        epilog="example: pihyst fit loop1.csv -o model.json && pihyst validate model.json "
               "loop2.csv --figure check.svg")
    p.add_argument("model", metavar="MODEL.json", help="model file (see pihyst.load_model)")
    p.add_argument("data", metavar="DATA", help="record with the voltage and the measured "
                   "displacement")
    p.add_argument("--figure", metavar="FILE",
                   help="also draw the loop and the error over time (.png, .svg or .pdf; "
                        "needs matplotlib)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    # judged from a state it states: by default the one the record's first full sweep
    # settles (those samples are not judged), else the one given
    add_initial_state_option(p, default=None)
    add_record_options(p, "DATA")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> None:
    from pihyst.io import load_model
    if args.figure and os.path.splitext(args.figure)[1].lower() not in FIGURE_FORMATS:
        raise UsageError(f"--figure {args.figure}: use a .png, .svg or .pdf file name")
    model = load_model(args.model)
    rec = read_from_args(args, args.data, need=("voltage", "displacement"), say=not args.json)
    limits = InputRange(model)
    u = limits.check(rec.voltage, rec)
    mode = args.initial_state or "settle"
    first = settle_end(u) if mode == "settle" else 0
    if first >= len(u):
        if args.initial_state is not None:
            raise UsageError(f"{args.data}: no samples left after the first sweep "
                             "(--initial-state settle)")
        mode, first = "model", 0        # (said in the start line)
    start = _start_text(mode, args.initial_state is None, first, len(u))
    # a delayed model: its delay at the record's sample period, converted or refused
    run_model = delay_for_run(limits.run_model, args.data, t=rec.time)
    result = validate_model(run_model, u, rec.displacement,
                            initial_state=initial_state(model, mode), first=first,
                            t=creep_times(run_model, rec, None).get("t"))
    if args.figure:
        _figure(args, rec, result)
    if args.json:
        print(json.dumps({"model": args.model, "data": args.data,
                          "record": {k: str(v) for k, v in rec.metadata.items()},
                          "input_range_note": limits.note(),
                          "start_state": {"mode": mode, "given": args.initial_state is not None,
                                          "settling_samples": first, "text": start},
                          **result.to_dict()}, indent=2))
        return
    _print(args, model, rec, result, limits, start)


def _start_text(mode, default, first, n):
    """The start state validate judges from, in words."""
    if mode == "settle":
        return (f"start state: settled by the record (its first full sweep, samples 0 to "
                f"{first - 1}, sets the operators and is not judged; "
                + ("the default" if default else "--initial-state settle") + ")")
    if default:
        return ("start state: the model file's (the record has no sample after its first "
                "full sweep to settle the operators with; give --initial-state to choose)")
    what = {"model": "the model file's", "bottom": "at rest at the bottom of the input "
            "range", "top": "at rest at the top of the input range", "zero": "every "
            "operator at 0"}[mode]
    return f"start state: {what} (--initial-state {mode}); all {n} samples judged"


def _line(name, e):
    pct = "".join(f" {e.pct(v):>8.3g} %" for v in (e.mean_abs, e.rms, e.max_abs))
    return f"  {name:<26}{e.mean_abs:>10.4g}{e.rms:>10.4g}{e.max_abs:>10.4g}{pct}"


def _print(args, model, rec, result, limits, start):
    e = result.errors
    unit = output_unit(model)
    print(f"pihyst validate: {args.model} on {args.data}: {len(rec)} samples, voltage "
          f"{rec.voltage.min():.4g} .. {rec.voltage.max():.4g} V, measured range "
          f"{e.span:.4g} {unit}"
          + (f"; the first {result.first} samples settle the operators (not judged)"
             if result.first else ""))
    print(start)
    if limits.note():
        print(f"note: {limits.note()}")
    print(f"\nerrors (measured - predicted) in {unit}, and in % of the measured range:")
    print(f"  {'':<26}{'mean |e|':>10}{'RMS':>10}{'max |e|':>10}{'mean':>11}{'RMS':>11}"
          f"{'max':>11}")
    print(_line("as the model is", e))
    print(_line(f"offset re-fitted ({result.shift:+.3g})", result.shifted))
    where = rec.error(e.at, "displacement", "").args[0].rstrip(": ")
    print(f"largest error at sample {e.at} ({where})")
    if abs(result.shift) > 2 * result.shifted.rms:
        print(f"note: the errors are mostly an offset of {result.shift:+.4g} {unit}: this "
              f"record's sensor zero differs from the fitted record's")
    print(f"\nper cycle (cut at the valleys of the voltage), {len(result.cycles)} cycles:")
    print(f"  {'cycle':>5}{'samples':>9}{'from':>9}{'mean |e|':>10}{'RMS':>10}{'max |e|':>10}")
    shown = result.cycles if len(result.cycles) <= 40 else \
        result.cycles[:20] + [None] + result.cycles[-19:]
    for k, c in enumerate(shown):
        if c is None:
            print(f"  {'...':>5}")
            continue
        a, b, ce = c
        number = k + 1 if k < 20 or len(result.cycles) <= 40 else len(result.cycles) - 39 + k
        print(f"  {number:>5}{ce.samples:>9}{a:>9}{ce.mean_abs:>10.4g}{ce.rms:>10.4g}"
              f"{ce.max_abs:>10.4g}")
    if args.figure:
        print(f"\nwrote {args.figure}")


def _figure(args, rec, result):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as err:
        raise UsageError(f"--figure needs matplotlib ({err}): pip install 'pihyst[plot]'") \
            from None
    import io

    from pihyst._atomic import write_atomically
    u, y, p = rec.voltage, rec.displacement, result.predicted
    t = rec.time if rec.time is not None else np.arange(len(u), dtype=float)
    step = max(1, len(u) // 200_000)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    ax1.plot(u[::step], y[::step], lw=0.8, label="measured")
    ax1.plot(u[::step], p[::step], lw=0.8, label="predicted")
    ax1.set_xlabel("voltage (V)")
    ax1.set_ylabel("displacement (µm)")
    ax1.legend()
    ax1.set_title(f"Figure 1. {os.path.basename(args.data)}: loop")
    ax2.plot(t[::step], (y - p)[::step], lw=0.6)
    ax2.set_xlabel("time (s)" if rec.time is not None else "sample")
    ax2.set_ylabel("measured − predicted (µm)")
    ax2.set_title(f"Figure 2. error (RMS {result.errors.rms:.3g} µm)")
    buf = io.BytesIO()
    fig.savefig(buf, format=os.path.splitext(args.figure)[1][1:].lower(), dpi=130)
    plt.close(fig)
    write_atomically(args.figure, buf.getvalue())
