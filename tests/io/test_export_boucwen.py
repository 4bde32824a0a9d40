"""Export of Bouc-Wen models: the generated C header compiles with the core's
pihyst_boucwen.c under the firmware flags and reproduces predict and compensate (double to
1e-12, float to the tolerance of docs/export.md); the shared library loads the flat file
(family 3) and does the same through ctypes; the command writes both."""

import ctypes

import numpy as np
import pytest
from c_export import compile_core, compile_driver, export_signals, run_driver, shared_library

from pihyst.cli import main
from pihyst.inverse import BoucWenCompensator
from pihyst.io._export import c_header, flat_text
from pihyst.model import BoucWenModel

MODELS = {
    "remanent": BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0, offset=0.3),
    "gamma-negative": BoucWenModel(beta=4.0, gamma=-2.0, n=1.5, hysteretic=5.0, linear=10.0,
                                   quadratic=3.0, input_range=(-20.0, 120.0)),
    "stiff": BoucWenModel(beta=60.0, gamma=20.0, n=2.5, hysteretic=2.0, linear=25.0,
                          quadratic=-4.0, offset=-1.0),
}

DRIVER = r"""
#include <stdio.h>
#include <math.h>
#include "{header}"
/* stdin: n, n voltages, n desired outputs; stdout: n predictions, then n voltages */
int main(void)
{{
    static {real} u[4096], yd[4096];
    pihyst_bw_model{sfx} m;
    pihyst_bw_compensator{sfx} c;
    int n, t;
    if (scanf("%d", &n) != 1 || n > 4096) return 3;
    for (t = 0; t < n; ++t) {{ double v; if (scanf("%lf", &v) != 1) return 3; u[t] = ({real})v; }}
    for (t = 0; t < n; ++t) {{ double v; if (scanf("%lf", &v) != 1) return 3; yd[t] = ({real})v; }}
    if ({name}_init(&m) != PIHYST_OK) return 4;
    for (t = 0; t < n; ++t) printf("%.17g\n", (double)pihyst_bw_step{sfx}(&m, u[t]));
    if ({name}_init(&m) != PIHYST_OK) return 4;
    if ({name}_compensator_init(&c, &m, NAN, NAN, INFINITY, m.u_min) != PIHYST_OK) return 5;
    for (t = 0; t < n; ++t)
        printf("%.17g\n", (double)pihyst_bw_compensator_step{sfx}(&c, yd[t], 0));
    return 0;
}}
"""


def _compensated(model, yd):
    return BoucWenCompensator(model, initial_voltage=model.input_range[0]).run(yd)


@pytest.fixture(scope="module")
def core_objects(tmp_path_factory):
    """The Bouc-Wen core compiled once with the firmware flags (both precisions, plus
    pihyst_model.c for the status texts)."""
    return compile_core(tmp_path_factory, ("pihyst_boucwen.c", "pihyst_boucwen_f32.c",
                                           "pihyst_model.c"))


def _build_and_run(tmp_path, model, precision, core):
    name = "exported_bw"
    real, sfx = ("double", "") if precision == "double" else ("float", "_f32")
    exe = compile_driver(tmp_path, f"{name}.h", c_header(model, name, precision=precision),
                         DRIVER.format(header=f"{name}.h", real=real, sfx=sfx, name=name), core)
    u, yd = export_signals(model)
    values = run_driver(exe, u, yd)
    return u, yd, values[:u.size], values[u.size:]


@pytest.mark.parametrize("key", sorted(MODELS))
def test_header_reproduces_predict_and_compensate_in_double(tmp_path, key, core_objects):
    model = MODELS[key]
    u, yd, y_c, u_c = _build_and_run(tmp_path, model, "double", core_objects)
    span = np.ptp(model.input_range)
    np.testing.assert_allclose(y_c, model.twin_simulation(u).output, rtol=0,
                               atol=1e-12 * np.ptp(y_c))
    np.testing.assert_allclose(u_c, _compensated(model, yd).voltage, rtol=0, atol=1e-12 * span)


@pytest.mark.parametrize("key", sorted(MODELS))
def test_header_in_single_precision_within_its_stated_tolerance(tmp_path, key, core_objects):
    """float: outputs within 1e-5 of the output range; the voltages' outputs within 1e-4
    of it (docs/export.md)."""
    model = MODELS[key]
    u, yd, y_c, u_c = _build_and_run(tmp_path, model, "float", core_objects)
    y = model.predict(u)
    assert np.max(np.abs(y_c - y)) <= 1e-5 * np.ptp(y)
    ref = _compensated(model, yd)
    lo, hi = model.input_range
    reached = model.predict(np.clip(u_c, lo, hi))
    assert np.max(np.abs(reached - ref.displacement)) <= 1e-4 * np.ptp(y)


# ---------------------------------------------------------------- the shared library
@pytest.fixture(scope="module")
def lib():
    return shared_library()


def _ptr(a, ctype=ctypes.c_double):
    return None if a is None else a.ctypes.data_as(ctypes.POINTER(ctype))


def _params(model):
    return np.array([model.beta, model.gamma, model.n, model.hysteretic, model.linear,
                     model.quadratic, model.offset, *model.input_range, *model.initial_state])


