"""Export for controllers: the generated C header compiles with the core under the
firmware flags and reproduces predict and compensate (double to 1e-12, float to a stated
tolerance); the shared library's plain C ABI, called through ctypes, does the same; the
flat model file round-trips."""

import ctypes
import subprocess

import numpy as np
import pytest
from c_export import (
    CSRC,
    compile_core,
    compile_driver,
    export_signals,
    needs_compiler,
    run_driver,
    shared_library,
)

import pihyst
from pihyst.cli import main
from pihyst.exceptions import InvalidArgumentError
from pihyst.io._export import CORE_HEADERS, c_header, flat_text

KP_LIKE = pihyst.PiecewiseLinearPI(
    [([0, 40, 60, 150], [0, 0, 1, 1]), ([0, 90, 110, 150], [0, 0, 1, 1]),
     ([0, 150], [-5, 145])],
    [([0, 10, 30, 150], [0, 0, 1, 1]), ([0, 60, 80, 150], [0, 0, 1, 1]),
     ([0, 150], [5, 155])],
    [6.0, 4.0, 0.2], offset=-1.5, initial_state=[0.0, 0.0, 5.0])
MODELS = {
    "classical": pihyst.ClassicalPI([0, 10, 30, 60], [0.2, 0.05, 0.03, 0.01], offset=0.7,
                                    initial_state=[0, 10, 30, 60]),
    "multislope": pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028], b=1.25),
    "pwl": KP_LIKE,
}

DRIVER = r"""
#include <stdio.h>
#include <math.h>
#include "{header}"
/* stdin: n, n voltages, n desired outputs; stdout: n predictions, then n voltages */
int main(void)
{{
    static {real} u[4096], yd[4096];
    pihyst_model{sfx} m;
    pihyst_compensator{sfx} c;
    int n, t;
    if (scanf("%d", &n) != 1 || n > 4096) return 3;
    for (t = 0; t < n; ++t) {{ double v; if (scanf("%lf", &v) != 1) return 3; u[t] = ({real})v; }}
    for (t = 0; t < n; ++t) {{ double v; if (scanf("%lf", &v) != 1) return 3; yd[t] = ({real})v; }}
    if ({name}_init(&m) != PIHYST_OK) return 4;
    for (t = 0; t < n; ++t) printf("%.17g\n", (double)pihyst_model_step{sfx}(&m, u[t]));
    pihyst_model_reset{sfx}(&m, {name}_initial_state);
    if ({name}_compensator_init(&c, &m, NAN, NAN, INFINITY, m.u_min) != PIHYST_OK) return 5;
    for (t = 0; t < n; ++t) printf("%.17g\n", (double)pihyst_compensator_step{sfx}(&c, yd[t], 0));
    return 0;
}}
"""


@pytest.fixture(scope="module")
def core_objects(tmp_path_factory):
    """The C core compiled once with the firmware flags, for every driver to link."""
    return compile_core(tmp_path_factory, ("pihyst_model.c", "pihyst_inverse.c",
                                           "pihyst_model_f32.c", "pihyst_inverse_f32.c"))


def _build_and_run(tmp_path, model, precision, core):
    name = f"exported_{model.family}"
    real, sfx = ("double", "") if precision == "double" else ("float", "_f32")
    exe = compile_driver(tmp_path, f"{name}.h", c_header(model, name, precision=precision),
                         DRIVER.format(header=f"{name}.h", real=real, sfx=sfx, name=name), core)
    u, yd = export_signals(model)
    values = run_driver(exe, u, yd)
    return u, yd, values[:u.size], values[u.size:]


@pytest.mark.parametrize("family", sorted(MODELS))
def test_header_reproduces_predict_and_compensate_in_double(tmp_path, family, core_objects):
    model = MODELS[family]
    u, yd, y_c, u_c = _build_and_run(tmp_path, model, "double", core_objects)
    np.testing.assert_allclose(y_c, model.predict(u), rtol=0, atol=1e-12)
    np.testing.assert_allclose(u_c, pihyst.compensate(model, yd).voltage, rtol=0, atol=1e-12)


