"""The creep part of an exported model (docs/export.md), for any model with a ``creep``
(:class:`pihyst.model.Creep`): PI models, and Bouc-Wen models once they carry one.

The C core's lags (csrc/pihyst_creep.h) run at the fixed interval ``creep.dt``:

    alpha_i = 1 - exp(-dt / tau_i)                     (C1, computed once by init)
    z_i    <- z_i + alpha_i (H - z_i)                  (C2)
    y       = H - sum_i g_i (H - z_i)                  (C3)

so the header holds the time constants, the gains, ``<NAME>_CREEP_DT`` and the alpha and
state storage, and the flat file a line ``creep n tau_1..tau_n g_1..g_n dt``. The lags
start at rest, z_i = H of the initial state (``<NAME>_INITIAL_OUTPUT``) for the model,
or of the compensator's state after its first voltage (``c.y_last``), as in Python.

A single-precision header (``--float``) holds the lags for the C core's ``_f32`` lags
(``pihyst_creep_f32``, csrc/pihyst_creep_f32.c, the deviation form (C2')-(C5') of
pihyst_creep.h): float time constants, gains, ``<NAME>_CREEP_DT`` and storage.
:func:`check_creep_precision` refuses, in one line, lags that floats cannot hold as the
model means them (a time constant that rounds to 0, gains whose float sum reaches 1,
which ``pihyst_creep_init_f32`` would refuse). A Bouc-Wen model's float header with creep
runs ``pihyst_bw_creep_compensator_step_f32`` (csrc/pihyst_bw_creep_f32.c).
"""

import numpy as np

from pihyst.exceptions import InvalidModelError

#: The flat file's first line: version 2 when the file has a creep line, so that a
#: library without creep refuses it instead of loading the model without its creep.
FLAT_MAGIC = "pihyst-flat 1"
FLAT_MAGIC_CREEP = "pihyst-flat 2"


def creep_of(model):
    """The model's :class:`~pihyst.model.Creep`, or None (a model without creep, or a
    model class that has none)."""
    return getattr(model, "creep", None)


def flat_magic(model):
    """The flat file's first line for ``model``."""
    return FLAT_MAGIC if creep_of(model) is None else FLAT_MAGIC_CREEP


def check_creep_precision(model, precision):
    """InvalidModelError (one line) when the lags of ``model`` have no header of
    ``precision``: in single precision, a time constant that is 0 or not finite as a
    float, or gains whose sum in float arithmetic (pihyst_creep_init_f32's check) is not
    below 1."""
    creep = creep_of(model)
    if precision != "float" or creep is None:
        return
    with np.errstate(over="ignore", under="ignore"):
        tau = np.asarray(creep.tau, dtype=np.float32)
        gain = np.asarray(creep.gain, dtype=np.float32)
        dt = np.float32(creep.dt)
    bad = np.flatnonzero(~np.isfinite(tau) | (tau <= 0))
    if bad.size:
        i = int(bad[0])
        raise InvalidModelError(f"creep.tau[{i}] = {float(creep.tau[i])!r} is 0 or infinite "
                                "as a float: --float cannot hold it; export in double "
                                "precision (without --float)")
    if not np.isfinite(dt):
        raise InvalidModelError(f"creep.dt = {creep.dt!r} is beyond the range of float: "
                                "--float cannot hold it; export in double precision "
                                "(without --float)")
    total = np.float32(0.0)
    for g in gain:                      # the order and precision of pihyst_creep_init_f32
        total = np.float32(total + g)
    if not total < 1:
        raise InvalidModelError(f"the creep gains sum to {float(total)!r} in single "
                                "precision (pihyst_creep_init_f32 needs less than 1): --float "
                                "cannot hold them; export in double precision (without "
                                "--float)")


def creep_flat_line(model, num):
    """``creep n tau_1..tau_n g_1..g_n dt`` (``num`` writes numbers exactly), or None for
    a model without creep."""
    creep = creep_of(model)
    if creep is None:
        return None
    return f"creep {creep.n_lags} {num(creep.tau)} {num(creep.gain)} {num([creep.dt])}"