@pytest.mark.parametrize("key", sorted(MODELS))
def test_shared_library_reproduces_predict_and_compensate(lib, key, tmp_path):
    model = MODELS[key]
    u, yd = export_signals(model)
    for source in ("arrays", "file"):
        status = ctypes.c_int32(1)
        if source == "arrays":
            params = _params(model)
            h = lib.pihyst_lib_create_boucwen(_ptr(params), ctypes.byref(status))
        else:
            path = tmp_path / "m.pihyst"
            path.write_text(flat_text(model))
            h = lib.pihyst_lib_load(str(path).encode(), ctypes.byref(status))
        assert status.value == 0, lib.pihyst_lib_status_text(status.value)
        try:
            assert lib.pihyst_lib_n_operators(h) == 1
            y = np.empty_like(u)
            assert lib.pihyst_lib_predict(h, _ptr(u), _ptr(y), u.size) == 0
            state = np.empty(2)
            assert lib.pihyst_lib_get_state(h, _ptr(state), 2) == 0
            assert lib.pihyst_lib_reset(h, None, 0) == 0
            assert lib.pihyst_lib_compensator_start(h, np.nan, np.nan, 0.0,
                                                    model.input_range[0]) == 0
            volts = np.empty_like(yd)
            flags = np.empty(yd.size, dtype=np.uint8)
            n_flagged = lib.pihyst_lib_compensate(h, _ptr(yd), _ptr(volts),
                                                  _ptr(flags, ctypes.c_uint8), yd.size)
        finally:
            lib.pihyst_lib_free(h)
        ref_run = model.simulate(u)
        np.testing.assert_allclose(y, ref_run.output, rtol=0, atol=1e-12 * np.ptp(y))
        np.testing.assert_allclose(state, ref_run.final_state, rtol=0, atol=1e-12)
        ref = _compensated(model, yd)
        np.testing.assert_allclose(volts, ref.voltage, rtol=0,
                                   atol=1e-12 * np.ptp(model.input_range))
        assert n_flagged == int(np.count_nonzero(flags)) == int(np.count_nonzero(ref.flags))


def test_shared_library_refuses_bad_bouc_wen_input(lib, tmp_path):
    status = ctypes.c_int32(0)
    params = _params(MODELS["remanent"])
    h = lib.pihyst_lib_create_boucwen(_ptr(params), ctypes.byref(status))
    try:
        u = np.array([0.0, 200.0])
        y = np.zeros(2)
        assert lib.pihyst_lib_predict(h, _ptr(u), _ptr(y), 2) == -105
        assert lib.pihyst_lib_get_state(h, _ptr(y), 1) == -104
        assert lib.pihyst_lib_reset(h, _ptr(np.array([0.0, 5.0])), 2) == -9    # z beyond z_max
        assert lib.pihyst_lib_compensator_start(h, 10.0, 5.0, 0.0, 7.0) == -11  # crossed
    finally:
        lib.pihyst_lib_free(h)
    params[1] = 9.0                                                            # gamma >= beta
    assert lib.pihyst_lib_create_boucwen(_ptr(params), ctypes.byref(status)) is None
    assert status.value == -5
    bad = tmp_path / "bad.pihyst"
    for text in ("pihyst-flat 1\n3 2\n0 0 150\n5 1 1\n-8 40 0\n0 0\n",           # K != 1
                 "pihyst-flat 1\n3 1\n0 0 150\n5 1 1\n-8 40 0\n0\n",             # cut short
                 flat_text(MODELS["remanent"]).replace("-8.0", "nan")):
        bad.write_text(text)
        assert lib.pihyst_lib_load(str(bad).encode(), ctypes.byref(status)) is None
        assert status.value == -102
    non_monotone = MODELS["remanent"].replace(linear=10.0)
    h = lib.pihyst_lib_create_boucwen(_ptr(_params(non_monotone)), ctypes.byref(status))
    try:
        assert lib.pihyst_lib_compensator_start(h, np.nan, np.nan, 0.0, 0.0) == -10
    finally:
        lib.pihyst_lib_free(h)


# ---------------------------------------------------------------- the command
def test_export_command_writes_bouc_wen_header_and_flat_file(tmp_path, capsys):
    model = MODELS["gamma-negative"]
    model_path = tmp_path / "bw.json"
    model.save(model_path)
    assert main(["export", str(model_path), "--c", "-o", str(tmp_path / "stage-y.h")]) == 0
    text = (tmp_path / "stage-y.h").read_text()
    assert "stage_y_init(pihyst_bw_model *m)" in text and '#include "pihyst_boucwen.h"' in text
    assert main(["export", str(model_path), "--c", "--float", "-o", str(tmp_path / "a.h")]) == 0
    assert "pihyst_bw_init_f32" in (tmp_path / "a.h").read_text()
    assert main(["export", str(model_path), "--flat", "-o", str(tmp_path / "m.pihyst")]) == 0
    assert (tmp_path / "m.pihyst").read_text() == flat_text(model)
    assert "bouc-wen model, state (u, z)" in capsys.readouterr().out


def test_a_delayed_bouc_wen_model_exports_its_delay():
    model = MODELS["remanent"].replace(delay=4)
    text = c_header(model, "ax")
    assert "#define AX_DELAY_SAMPLES 4" in text and "tick k + 4" in text
    assert flat_text(model).endswith("delay 4\n")
    assert "#define AX_DELAY_SAMPLES 0" in c_header(MODELS["remanent"], "ax")