@pytest.mark.parametrize("family", sorted(MODELS))
def test_header_in_single_precision_within_its_stated_tolerance(tmp_path, family,
                                                                core_objects):
    """float: outputs within 1e-5 of the output range; voltages within 1e-4 of the input
    range where the model is not flat (docs/export.md)."""
    model = MODELS[family]
    u, yd, y_c, u_c = _build_and_run(tmp_path, model, "float", core_objects)
    y = model.predict(u)
    assert np.max(np.abs(y_c - y)) <= 1e-5 * np.ptp(y)
    ref = pihyst.compensate(model, yd)
    assert np.max(np.abs(model.predict(u_c) - model.predict(ref.voltage))) <= 1e-4 * np.ptp(y)


# ---------------------------------------------------------------- the shared library
@pytest.fixture(scope="module")
def lib():
    return shared_library()


def _ptr(a, ctype=ctypes.c_double):
    return None if a is None else a.ctypes.data_as(ctypes.POINTER(ctype))


def _create(lib, model):
    f = lambda a: None if a is None else np.ascontiguousarray(a, dtype=float)  # noqa: E731
    status = ctypes.c_int32(1)
    family = {"classical": 0, "multislope": 1, "pwl": 2}[model.family]
    keep = {"w": f(model.weights), "s0": f(model.initial_state)}
    if model.family == "pwl":
        keep["rl"] = np.array([x.size for x, _ in model.rising], dtype=np.int32)
        keep["fl"] = np.array([x.size for x, _ in model.falling], dtype=np.int32)
        keep["rx"] = f(np.concatenate([x for x, _ in model.rising]))
        keep["ry"] = f(np.concatenate([y for _, y in model.rising]))
        keep["fx"] = f(np.concatenate([x for x, _ in model.falling]))
        keep["fy"] = f(np.concatenate([y for _, y in model.falling]))
    shape = f([model.U, model.a, model.b, model.h]) if model.family == "multislope" else None
    thr = f(model.thresholds) if model.family != "pwl" else None
    i32p = lambda a: _ptr(a, ctypes.c_int32)  # noqa: E731
    h = lib.pihyst_lib_create(family, model.n_operators, _ptr(thr), _ptr(keep["w"]),
                              model.offset, *model.input_range, _ptr(shape),
                              i32p(keep.get("rl")), _ptr(keep.get("rx")), _ptr(keep.get("ry")),
                              i32p(keep.get("fl")), _ptr(keep.get("fx")), _ptr(keep.get("fy")),
                              _ptr(keep["s0"]), ctypes.byref(status))
    assert status.value == 0, lib.pihyst_lib_status_text(status.value)
    return h


def _run_lib(lib, h, model):
    u, yd = export_signals(model)
    y = np.empty_like(u)
    assert lib.pihyst_lib_predict(h, _ptr(u), _ptr(y), u.size) == 0
    assert lib.pihyst_lib_reset(h, None, 0) == 0
    assert lib.pihyst_lib_compensator_start(h, np.nan, np.nan, 0.0, model.input_range[0]) == 0
    volts = np.empty_like(yd)
    flags = np.empty(yd.size, dtype=np.uint8)
    n_flagged = lib.pihyst_lib_compensate(h, _ptr(yd), _ptr(volts),
                                          _ptr(flags, ctypes.c_uint8), yd.size)
    return u, yd, y, volts, flags, n_flagged


@pytest.mark.parametrize("family", sorted(MODELS))
def test_shared_library_reproduces_predict_and_compensate(lib, family, tmp_path):
    model = MODELS[family]
    for source in ("arrays", "file"):
        if source == "arrays":
            h = _create(lib, model)
        else:
            path = tmp_path / "m.pihyst"
            path.write_text(flat_text(model))
            status = ctypes.c_int32(1)
            h = lib.pihyst_lib_load(str(path).encode(), ctypes.byref(status))
            assert status.value == 0, lib.pihyst_lib_status_text(status.value)
        try:
            u, yd, y, volts, flags, n_flagged = _run_lib(lib, h, model)
        finally:
            lib.pihyst_lib_free(h)
        np.testing.assert_allclose(y, model.predict(u), rtol=0, atol=1e-12)
        ref = pihyst.compensate(model, yd)
        np.testing.assert_allclose(volts, ref.voltage, rtol=0, atol=1e-12)
        assert n_flagged == int(np.count_nonzero(flags)) == int(np.count_nonzero(ref.flags))


