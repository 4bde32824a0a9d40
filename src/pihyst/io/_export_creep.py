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

The C lags are double precision only: a single-precision header of a model with creep is
refused (:func:`check_creep_precision`) rather than written without its creep.
"""

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
    """InvalidModelError for a single-precision header of a model with creep."""
    if precision == "float" and creep_of(model) is not None:
        raise InvalidModelError("a model with creep has no single-precision C header: the "
                                "C core's creep lags (pihyst_creep.h) are double only; "
                                "export it without --float")


def creep_flat_line(model, num):
    """``creep n tau_1..tau_n g_1..g_n dt`` (``num`` writes numbers exactly), or None for
    a model without creep."""
    creep = creep_of(model)
    if creep is None:
        return None
    return f"creep {creep.n_lags} {num(creep.tau)} {num(creep.gain)} {num([creep.dt])}"


def creep_comment(model, name, *, bouc_wen=False):
    """The header comment's lines on the creep lags: how a firmware loop runs them (none
    without creep)."""
    creep = creep_of(model)
    if creep is None:
        return []
    up = name.upper()
    step = "pihyst_bw_step" if bouc_wen else "pihyst_model_step"
    lines = [" *\n",
             f" * Creep: {up}_CREEP_LAGS = {creep.n_lags} lags (pihyst_creep.h, "
             f"docs/theory/creep.md) at the\n",
             f" * fixed interval {up}_CREEP_DT = {creep.dt:g} s: run one step per tick at "
             f"that interval.\n",
             " * The model, its lags at rest at the initial state:\n",
             " *     pihyst_creep cr;\n",
             f" *     {name}_creep_init(&cr, {up}_INITIAL_OUTPUT);\n",
             f" *     double y = pihyst_creep_step(&cr, {step}(&m, u));\n",
             f" * The compensator, after {name}_compensator_init (the lags at rest at the\n",
             " * output of u_initial), with dt = -1.0 for the fixed interval:\n",
             f" *     {name}_creep_init(&cr, c.y_last);\n"]
    call = "pihyst_bw_creep_compensator_step" if bouc_wen else "pihyst_creep_compensator_step"
    lines += [f" *     double volts = {call}(&cr, &c, -1.0, y_desired, &y, &flags);\n",
              " * Build with csrc/pihyst_creep.c" + (" and csrc/pihyst_bw_creep.c" if bouc_wen
                                                    else "") + " too.\n"]
    return lines


def creep_include(model, *, bouc_wen=False):
    """The extra #include of a header with creep (empty without)."""
    if creep_of(model) is None:
        return ""
    return "#include \"pihyst_bw_creep.h\"\n" if bouc_wen else "#include \"pihyst_creep.h\"\n"


def creep_defines(model, name, initial_output, literal):
    """``#define``s of the lag count, the fixed interval and the initial hysteresis output
    ``initial_output`` (none without creep); ``literal`` writes a double exactly."""
    creep = creep_of(model)
    if creep is None:
        return []
    up = name.upper()
    return [f"#define {up}_CREEP_LAGS {creep.n_lags}\n",
            f"#define {up}_CREEP_DT {literal(creep.dt)}\n",
            f"#define {up}_INITIAL_OUTPUT {literal(initial_output)}\n"]


def creep_body(model, name, array):
    """The lag arrays, their alpha and state storage and ``<name>_creep_init`` (empty
    without creep); ``array(ctype, name, values)`` writes a static const array."""
    creep = creep_of(model)
    if creep is None:
        return []
    up = name.upper()
    return [array("double", f"{name}_creep_tau", creep.tau),
            array("double", f"{name}_creep_gain", creep.gain),
            f"static double {name}_creep_alpha[{up}_CREEP_LAGS];\n",
            f"static double {name}_creep_state[{up}_CREEP_LAGS];\n\n",
            f"/* Wire up cr with this model's creep lags at {up}_CREEP_DT, at rest at the\n"
            " * hysteresis output h_settled (every lag state = h_settled). */\n",
            f"static inline pihyst_creep_status {name}_creep_init(pihyst_creep *cr, "
            f"double h_settled)\n{{\n",
            f"    pihyst_creep_status s = pihyst_creep_init(cr, {up}_CREEP_LAGS, "
            f"{name}_creep_tau,\n"
            f"        {name}_creep_gain, {up}_CREEP_DT, {name}_creep_alpha, "
            f"{name}_creep_state, NULL);\n",
            "    if (s == PIHYST_CREEP_OK) pihyst_creep_settle(cr, h_settled);\n",
            "    return s;\n}\n\n"]
