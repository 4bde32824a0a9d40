"""``--float`` export of a model with creep (docs/export.md): the single-precision
header's lags (``pihyst_creep_f32``, the deviation form (C2')-(C5') of pihyst_creep.h)
compile with the core's ``_f32`` files under the firmware flags (PI models, and Bouc-Wen
models through ``pihyst_bw_creep_compensator_step_f32``), and a firmware loop on
floats follows ``predict`` and ``compensate`` of the double model on many signals, within
a bound derived from the float arithmetic (:func:`lag_rounding_bound`) and checked sample
by sample; lags floats cannot hold are refused in one line.

The bound. The float loop's output with creep differs from the double model's by
  (a) the hysteresis part: |H_f - H| (the ``--float`` tolerance of the models without
      creep, 1e-5 of the output range, checked here too). The lags are a convex
      average of past H: y = (1 - sum g) H + sum g_i z_i with z_i a convex combination
      of H's, so an error of at most D in every past H moves y by at most D;
  (b) the lags' own float arithmetic, accumulated per lag with its decay (1 - alpha_i):
      per step (C2') rounds dh, x and alpha x and e (at most 2 eps (|dh| + |x|)), and
      alpha_i itself is off by a few roundings (dt, tau as floats, the division and
      expm1f: at most 4 eps alpha_i relative), which adds 4 eps alpha_i |x|; the gains
      as floats and the sum (C3') add (n + 1) eps sum g_i |e_i| + eps |y|.
The compensator: the float compensator meets its hysteresis target H* to 4 tol_f32
(docs/c-core.md (C); Bouc-Wen: tol = 4 eps (|H*| + scale), docs/c-core.md), and (C5')
and (C3') round by at most 8 eps (|y_d| + |H| + sum g_i |e_i|); the double model with
creep run on the float loop's voltages then meets y_d to that plus (a) and (b) at those
voltages.
"""

import re
import subprocess

import numpy as np
import pytest
from c_export import compile_core, compile_driver, export_signals

import pihyst
from pihyst.cli import main
from pihyst.exceptions import InvalidModelError
from pihyst.io._export import c_header
from pihyst.model import BoucWenModel, Creep

EPS = float(np.finfo(np.float32).eps)

KP_LIKE = pihyst.PiecewiseLinearPI(
    [([0, 40, 60, 150], [0, 0, 1, 1]), ([0, 90, 110, 150], [0, 0, 1, 1]),
     ([0, 150], [-5, 145])],
    [([0, 10, 30, 150], [0, 0, 1, 1]), ([0, 60, 80, 150], [0, 0, 1, 1]),
     ([0, 150], [5, 155])],
    [6.0, 4.0, 0.2], offset=-1.5, initial_state=[0.0, 0.0, 5.0],
    creep=Creep([0.05, 0.5], [0.1, 0.05], dt=0.002))
MODELS = {
    "classical": pihyst.ClassicalPI([0, 10, 30, 60], [0.2, 0.05, 0.03, 0.01], offset=0.7,
                                    initial_state=[0, 10, 30, 60],
                                    creep=Creep([0.3, 3.0, 30.0], [0.02, 0.035, 0.015],
                                                dt=0.01)),
    "multislope": pihyst.MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028], b=1.25,
                                      creep=Creep([1.0], [0.04], dt=0.05)),
    "pwl": KP_LIKE,
    # P-885-like: an output far from 0 (-120 um) and lags up to 1000 s at 200 Hz
    # (alpha = 5e-6), where (C2) in floats would stop short of H by up to 0.8 um
    "slow-lags-offset": pihyst.ClassicalPI(
        [0, 15, 40, 80, 120], [0.5, 0.2, 0.1, 0.05, 0.05], offset=-120.0,
        creep=Creep([0.1, 10.0, 1000.0], [0.03, 0.04, 0.05], dt=0.005)),
    "bouc-wen": BoucWenModel(beta=4.0, gamma=-2.0, n=1.5, hysteretic=5.0, linear=10.0,
                             quadratic=3.0, input_range=(-20.0, 120.0),
                             creep=Creep([0.3, 3.0, 30.0], [0.02, 0.035, 0.015], dt=0.01)),
    "bouc-wen-n1": BoucWenModel(beta=5.0, gamma=1.0, n=1.0, hysteretic=-8.0, linear=40.0,
                                offset=0.3, input_range=(0.0, 150.0),
                                creep=Creep([0.1, 10.0, 1000.0], [0.03, 0.04, 0.05],
                                            dt=0.005)),
}

