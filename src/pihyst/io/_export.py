"""Models out of Python: a C header for firmware, a flat text file for the shared library.

- :func:`c_header`: the model as ``static const`` data with an init function, for a
  controller that compiles the C core (csrc/) itself. Double precision, or single with
  ``precision="float"`` (the core's ``_f32`` API). Values are written with enough digits
  to be read back exactly (17 significant digits for double, 9 for float).
- :func:`flat_text`: the model as lines of numbers that ``pihyst_lib_load`` of the shared
  library reads (docs/export.md gives the format), for LabVIEW, MATLAB or Simulink.

A model's input delay of d samples (``model.delay``) is not inside the C core's step: the
header defines ``<NAME>_DELAY_SAMPLES`` and the flat file ends with a line ``delay d``
(only when d > 0); firmware feeds the compensator the target d ticks ahead, and
predictions come d ticks late (docs/export.md).

A model with creep (``model.creep``) carries its lags into both forms
(:mod:`pihyst.io._export_creep`): the header's ``<name>_creep_init`` and the flat file's
``creep`` line, which the shared library applies at the fixed interval ``creep.dt``.
"""

import re

import numpy as np

from pihyst._version import __version__
from pihyst.exceptions import InvalidArgumentError, InvalidModelError
from pihyst.io._export_boucwen import boucwen_flat_lines, boucwen_header
from pihyst.io._export_creep import (
    check_creep_precision,
    creep_body,
    creep_comment,
    creep_defines,
    creep_flat_line,
    creep_include,
    flat_magic,
)

_FAMILY_ENUM = {"classical": "PIHYST_CLASSICAL", "multislope": "PIHYST_MULTISLOPE",
                "pwl": "PIHYST_PWL"}
_FAMILY_CODE = {"classical": 0, "multislope": 1, "pwl": 2}


#: the C core's headers (csrc/, csrc/lib/): a generated header of the same name would be
#: included in their place
CORE_HEADERS = ("pihyst.h", "pihyst_api.h", "pihyst_boucwen.h", "pihyst_boucwen_api.h",
                "pihyst_bw_creep.h", "pihyst_creep.h", "pihyst_f32_names.h",
                "pihyst_internal.h", "pihyst_lib.h")


def c_identifier(text):
    """A C identifier made from ``text`` (a file name, say): letters, digits and _,
    starting with a letter (a leading _ is reserved in C at file scope)."""
    name = re.sub(r"[^0-9A-Za-z_]", "_", text).lstrip("_")
    if not name or name[0].isdigit():
        name = "model_" + name if name else "model"
    return name


def core_prefix(name):
    """True if the C prefix ``name`` is in the C core's namespace (pihyst_..., PIHYST_...):
    the header's symbols and macros would collide with the core's."""
    return name.lower().startswith("pihyst")


def checked_c_prefix(name):
    """``name`` made a C identifier, refused (InvalidArgumentError) in the core's
    namespace."""
    ident = c_identifier(name)
    if core_prefix(ident):
        raise InvalidArgumentError(f"C prefix {ident!r}: names starting with 'pihyst' are "
                                   "the C core's (pihyst_model_init, pihyst_params, ...); "
                                   "choose another")
    return ident


FLOAT_MAX = float(np.finfo(np.float32).max)


def _literal(x, precision, where=""):
    """A C literal of ``x``; InvalidModelError naming the value when single precision
    cannot hold it (it would be written as ``inf``, which does not compile)."""
    if precision == "float":
        if abs(float(x)) > FLOAT_MAX:
            raise InvalidModelError(
                f"{where or 'a value'} = {float(x)!r} is beyond the range of float "
                f"(largest {FLOAT_MAX:.8g}): --float cannot hold it; export in double "
                "precision (without --float)")
        with np.errstate(over="ignore"):
            v = np.float32(x)
        text = np.format_float_positional(v, unique=True, trim="0") if abs(v) < 1e16 and \
            (v == 0 or abs(v) >= 1e-4) else np.format_float_scientific(v, unique=True)
        return (text if any(c in text for c in ".e") else text + ".0") + "f"
    return repr(float(x))


def _array(ctype, name, values, precision, per_line=4):
    items = [_literal(v, precision, f"{name}[{i}]") for i, v in enumerate(values)]
    lines = [", ".join(items[i:i + per_line]) for i in range(0, len(items), per_line)]
    body = ",\n    ".join(lines)
    return f"static const {ctype} {name}[{len(items)}] = {{\n    {body}\n}};\n"


def _sizes(name, values):
    return f"static const size_t {name}[{len(values)}] = {{{', '.join(map(str, values))}}};\n"