def _api(precision):
    """(C type, suffix of the _f32 API, the fixed-interval dt argument) of ``precision``."""
    return ("float", "_f32", "-1.0f") if precision == "float" else ("double", "", "-1.0")


def creep_comment(model, name, *, bouc_wen=False, precision="double"):
    """The header comment's lines on the creep lags: how a firmware loop runs them (none
    without creep)."""
    creep = creep_of(model)
    if creep is None:
        return []
    real, sfx, fixed = _api(precision)
    up = name.upper()
    step = f"pihyst_bw_step{sfx}" if bouc_wen else f"pihyst_model_step{sfx}"
    lines = [" *\n",
             f" * Creep: {up}_CREEP_LAGS = {creep.n_lags} lags (pihyst_creep.h, "
             f"docs/theory/creep.md) at the\n",
             f" * fixed interval {up}_CREEP_DT = {creep.dt:g} s: run one step per tick at "
             f"that interval.\n",
             " * The model, its lags at rest at the initial state:\n",
             f" *     pihyst_creep{sfx} cr;\n",
             f" *     {name}_creep_init(&cr, {up}_INITIAL_OUTPUT);\n",
             f" *     {real} y = pihyst_creep_step{sfx}(&cr, {step}(&m, u));\n",
             f" * The compensator, after {name}_compensator_init (the lags at rest at the\n",
             f" * output of u_initial), with dt = {fixed} for the fixed interval:\n",
             f" *     {name}_creep_init(&cr, c.y_last);\n"]
    call = ("pihyst_bw_creep_compensator_step" if bouc_wen
            else "pihyst_creep_compensator_step") + sfx
    sources = [f"csrc/pihyst_creep{sfx}.c"] + ([f"csrc/pihyst_bw_creep{sfx}.c"] if bouc_wen
                                               else [])
    lines += [f" *     {real} volts = {call}(&cr, &c, {fixed}, y_desired, &y, &flags);\n",
              f" * Build with {' and '.join(sources)} too.\n"]
    return lines


def creep_include(model, *, bouc_wen=False):
    """The extra #include of a header with creep (empty without)."""
    if creep_of(model) is None:
        return ""
    return "#include \"pihyst_bw_creep.h\"\n" if bouc_wen else "#include \"pihyst_creep.h\"\n"


def creep_defines(model, name, initial_output, literal):
    """``#define``s of the lag count, the fixed interval and the initial hysteresis output
    ``initial_output`` (none without creep); ``literal`` writes a number exactly in the
    header's precision."""
    creep = creep_of(model)
    if creep is None:
        return []
    up = name.upper()
    return [f"#define {up}_CREEP_LAGS {creep.n_lags}\n",
            f"#define {up}_CREEP_DT {literal(creep.dt)}\n",
            f"#define {up}_INITIAL_OUTPUT {literal(initial_output)}\n"]


def creep_body(model, name, array, precision="double"):
    """The lag arrays, their alpha and state storage and ``<name>_creep_init`` (empty
    without creep); ``array(ctype, name, values)`` writes a static const array."""
    creep = creep_of(model)
    if creep is None:
        return []
    real, sfx, _ = _api(precision)
    up = name.upper()
    return [array(real, f"{name}_creep_tau", creep.tau),
            array(real, f"{name}_creep_gain", creep.gain),
            f"static {real} {name}_creep_alpha[{up}_CREEP_LAGS];\n",
            f"static {real} {name}_creep_state[{up}_CREEP_LAGS];\n\n",
            f"/* Wire up cr with this model's creep lags at {up}_CREEP_DT, at rest at the\n"
            " * hysteresis output h_settled (every lag state = h_settled). */\n",
            f"static inline pihyst_creep_status {name}_creep_init(pihyst_creep{sfx} *cr, "
            f"{real} h_settled)\n{{\n",
            f"    pihyst_creep_status s = pihyst_creep_init{sfx}(cr, {up}_CREEP_LAGS, "
            f"{name}_creep_tau,\n"
            f"        {name}_creep_gain, {up}_CREEP_DT, {name}_creep_alpha, "
            f"{name}_creep_state, NULL);\n",
            f"    if (s == PIHYST_CREEP_OK) pihyst_creep_settle{sfx}(cr, h_settled);\n",
            "    return s;\n}\n\n"]