DRIVER = r"""
#include <stdio.h>
#include <math.h>
#include "{header}"
/* stdin: n, n voltages, n desired outputs. stdout: per voltage the hysteresis output and
 * the output with creep (the model loop of the header's comment); the compensator's
 * tolerance (Bouc-Wen: its output scale) and its output at u_initial; per desired
 * output the voltage, the hysteresis output reached, the output with creep and the
 * flags (the compensator loop). All in single precision. */
int main(void)
{{
    static float u[8192], yd[8192];
    pihyst_{kind}model_f32 m;
    pihyst_{kind}compensator_f32 c;
    pihyst_creep_f32 cr;
    int n, t;
    if (scanf("%d", &n) != 1 || n > 8192) return 3;
    for (t = 0; t < n; ++t) {{ double v; if (scanf("%lf", &v) != 1) return 3; u[t] = (float)v; }}
    for (t = 0; t < n; ++t) {{ double v; if (scanf("%lf", &v) != 1) return 3; yd[t] = (float)v; }}
    if ({name}_init(&m) != PIHYST_OK) return 4;
    if ({name}_creep_init(&cr, {NAME}_INITIAL_OUTPUT) != PIHYST_CREEP_OK) return 6;
    for (t = 0; t < n; ++t) {{
        const float h = pihyst_{step}_f32(&m, u[t]);
        printf("%.9g %.9g\n", (double)h, (double)pihyst_creep_step_f32(&cr, h));
    }}
    if ({name}_init(&m) != PIHYST_OK) return 4;
    if ({name}_compensator_init(&c, &m, NAN, NAN, INFINITY, m.u_min) != PIHYST_OK) return 5;
    if ({name}_creep_init(&cr, c.y_last) != PIHYST_CREEP_OK) return 6;
    printf("%.9g %.9g\n", (double)c.{tol}, (double)c.y_last);
    for (t = 0; t < n; ++t) {{
        pihyst_flags flags = 0;
        float y;
        const float volts = pihyst_{kind}creep_compensator_step_f32(&cr, &c, -1.0f, yd[t], &y,
                                                                     &flags);
        printf("%.9g %.9g %.9g %d\n", (double)volts, (double)c.y_last, (double)y, (int)flags);
    }}
    return 0;
}}
"""


def lag_rounding_bound(creep, h, h0):
    """Per sample, the most the _f32 lags' arithmetic can add to the output with creep
    for hysteresis outputs ``h`` from lags at rest at ``h0`` ((b) of the module
    docstring), evaluated on the double trajectory."""
    alpha = -np.expm1(-creep.dt / creep.tau)
    g = creep.gain
    e = np.zeros(creep.n_lags)
    b = np.zeros(creep.n_lags)
    out = np.empty(len(h))
    prev = h0
    for t, ht in enumerate(np.asarray(h, dtype=float)):
        dh = ht - prev
        prev = ht
        x = e - dh
        e = x - alpha * x
        b = (1 - alpha) * b + 2 * EPS * (abs(dh) + np.abs(x)) + 4 * EPS * alpha * np.abs(x)
        out[t] = g @ b + EPS * (creep.n_lags + 1) * (g @ np.abs(e)) + EPS * abs(ht + g @ e)
    return out, e


def _ratio(err, bound):
    """The largest err / bound (0 / 0 counts 0)."""
    return float(np.max(err / np.maximum(bound, np.finfo(float).tiny)))


def _as_float(values):
    return np.asarray(values, dtype=np.float32).astype(float)


@pytest.fixture(scope="module")
def core_objects(tmp_path_factory):
    """The single-precision core with its lags, compiled once with the firmware flags."""
    return compile_core(tmp_path_factory, ("pihyst_model_f32.c", "pihyst_inverse_f32.c",
                                           "pihyst_creep_f32.c", "pihyst_boucwen_f32.c",
                                           "pihyst_bw_creep_f32.c"))