def test_shared_library_refuses_bad_input(lib, tmp_path):
    h = _create(lib, MODELS["classical"])
    try:
        u = np.array([0.0, 200.0])
        y = np.zeros(2)
        assert lib.pihyst_lib_predict(h, _ptr(u), _ptr(y), 2) == -105
        assert b"outside the input range" in lib.pihyst_lib_status_text(-105)
        assert lib.pihyst_lib_compensate(h, _ptr(u), _ptr(y), None, 2) == -103
        assert lib.pihyst_lib_get_state(h, _ptr(y), 2) == -104
        assert lib.pihyst_lib_compensator_start(h, 10.0, 5.0, 0.0, 7.0) < 0  # limits crossed
    finally:
        lib.pihyst_lib_free(h)
    status = ctypes.c_int32(0)
    bad = tmp_path / "bad.pihyst"
    for text in ("", "pihyst-flat 3\n0 1\n", "pihyst-flat 1\n0 1\n0 0 150\n150 0.8 1.2 0.5\n0\n",
                 flat_text(MODELS["classical"]).replace("0.2", "nan")):
        bad.write_text(text)
        assert lib.pihyst_lib_load(str(bad).encode(), ctypes.byref(status)) is None
        assert status.value == -102
    assert lib.pihyst_lib_load(str(tmp_path / "missing").encode(), ctypes.byref(status)) is None
    assert status.value == -101
    negative = MODELS["classical"].replace(weights=[0.2, -0.05, 0.03, 0.01])
    h = _create(lib, negative)
    try:
        assert lib.pihyst_lib_compensator_start(h, np.nan, np.nan, 0.0, 0.0) == -10
    finally:
        lib.pihyst_lib_free(h)


# ---------------------------------------------------------------- the command
def test_export_command_writes_header_and_flat_file(tmp_path, capsys):
    model_path = tmp_path / "m.json"
    MODELS["multislope"].save(model_path)
    assert main(["export", str(model_path), "--c", "-o", str(tmp_path / "stage-x.h")]) == 0
    text = (tmp_path / "stage-x.h").read_text()
    assert "stage_x_init(pihyst_model *m)" in text and "PIHYST_MULTISLOPE" in text
    assert main(["export", str(model_path), "--c", "--float", "--name", "ax1",
                 "-o", str(tmp_path / "a.h")]) == 0
    assert "pihyst_model_init_f32" in (tmp_path / "a.h").read_text()
    assert main(["export", str(model_path), "--flat", "-o", str(tmp_path / "m.pihyst")]) == 0
    assert (tmp_path / "m.pihyst").read_text() == flat_text(MODELS["multislope"])


@pytest.mark.parametrize("extra, message", [
    (["--flat", "--float"], "--float and --name go with --c"),
    (["--c", "--name", "2bad-name"], "not a C identifier"),
    (["--c", "--name", "_Stage"], "not a C identifier"),       # reserved in C
    # the core's namespace: pihyst_model_init, pihyst_params, ... would be redefined
    (["--c", "--name", "pihyst_model"], "--name pihyst_model: names starting with 'pihyst' "
                                        "are the C core's"),
    (["--c", "--name", "PIHYST"], "names starting with 'pihyst' are the C core's"),
])
def test_export_command_errors(tmp_path, capsys, extra, message):
    model_path = tmp_path / "m.json"
    MODELS["classical"].save(model_path)
    out = tmp_path / "out.h"
    assert main(["export", str(model_path), *extra, "-o", str(out)]) == 2
    assert message in capsys.readouterr().err and not out.exists()