def c_header(model, name, *, precision="double", source=""):
    """The text of a C header holding ``model`` (see the module docstring).

    The header defines ``<name>_params`` (a ``pihyst_params``), the model's scratch and
    state, ``<name>_init(pihyst_model *m)`` and ``<name>_compensator_init(...)``.
    """
    if precision not in ("double", "float"):
        raise InvalidModelError(f"precision must be 'double' or 'float', got {precision!r}")
    check_creep_precision(model, precision)
    if model.family == "bouc-wen":
        name = checked_c_prefix(name)
        return boucwen_header(model, name, lambda v: _literal(v, precision), precision,
                              source, _delay_comment(model, name),
                              lambda ctype, label, values: _array(ctype, label, values,
                                                                  precision))
    if model.family not in _FAMILY_ENUM:
        raise InvalidModelError(f"no C form for a {model.family!r} model")
    name = checked_c_prefix(name)
    real, sfx = ("double", "") if precision == "double" else ("float", "_f32")
    k = model.n_operators
    guard = f"PIHYST_MODEL_{name.upper()}_H"
    out = [f"/* {name}.h - a {model.family} model of {k} operators, generated by pihyst "
           f"{__version__}{' from ' + source if source else ''}.\n",
           " *\n",
           " * Compile with the C core (csrc/pihyst_*.c, -std=c99). Use:\n",
           f" *     pihyst_model{sfx} m;\n",
           f" *     if ({name}_init(&m) != PIHYST_OK) ... ;\n",
           f" *     {real} y = pihyst_model_step{sfx}(&m, u);\n",
           " * or, for the feedforward compensator (voltage limits, slew in volts per sample):\n",
           f" *     pihyst_compensator{sfx} c;\n",
           f" *     {name}_compensator_init(&c, &m, u_min, u_max, max_step, u_initial);\n",
           f" *     {real} volts = pihyst_compensator_step{sfx}(&c, y_desired, &flags);\n",
           " * One model per header: the state and scratch below are this model's.\n",
           *_delay_comment(model, name),
           *creep_comment(model, name, precision=precision),
           " */\n",
           f"#ifndef {guard}\n#define {guard}\n\n#include \"pihyst.h\"\n",
           creep_include(model), "\n",
           f"#define {name.upper()}_N_OPS {k}\n",
           f"#define {name.upper()}_DELAY_SAMPLES {model.delay}\n",
           *creep_defines(model, name, model.hysteresis_output(model.initial_state),
                          lambda v: _literal(v, precision))]
    n_points = 0
    if model.family in ("classical", "multislope"):
        out.append(_array(real, f"{name}_thresholds", model.thresholds, precision))
    else:
        rise_start = np.concatenate([[0], np.cumsum([x.size for x, _ in model.rising])])
        fall_start = np.concatenate([[0], np.cumsum([x.size for x, _ in model.falling])])
        n_points = int(rise_start[-1] + fall_start[-1])
        out += [_sizes(f"{name}_rise_start", rise_start),
                _array(real, f"{name}_rise_x", np.concatenate([x for x, _ in model.rising]),
                       precision),
                _array(real, f"{name}_rise_y", np.concatenate([y for _, y in model.rising]),
                       precision),
                _sizes(f"{name}_fall_start", fall_start),
                _array(real, f"{name}_fall_x", np.concatenate([x for x, _ in model.falling]),
                       precision),
                _array(real, f"{name}_fall_y", np.concatenate([y for _, y in model.falling]),
                       precision)]
    out += [_array(real, f"{name}_weights", model.weights, precision),
            _array(real, f"{name}_initial_state", model.initial_state, precision), "\n"]
    lit = lambda v, where="": _literal(v, precision, where)  # noqa: E731
    fields = [f"    .family = {_FAMILY_ENUM[model.family]},", f"    .n_ops = {k},"]
    if model.family != "pwl":
        fields.append(f"    .thresholds = {name}_thresholds,")
    fields += [f"    .weights = {name}_weights,", f"    .offset = {lit(model.offset, 'offset')},",
               f"    .u_min = {lit(model.input_range[0], 'input_range[0]')},",
               f"    .u_max = {lit(model.input_range[1], 'input_range[1]')},"]
    if model.family == "multislope":
        fields.append(f"    .shape = {{.U = {lit(model.U)}, .a = {lit(model.a)}, "
                      f".b = {lit(model.b)}, .h = {lit(model.h)}}},")
    if model.family == "pwl":
        fields.append(f"    .pwl = {{{name}_rise_start, {name}_rise_x, {name}_rise_y,\n"
                      f"            {name}_fall_start, {name}_fall_x, {name}_fall_y}},")
    fields.append(f"    .initial_state = {name}_initial_state,")
    scratch_len = (f"PIHYST_COMPENSATOR_SCRATCH_LEN{'_F32' if sfx else ''}({k}, {n_points})")
    out += [f"static const pihyst_params{sfx} {name}_params = {{\n", "\n".join(fields), "\n};\n\n",
            f"static {real} {name}_coef[PIHYST_COEF_LEN({k})];\n",
            f"static {real} {name}_state[{k}];\n",
            f"static {real} {name}_scratch[{scratch_len}];\n\n",
            "/* Wire up m with this model, its operators at the initial state. */\n",
            f"static inline pihyst_status {name}_init(pihyst_model{sfx} *m)\n{{\n",
            f"    return pihyst_model_init{sfx}(m, &{name}_params, {name}_coef, "
            f"{name}_state);\n}}\n\n",
            f"/* A compensator of m (initialised by {name}_init) with voltage limits\n"
            " * [u_min, u_max] (NAN: the model's input range), a slew limit max_step in\n"
            " * volts per sample (INFINITY: none) and the voltage u_initial before the first\n"
            " * sample. */\n",
            f"static inline pihyst_status {name}_compensator_init(pihyst_compensator{sfx} *c,\n"
            f"        pihyst_model{sfx} *m, {real} u_min, {real} u_max, {real} max_step,\n"
            f"        {real} u_initial)\n{{\n",
            f"    return pihyst_compensator_init{sfx}(c, m, u_min, u_max, max_step, u_initial,\n"
            f"        {name}_scratch, sizeof {name}_scratch / sizeof {name}_scratch[0]);\n}}\n\n",
            *creep_body(model, name, lambda ctype, label, values:
                        _array(ctype, label, values, precision), precision),
            f"#endif /* {guard} */\n"]
    return "".join(out)