def _signals(model):
    """export_signals for four seeds, and a jump to each end of the range held for
    long (the lags settling: the slow lags' case)."""
    out = [export_signals(model, n=1500, seed=seed) for seed in range(1, 5)]
    lo, hi = model.input_range
    u = np.r_[np.full(200, lo), np.full(3000, hi), np.full(3000, lo + 0.3 * (hi - lo))]
    out.append((u, model.predict(u)))
    return out


def _run(exe, u, yd):
    stdin = "\n".join(f"{v!r}" for v in [u.size, *u.tolist(), *yd.tolist()]) + "\n"
    text = subprocess.run([str(exe)], input=stdin, check=True, capture_output=True,
                          text=True).stdout.split()
    values = np.array(text, dtype=float)
    forward = values[:2 * u.size].reshape(-1, 2)
    tol, h_start = values[2 * u.size:2 * u.size + 2]
    loop = values[2 * u.size + 2:].reshape(-1, 4)
    return forward[:, 0], forward[:, 1], (tol, h_start), loop[:, 0], loop[:, 1], \
        loop[:, 2], loop[:, 3].astype(np.uint8)


@pytest.mark.parametrize("family", sorted(MODELS))
def test_float_header_follows_predict_and_compensate_with_creep(tmp_path, family,
                                                                core_objects):
    model = MODELS[family]
    name = "exported_" + family.replace("-", "_")
    bw = model.family == "bouc-wen"
    exe = compile_driver(tmp_path, "exported.h", c_header(model, name, precision="float"),
                         DRIVER.format(header="exported.h", name=name, NAME=name.upper(),
                                       kind="bw_" if bw else "", tol="scale" if bw else "tol",
                                       step="bw_step" if bw else "model_step"),
                         core_objects)
    hysteresis = model.replace(creep=None)
    lo, hi = model.input_range
    h0 = (model.output(*model.initial_state) if bw
          else model.hysteresis_output(model.initial_state))
    worst = {"forward": 0.0, "compensator": 0.0}
    for u, yd in _signals(model):
        u, yd = _as_float(u), _as_float(yd)
        h_f, y_f, (tol, h_start), volts, h_c, y_c, flags = _run(exe, u, yd)
        span = np.ptp(hysteresis.predict(u))
        # the model: (a) the hysteresis part within the --float tolerance, then (a) + (b)
        h = hysteresis.predict(u)
        d = np.maximum.accumulate(np.r_[abs(np.float32(h0) - h0), np.abs(h_f - h)])[1:]
        assert d[-1] <= 1e-5 * span
        bound, _ = lag_rounding_bound(model.creep, h, h0)
        y = model.predict(u)
        err = np.abs(y_f - y)
        assert np.all(err <= d + bound), (np.max(err - d - bound), family)
        worst["forward"] = max(worst["forward"], _ratio(err, d + bound))
        # creep is in the loop: without it the outputs differ by far more than the bound
        assert np.max(np.abs(y - h)) > 100 * np.max(d + bound)
        # the compensator: voltages inside the limits; the double model with creep on the
        # float loop's voltages meets the desired values wherever the loop flagged none
        assert np.all((volts >= lo) & (volts <= hi))
        # the loop's lags start at rest at the output of u_initial = lo, as compensate's
        h_lo = float(hysteresis.predict([lo])[0])
        h_true = hysteresis.predict(volts)
        d_c = np.maximum.accumulate(np.r_[abs(h_start - h_lo), np.abs(h_c - h_true)])[1:]
        assert d_c[-1] <= 1e-5 * span
        bound_c, _ = lag_rounding_bound(model.creep, h_true, h_lo)
        y_true = model.predict(volts, creep_state=np.full(model.creep.n_lags, h_lo))
        if bw:      # the Bouc-Wen compensator's tolerance from its scale
            tol = 4 * EPS * (np.abs(h_c) + tol)
        met = 4 * tol + 8 * EPS * (np.abs(yd) + np.abs(h_c) + np.abs(y_c - h_c))
        assert np.all(np.abs(y_c - y_true) <= d_c + bound_c)
        ok = flags == 0
        err_c = np.abs(y_true - yd)
        assert np.all(err_c[ok] <= (met + d_c + bound_c)[ok]), family
        worst["compensator"] = max(worst["compensator"],
                                   _ratio(err_c[ok], (met + d_c + bound_c)[ok]))
        # pihyst.compensate in double: the same flags but where y_d is within the bound
        # of the end of reach, and the same voltage where both saturate
        ref = pihyst.compensate(model, yd, initial_voltage=lo)
        borderline = np.abs(ref.displacement - yd) <= 2 * (met + d_c + bound_c)
        differ = flags != ref.flags
        assert np.all(borderline[differ]), family
        both = (flags == ref.flags) & (flags != 0)
        np.testing.assert_array_equal(volts[both], ref.voltage[both])
        assert np.count_nonzero(ok) > 0.5 * u.size
    # measured against the bound (docs/export.md quotes these)
    print(f"{family}: worst error / bound: model {worst['forward']:.3g}, "
          f"compensator {worst['compensator']:.3g}")