@pytest.mark.parametrize("file_name, extra, message", [
    # the name from the file: pihyst_model_init(pihyst_model *m) would not compile
    ("pihyst_model.h", [], "-o {out}: the prefix 'pihyst_model': names starting with "
                           "'pihyst' are the C core's"),
    ("Pihyst-X.h", [], "the prefix 'Pihyst_X': names starting with 'pihyst'"),
    # a header named like the core's is included in place of the core's
    ("pihyst.h", ["--name", "stage"], "-o {out}: the C core has a header of that name"),
    ("pihyst_creep.h", ["--name", "stage"], "the C core has a header of that name"),
])
def test_export_refuses_names_that_collide_with_the_core(tmp_path, capsys, file_name, extra,
                                                          message):
    model_path = tmp_path / "m.json"
    MODELS["classical"].save(model_path)
    out = tmp_path / file_name
    assert main(["export", str(model_path), "--c", *extra, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message.format(out=out) in err[0], err
    assert not out.exists()


def test_core_headers_are_the_ones_in_csrc():
    needs_compiler()
    headers = {p.name for p in (*CSRC.glob("*.h"), *(CSRC / "lib").glob("*.h"))}
    assert headers == set(CORE_HEADERS)


@pytest.mark.parametrize("file_name, prefix", [
    ("Ünit.h", "nit"), (".h", "h"), ("2axis.h", "model_2axis"), ("int.h", "int"),
    ("stage-x.h", "stage_x"), ("__y.h", "y"), ("é.h", "model"),
])
def test_names_from_odd_file_names_compile(tmp_path, capsys, core_objects, file_name,
                                           prefix):
    model_path = tmp_path / "m.json"
    MODELS["classical"].save(model_path)
    out = tmp_path / file_name
    assert main(["export", str(model_path), "--c", "-o", str(out)]) == 0
    assert f"as {prefix}_params" in capsys.readouterr().out
    driver = (f'#include "{file_name}"\nint main(void)\n{{\n    static pihyst_model m;\n'
              f'    static pihyst_compensator c;\n    if ({prefix}_init(&m) != PIHYST_OK) '
              f'return 1;\n    return {prefix}_compensator_init(&c, &m, 0.0, 150.0, 0.5, '
              f'0.0) != PIHYST_OK;\n}}\n')
    exe = compile_driver(tmp_path, file_name, out.read_text(), driver, core_objects)
    assert subprocess.run([str(exe)]).returncode == 0


def test_c_header_refuses_a_prefix_in_the_core_namespace():
    with pytest.raises(InvalidArgumentError, match="names starting with 'pihyst'"):
        c_header(MODELS["classical"], "pihyst")
    with pytest.raises(InvalidArgumentError, match="names starting with 'pihyst'"):
        c_header(pihyst.BoucWenModel(beta=1.0, gamma=0.5, n=1.0, hysteretic=1.0,
                                     linear=1.0), "pihyst_bw")


def test_a_delayed_model_carries_its_delay_into_both_forms():
    model = MODELS["multislope"].replace(delay=3, sample_period=5e-3)
    header = c_header(model, "stage_x")
    assert "#define STAGE_X_DELAY_SAMPLES 3\n" in header
    assert "desired displacement of tick k + 3" in header and "0.005 s per tick" in header
    assert "#define STAGE_X_DELAY_SAMPLES 0\n" in c_header(MODELS["multislope"], "stage_x")
    text = flat_text(model)
    assert text.endswith("\ndelay 3\n")
    assert text[:-len("delay 3\n")] == flat_text(model.replace(delay=0))
    assert "delay" not in flat_text(MODELS["multislope"])     # old files stay as they were


def test_the_library_runs_a_delayed_model_as_firmware_does(lib, tmp_path):
    # the library loads the flat file of a delayed model (its last line is the delay);
    # fed the target d ticks ahead it gives pihyst.compensate's voltages, and its
    # prediction is the model's d ticks early
    d = 3
    model = MODELS["classical"].replace(delay=d)
    path = tmp_path / "m.pihyst"
    path.write_text(flat_text(model))
    assert path.read_text().splitlines()[-1] == f"delay {d}"
    status = ctypes.c_int32(1)
    h = lib.pihyst_lib_load(str(path).encode(), ctypes.byref(status))
    assert status.value == 0, lib.pihyst_lib_status_text(status.value)
    try:
        u, yd = export_signals(model)
        y = np.empty_like(u)
        assert lib.pihyst_lib_predict(h, _ptr(u), _ptr(y), u.size) == 0
        np.testing.assert_allclose(y[:-d], model.predict(u)[d:], rtol=0, atol=1e-12)
        assert lib.pihyst_lib_reset(h, None, 0) == 0
        assert lib.pihyst_lib_compensator_start(h, np.nan, np.nan, 0.0, 0.0) == 0
        ahead = np.ascontiguousarray(yd[d:])
        volts = np.empty_like(ahead)
        flags = np.empty(ahead.size, dtype=np.uint8)
        lib.pihyst_lib_compensate(h, _ptr(ahead), _ptr(volts), _ptr(flags, ctypes.c_uint8),
                                  ahead.size)
    finally:
        lib.pihyst_lib_free(h)
    ref = pihyst.compensate(model, yd, initial_voltage=0.0)
    np.testing.assert_allclose(volts, ref.voltage[:-d], rtol=0, atol=1e-12)
