"""pihyst export MODEL.json (--c | --flat) -o OUT [--name NAME] [--float]"""

import argparse
import os

from pihyst._atomic import write_atomically
from pihyst.cli.errors import UsageError
from pihyst.exceptions import InvalidModelError
from pihyst.io import load_model
from pihyst.io._export import CORE_HEADERS, c_header, c_identifier, core_prefix, flat_text


def register(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    p = sub.add_parser(
        "export", help="a model for a controller: C header, or the shared library's file",
        description="Write MODEL.json for use outside Python: --c writes a C header with the "
                    "model as static const data and an init function for a firmware build "
                    "with the C core (csrc/); --flat writes the model file that the shared "
                    "library (make -C csrc shared; LabVIEW, MATLAB, Simulink) loads with "
                    "pihyst_lib_load.",
        epilog="example: pihyst export model.json --c -o actuator_x.h   (docs/export.md)")
    p.add_argument("model", metavar="MODEL.json", help="model file (see pihyst.load_model)")
    kind = p.add_mutually_exclusive_group(required=True)
    kind.add_argument("--c", action="store_true", help="C header for the C core")
    kind.add_argument("--flat", action="store_true", help="model file of the shared library")
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="file to write")
    p.add_argument("--name", help="C prefix of the header's symbols (default: from OUT)")
    p.add_argument("--float", action="store_true",
                   help="single precision (the core's _f32 API), for FPUs without double")
    p.set_defaults(run=run)


def _size(model):
    size = "state (u, z)" if model.family == "bouc-wen" else f"{model.n_operators} operators"
    creep = getattr(model, "creep", None)
    if creep is not None:
        size += f", {creep.n_lags} creep lags at {creep.dt:g} s"
    return size


def run(args: argparse.Namespace) -> None:
    model = load_model(args.model)
    if args.flat:
        if args.float or args.name:
            raise UsageError("--float and --name go with --c, not --flat")
        write_atomically(args.output, flat_text(model))
        print(f"wrote {args.output}: {model.family} model, {_size(model)} (pihyst_lib_load)")
        return
    base = os.path.basename(args.output)
    if base.lower() in CORE_HEADERS:
        raise UsageError(f"-o {args.output}: the C core has a header of that name, which "
                         "this one would replace in your build; choose another file name")
    stem = os.path.splitext(base)[0]
    name = args.name if args.name is not None else stem
    if args.name is not None and c_identifier(args.name) != args.name:
        raise UsageError(f"--name {args.name!r} is not a C identifier (letters, digits "
                         "and _, starting with a letter)")
    if core_prefix(c_identifier(name)):
        where = f"--name {args.name}" if args.name is not None else \
            f"-o {args.output}: the prefix {c_identifier(name)!r}"
        raise UsageError(f"{where}: names starting with 'pihyst' are the C core's "
                         "(pihyst_model_init, pihyst_params, ...) and would not compile; "
                         "choose another" + ("" if args.name is not None else " (--name)"))
    try:
        text = c_header(model, name, precision="float" if args.float else "double",
                        source=os.path.basename(args.model))
    except InvalidModelError as err:
        raise UsageError(f"{args.model}: {err}") from None
    write_atomically(args.output, text)
    print(f"wrote {args.output}: {model.family} model, {_size(model)} as "
          f"{c_identifier(name)}_params ({'float' if args.float else 'double'}); init with "
          f"{c_identifier(name)}_init(&model)")