def test_float_header_holds_the_creep_parameters_as_floats():
    model = MODELS["classical"]
    text = c_header(model, "stage_x", precision="float")
    assert "#define STAGE_X_CREEP_DT 0.01f\n" in text
    initial = re.search(r"#define STAGE_X_INITIAL_OUTPUT (\S+)f\n", text).group(1)
    assert np.float32(initial) == np.float32(model.hysteresis_output(model.initial_state))
    assert "static const float stage_x_creep_tau[3] = {\n    0.3f, 3.0f, 30.0f\n};" in text
    assert "static const float stage_x_creep_gain[3] = {\n    0.02f, 0.035f, 0.015f\n};" in text
    assert "static float stage_x_creep_alpha[STAGE_X_CREEP_LAGS];" in text
    assert "stage_x_creep_init(pihyst_creep_f32 *cr, float h_settled)" in text
    assert "pihyst_creep_init_f32(cr, STAGE_X_CREEP_LAGS" in text
    assert "pihyst_creep_compensator_step_f32(&cr, &c, -1.0f, y_desired, &y, &flags)" in text
    assert "csrc/pihyst_creep_f32.c" in text and "double" not in text


@pytest.mark.parametrize("creep, message", [
    # pihyst_creep_init_f32 sums the gains in float: 0.5 + (0.5 - 1e-9) is 1.0f
    (Creep([1.0, 2.0], [0.5, 0.5 - 1e-9], dt=0.01), "sum to 1.0 in single precision"),
    (Creep([1e-50, 2.0], [0.1, 0.1], dt=0.01), "creep.tau[0] = 1e-50 is 0"),
    (Creep([1e39, 2.0], [0.1, 0.1], dt=0.01), "creep.tau[0] = 1e+39 is 0 or infinite"),
    (Creep([1.0, 2.0], [0.1, 0.1], dt=1e39), "creep.dt = 1e+39 is beyond the range of float"),
])
def test_lags_floats_cannot_hold_are_refused_in_one_line(creep, message):
    model = MODELS["classical"].replace(creep=creep)
    with pytest.raises(InvalidModelError, match="--float cannot hold") as err:
        c_header(model, "ax", precision="float")
    assert message in str(err.value) and "\n" not in str(err.value)
    assert "pihyst_creep_init(" in c_header(model, "ax")          # double holds them


def test_export_command_writes_a_float_header_with_creep(tmp_path, capsys):
    model = MODELS["slow-lags-offset"]
    path = tmp_path / "m.json"
    model.save(path)
    out = tmp_path / "stage.h"
    assert main(["export", str(path), "--c", "--float", "-o", str(out)]) == 0
    assert out.read_text() == c_header(model, "stage", precision="float", source="m.json")
    assert "3 creep lags at 0.005 s as stage_params (float)" in capsys.readouterr().out
    bad = model.replace(creep=Creep([1.0, 2.0], [0.5, 0.5 - 1e-9], dt=0.01))
    bad.save(path)
    out = tmp_path / "bad.h"
    assert main(["export", str(path), "--c", "--float", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--float cannot hold" in err and len(err.splitlines()) == 1
    assert "Traceback" not in err and not out.exists()