def _delay_comment(model, name):
    """The header's lines on the model's input delay (none without one)."""
    if not model.delay:
        return []
    period = ("" if model.sample_period is None else
              f" at {model.sample_period:g} s per tick")
    return [" *\n",
            f" * The output lags the input by {name.upper()}_DELAY_SAMPLES = {model.delay} "
            f"ticks{period}:\n",
            f" * at tick k feed the compensator the desired displacement of tick k + "
            f"{model.delay}\n",
            " * (the trajectory's preview; hold the last voltage for the final ticks), and\n",
            f" * read pihyst_model_step's output as the displacement {model.delay} ticks "
            f"later.\n"]


def flat_text(model):
    """The model as the shared library's flat model file (docs/export.md).

    Lines: the magic ``pihyst-flat 1``; ``family K`` (0 classical, 1 multislope, 2 pwl;
    3 Bouc-Wen, whose lines follow :func:`pihyst.io._export_boucwen.boucwen_flat_lines`);
    ``offset u_min u_max``; ``U a b h`` (multislope, else the paper's defaults); the K
    thresholds (classical, multislope) or, for pwl, K lines ``n x_1..x_n y_1..y_n`` of
    rising then K of falling polylines; the K weights; the K initial states; for a model
    with creep, ``creep n tau_1..tau_n g_1..g_n dt`` (and the magic ``pihyst-flat 2``);
    for a delayed model, ``delay d``. Numbers in 17 significant digits, so the library
    reads back exactly the model's doubles.
    """
    num = lambda values: " ".join(repr(float(v)) for v in values)  # noqa: E731
    if model.family == "bouc-wen":
        return _with_tail(model, [flat_magic(model), *boucwen_flat_lines(model, num)], num)
    if model.family not in _FAMILY_CODE:
        raise InvalidModelError(f"no flat form for a {model.family!r} model")
    lines = [flat_magic(model), f"{_FAMILY_CODE[model.family]} {model.n_operators}",
             num([model.offset, *model.input_range])]
    if model.family == "multislope":
        lines.append(num([model.U, model.a, model.b, model.h]))
    else:
        lines.append(num([150.0, 0.8, 1.2, 0.5]))
    if model.family == "pwl":
        for x, y in (*model.rising, *model.falling):
            lines.append(f"{x.size} {num(x)} {num(y)}")
    else:
        lines.append(num(model.thresholds))
    lines += [num(model.weights), num(model.initial_state)]
    return _with_tail(model, lines, num)


def _with_tail(model, lines, num):
    """The file's text: ``lines``, then the creep and delay lines the model has. Both come
    after the numbers of the model: the library applies the creep, and loads a delayed
    model as the same model without the delay, which the caller applies
    (docs/export.md)."""
    creep = creep_flat_line(model, num)
    if creep is not None:
        lines.append(creep)
    if model.delay:
        lines.append(f"delay {model.delay}")
    return "\n".join(lines) + "\n"
