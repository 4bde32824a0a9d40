"""The sources of the figures quoted in README.md and docs/ (docs/figures.toml names
them; tools/check_figures.py checks the text against them).

Each source computes its figures with the current code and returns them as a nested
dict; a placeholder ``{a.b}`` of a quote names ``values["a"]["b"]``. Quick sources take
a few seconds at most and run in the quick tests; slow ones (the demo's study, fits of
the measured sets and of the simulated beams' records, the learning benchmark's stages)
in the slow tests and under ``check_figures.py --all``; script-only ones
(``script``: minutes each, the learning benchmark's fresh stages) under
``check_figures.py --all`` alone. Sources that need the
measured data sets (``data``) are skipped, saying why, without them.
"""

import json
from dataclasses import dataclass
from typing import Callable

import numpy as np

SOURCES = {}


@dataclass
class Source:
    name: str
    compute: Callable
    slow: bool
    doc: str
    data: bool = False        # needs the measured data sets (skipped, saying why, without)
    script: bool = False      # minutes: run by tools/check_figures.py --all only, not the tests

    def available_from(self, options):
        """Whether the figures can be had quickly from a file named in ``options``."""
        return self.name == "demo" and bool(options.get("demo_metrics"))

    def values(self, options):
        return self.compute(options)


def source(slow=False, data=False, script=False):
    def register(fn):
        SOURCES[fn.__name__] = Source(fn.__name__, fn, slow or script,
                                      (fn.__doc__ or "").strip(), data, script)
        return fn
    return register


def _triangle():
    """The paper's drive as the README's example builds it: 0 -> 150 -> 0 V, 1 V steps."""
    return np.r_[np.arange(0, 151), np.arange(149, -1, -1)].astype(float)


@source()
def paper_models(options):
    """The paper's Table 1 models (examples/paper_table1_*.json) on its triangle from the
    zero state: the displacement at 150 V and back at 0 V."""
    import pihyst

    u = _triangle()
    out = {}
    for key in ("classical", "multislope"):
        model = pihyst.load_model(f"{_repo()}/examples/paper_table1_{key}.json")
        y = model.predict(u)
        out[key] = {"peak": float(y[150]), "end": float(y[-1]),
                    "thresholds": [float(r) for r in model.thresholds],
                    "weights": [float(w) for w in model.weights]}
    c = out["classical"]
    # what the r = 10 and r = 30 operators hold back at 0 V: w * r, summed
    out["classical"]["held_at_zero"] = float(sum(w * r for r, w in
                                                 zip(c["thresholds"][1:3], c["weights"][1:3])))
    out["classical"]["top_weight"] = c["weights"][-1]
    from pihyst.paper import BEAM_MAX_DISPLACEMENT_UM
    out["beam_stroke"] = BEAM_MAX_DISPLACEMENT_UM
    return out


@source()
def multislope_shape(options):
    """The multislope operator of the paper's shape (U = 150, a = 0.8, b = 1.2, h = 0.5):
    the largest valid threshold, and the r = 40 operator's kinks and holds, found by
    running the operator on a fine 0 -> 150 -> 0 V grid (not from the formulas)."""
    import pihyst
    from pihyst.exceptions import InvalidModelError

    U, a, h = 150.0, 0.8, 0.5
    limit = (1 - a) * U / (1 - a * h)
    try:                                   # the code agrees: just above the limit is refused
        pihyst.MultislopePI([0.0, limit * 1.001], [1.0, 1.0])
        refused = False
    except InvalidModelError:
        refused = True
    if not refused:
        raise AssertionError("a multislope threshold above (1 - a)U/(1 - ah) was accepted")
    step = 0.01
    up = np.arange(0.0, U + step / 2, step)
    n = up.size
    u = np.r_[up, up[-2::-1]]
    y = pihyst.MultislopePI([40.0], [1.0]).predict(u)
    slope = np.round(np.diff(y) / np.diff(u), 6)     # slope[i]: from u[i] to u[i + 1]
    changes = [i for i in range(1, slope.size) if slope[i] != slope[i - 1]]
    rising = [float(u[i]) for i in changes if i < n - 1 and u[i] > 40.0]
    falling = [float(u[i]) for i in changes if i > n - 1]
    # the hold after a reversal at M = 100 V: the voltage drop before the output moves
    top = 100.0
    up_m = np.arange(0.0, top + step / 2, step)
    u_m = np.r_[up_m, up_m[-2::-1]]
    y_m = pihyst.MultislopePI([40.0], [1.0]).predict(u_m)
    m = up_m.size
    moved = np.flatnonzero(np.abs(y_m[m:] - y_m[m - 1]) > 1e-9)[0]
    r0 = pihyst.MultislopePI([0.0], [1.0])
    rise0, fall0 = (float(np.ravel(e)[0]) for e in r0.envelopes(75.0)[:2])
    return {"limit_V": limit,
            "r0_at_75": {"R": rise0, "F": fall0},
            "r40": {"rising_kink_V": rising[0], "hold_end_V": falling[0],
                    "falling_kink_V": falling[1], "top": float(y[n - 1]),
                    "end": float(y[-1]),
                    "hold_after_100_V": float(top - u_m[m + moved - 1])}}


@source()
def paper_beam(options):
    """The simulated paper-beam (seed 0) on the paper's 0-150-0 V, 300 s triangle: its
    displacement at 150 V and back at 0 V, and the loop's largest width (falling minus
    rising branch at the same voltage) in % of the range."""
    from pihyst.sim import make_plant
    from pihyst.sim.signals import triangle

    t, u = triangle(u_max=150.0, dt=0.5)
    y = make_plant("paper-beam", seed=0).run(u, t)
    top = int(np.argmax(u))
    grid = np.arange(0.0, 151.0)
    rising = np.interp(grid, u[:top + 1], y[:top + 1])
    falling = np.interp(grid, u[top:][::-1], y[top:][::-1])
    return {"peak_um": float(y[top]), "end_um": float(y[-1]),
            "width_pct": float(100 * np.max(falling - rising) / np.ptp(y))}


@source()
def constants(options):
    """The rules' constants as the code holds them (the choice's tolerance, the delay
    rule, the subset search, the command line's range slack and reach rule) and the
    simulated beams' parameters (creep per time decade, smallest and largest over the
    beams; sensor noise; supply step; the beam's mode), in the units the text quotes."""
    from pihyst.cli import frames, model_inputs
    from pihyst.identify import _constants, _delay, _options, _subsets
    from pihyst.sim import PLANT_NAMES, _plant, make_plant

    creep = [100 * make_plant(name).creep_per_decade for name in PLANT_NAMES]
    import pihyst
    ms, cl = pihyst.MultislopePI([0.0], [1.0]), pihyst.ClassicalPI([0.0], [1.0])
    return {"multislope": {"U": ms.U, "a": ms.a, "b": ms.b, "h": ms.h},
            "input_range": list(cl.input_range),"choice_pct": 100 * _constants.TOLERANCE,
            "delay": {"adopt_pct": 100 * _constants.ADOPT_GAIN,
                      "max_pct_of_cycle": 100 * _constants.DELAY_MAX_FRACTION,
                      "max_samples": _delay.MAX_SAMPLES},
            "reversal_pct": 100 * _constants.REVERSAL_TOLERANCE,
            "major_pct": 100 * _constants.MAJOR_TOLERANCE,
            "path_max_exhaustive": _subsets.PATH_MAX_EXHAUSTIVE,
            "refine_reach": _constants.REFINE_REACH,
            "creep_reach": _constants.CREEP_REACH,
            "size_pct": 100 * _constants.SIZE_TOLERANCE,
            "kp_undetermined_pct": 100 * _constants.KP_UNDETERMINED_TOLERANCE,
            "n_candidates": _options.DEFAULT_N_CANDIDATES,
            "max_exhaustive": _subsets.DEFAULT_MAX_EXHAUSTIVE,
            "rest_pct": 100 * _constants.REST_TOLERANCE,
            "weak_explained_pct": 100 * _constants.WEAK_EXPLAINED,
            "min_loop_width_pct": 100 * _constants.MIN_LOOP_WIDTH,
            "range_slack_pct": 100 * model_inputs.TOLERANCE,
            "out_of_reach_pct": 100 * frames.MAX_OUT_OF_REACH,
            "beams": {"creep_pct_per_decade": {"min": min(creep), "max": max(creep)},
                      "creep": {name.replace("-", "_"): c for name, c in zip(PLANT_NAMES, creep)},
                      "paper_beam_creep_pct_per_decade":
                          100 * make_plant("paper-beam").creep_per_decade,
                      "noise_um": _plant.NOISE_UM, "supply_step_mV": 1e3 * _plant.SUPPLY_STEP_V,
                      "mode_hz": _plant.BEAM_RESONANCE_HZ, "damping": _plant.BEAM_DAMPING},
            "stage": _stage_defaults()}


def _stage_defaults():
    """pihyst.sim.make_stage's defaults: its mode (Hz, damping in %), delay (ticks),
    clock (kHz) and sensor noise (µm)."""
    import inspect

    from pihyst.sim import make_stage

    d = {k: p.default for k, p in inspect.signature(make_stage).parameters.items()}
    (hz, zeta), = d["modes"]
    return {"mode_hz": hz, "damping_pct": 100 * zeta, "delay_ticks": d["delay_samples"],
            "clock_khz": d["rate_hz"] / 1e3, "noise_um": d["noise_um"]}


@source()
def link_budget(options):
    """The rig's link budget as benchmarks/bench_rig.py measures it (its configuration):
    per supply baud rate (19 200, 115 200) with and without a readback every tick, the
    bytes per tick, their time on the wire (8N1, the sensor at 115 200 baud), the busy
    time per tick through the emulated instruments in virtual time (every tick overruns,
    so it is the shortest period) and the highest tick rate it allows."""
    from pihyst.rig import Rig, VoltageProgram

    bench = _benchmark("bench_rig")
    out = {}
    for baud in (19200, 115200):
        for readback in (True, False):
            with Rig(bench.config(baud, 1000.0, readback)) as rig:
                result = rig.run(VoltageProgram(np.linspace(0.0, 100.0, 200)),
                                 handle_signals=False)
            busy = float(np.mean(result.column("busy_s", "run")))
            supply_bytes = 13 + 8 + ((8 + 9) if readback else 0)
            sensor_bytes = 6 + 17
            wire = supply_bytes * 10 / baud + sensor_bytes * 10 / 115200
            out[f"b{baud}_{'readback' if readback else 'plain'}"] = {
                "bytes": supply_bytes + sensor_bytes, "wire_ms": 1e3 * wire,
                "busy_ms": 1e3 * busy, "max_rate_hz": 1 / busy}
    return out


def _benchmark(name):
    """The module benchmarks/NAME.py (its functions and constants)."""
    import importlib
    import sys

    path = str(_repo() / "benchmarks")
    sys.path.insert(0, path)
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(path)


@source()
def rig_example(options):
    """The rig example the README and docs/rig.md run: examples/rig/emulated.toml's tick
    rate and examples/rig/desired_triangle.csv's peak and duration."""
    from pihyst.rig import load_config

    cfg = load_config(str(_repo() / "examples" / "rig" / "emulated.toml"))
    t, y = np.genfromtxt(_repo() / "examples" / "rig" / "desired_triangle.csv", delimiter=",",
                         skip_header=2, unpack=True)
    return {"rate_hz": cfg.rig.rate_hz, "peak_um": float(y.max()),
            "duration_s": float(t[-1] - t[0])}


@source()
def learning_settings(options):
    """benchmarks/bench_learn.py's settings as the README describes them: the clock (kHz),
    the sensor noise (µm), the trials, the voltage limits (V)."""
    bench = _benchmark("bench_learn")
    return {"clock_khz": bench.CLOCK_HZ / 1e3, "noise_um": bench.NOISE_UM,
            "trials": bench.TRIALS, "u_min": bench.U_MIN, "u_max": bench.U_MAX}


@source()
def simulate_defaults(options):
    """`pihyst simulate`'s option defaults, from the command line's own parser (the
    beam's top voltage, which is not an option default, from the beam)."""
    from pihyst.cli import build_parser
    from pihyst.sim import make_plant

    args = build_parser().parse_args(["simulate", "-o", "x.csv"])
    out = {k: v for k, v in vars(args).items() if isinstance(v, (int, float))
           and not isinstance(v, bool)}
    out["beam_u_max"] = make_plant(args.plant).u_max
    return out


@source()
def paper(options):
    """The paper's published numbers as pihyst records them (pihyst.paper), which the
    report prints beside its own."""
    from pihyst.paper import SUPPLY_STEP_V, published
    return published() | {"supply_step_mV": 1e3 * SUPPLY_STEP_V}


@source(slow=True)
def demo(options):
    """pihyst demo's figures (seed 0, the paper beam): its metrics.json, from the file
    given (--demo-metrics) or computed by the study itself (without the other beams,
    which no quoted figure depends on)."""
    path = options.get("demo_metrics")
    if path:
        with open(path, encoding="utf-8") as f:
            metrics = json.load(f)
    else:
        from pihyst.study import paper_study
        metrics = paper_study(seed=0, variants=False, rig=True, progress=None).metrics
    return _demo_derived(metrics)


@source(data=True)
def p885_data(options):
    """The P-885 identification record as it is (Model_Vi_Do.dat, column 5): the range of
    the sensor's absolute readings (µm)."""
    from pihyst.io import datasets

    root = datasets.data_root()
    if root is None:
        raise LookupError("the measured data sets are not here ($PIHYST_DATA or "
                          "../shared/data; make data)")
    y = np.loadtxt(root / datasets.P885_DIR / "Model_Vi_Do.dat", usecols=4)
    return {"sensor_min_um": float(y.min()), "sensor_max_um": float(y.max())}


@source(data=True)
def smart_data(options):
    """The SmartHysteresis record as it is (hysteresis_v_150_1hz.csv): when its voltage
    steps from 0 (s), the --skip-until the README and docs/records.md give (the step plus
    the second pihyst.io.datasets lets the actuator settle) and its sample rate (Hz)."""
    from pihyst.io import datasets

    a = np.genfromtxt(_data_root() / datasets.SMART_DIR / "hysteresis_v_150_1hz.csv",
                      delimiter=",", usecols=(1, 3))
    t, u = a[:, 0], a[:, 1]
    step = float(t[np.flatnonzero(u != 0)[0]])
    return {"step_s": step, "skip_until_s": step + datasets.SMART_SETTLE_S,
            "rate_hz": 1.0 / float(np.median(np.diff(t)))}


@source(slow=True, data=True)
def p885_pair(options):
    """The P-885 pair as benchmarks/bench_identify.py judges it: pihyst.fit on
    Model_Vi_Do.dat (default, and delay=0), each family's model predicting the
    uncompensated stretch of Test_Vi_Do_Di.dat with its own delay (RMS with the mean
    removed), and its held-back RMS; the sets found by pihyst.io.datasets' rule."""
    import warnings

    from pihyst import fit
    from pihyst.exceptions import PihystWarning
    from pihyst.io import datasets

    root = datasets.data_root()
    if root is None:
        raise LookupError("the measured data sets are not here ($PIHYST_DATA or "
                          "../shared/data; make data)")
    u, y = datasets.p885(root)
    ut, yt = datasets.p885_test(root)
    a, z = datasets.P885_TEST_UNCOMPENSATED
    out = {}
    for label, delay in (("default", "auto"), ("delay0", 0)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PihystWarning)
            res = fit(u, y, delay=delay)
        rep = res.report.to_dict()
        entry = {"delay": rep["data"]["delay"]["samples"], "families": {}}
        for f in res.report.families:
            e = yt[a:z] - res.models[f["family"]].predict(ut)[a:z]
            row = {"n_operators": f["n_operators"], "test": float(np.sqrt(np.mean(
                (e - e.mean()) ** 2))), "held_back": f["errors"]["held_back"]["rms"]}
            entry["families"][f["family"]] = row
            if f["chosen"]:
                entry.update(row, chosen=f["family"])
        out[label] = entry
    return out


def _data_root():
    from pihyst.io import datasets

    root = datasets.data_root()
    if root is None:
        raise LookupError("the measured data sets are not here ($PIHYST_DATA or "
                          "../shared/data; make data)")
    return root


@source(slow=True, data=True)
def measured_heldback(options):
    """The README's table of held-back RMS on the measured sets, as
    benchmarks/bench_identify.py fits them (the first cycle settles the operators, fit on
    the first half, judged on the second, no refit): the default fit, with delay=0, and
    a classical PI of 20 equally spaced thresholds in [0, S/2) with the delay the rule
    adopts and without; per set, the chosen family's operators and the delay (samples,
    and ms at the record's rate)."""
    import warnings

    from pihyst import fit
    from pihyst.exceptions import PihystWarning
    from pihyst.io import datasets

    root = _data_root()
    smart = np.genfromtxt(root / datasets.SMART_DIR / "hysteresis_v_150_1hz.csv",
                          delimiter=",", usecols=1)
    rates = {"p885": 200.0, "smart": 1.0 / float(np.median(np.diff(smart)))}
    out = {}
    for key, load in (("p885", datasets.p885), ("smart", datasets.smarthysteresis)):
        u, y = load(root)
        S = float(u.max() - u.min())
        twenty = np.arange(20) * (S / 2) / 20
        entry = {}
        for label, kw in (("default", {}), ("delay0", {"delay": 0}),
                          ("classical20", {"family": "classical", "thresholds": twenty}),
                          ("classical20_delay0", {"family": "classical",
                                                  "thresholds": twenty, "delay": 0})):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", PihystWarning)
                res = fit(u, y, initial_state="settle", holdout=0.5, refit=False, **kw)
            rep = res.report.to_dict()
            chosen = res.report.family(res.report.chosen)
            delay = rep["data"]["delay"]["samples"]
            entry[label] = {"rms": chosen["errors"]["held_back"]["rms"],
                            "n_operators": chosen["n_operators"], "delay": delay,
                            "delay_ms": 1e3 * delay / rates[key]}
        out[key] = entry
    return out


@source(slow=True)
def tracking_beams(options):
    """Feedforward tracking on every simulated beam as tests/inverse/test_tracking.py
    runs it (seed 1, the default fit of a decaying-triangles record; a triangle and a
    trajectory with minor loops within 2-95 % of the model's rise): the mean absolute
    error in % of the desired range, compensated and without compensation (a voltage
    proportional to the desired displacement); smallest and largest over the beams."""
    import pihyst
    from pihyst.sim import PLANT_NAMES, make_plant, signals

    compensated, uncompensated = [], []
    for name in PLANT_NAMES:
        beam = make_plant(name, seed=1)
        t, u = signals.decaying_triangles()
        model = pihyst.fit(u, beam.run(u, t)).model
        y = model.predict(np.linspace(*model.input_range, 301))
        lo, hi = y[0] + 0.02 * (y[-1] - y[0]), y[0] + 0.95 * (y[-1] - y[0])
        gain = (model.predict([model.input_range[1]])[0] - model.predict([0.0])[0]) / 150.0
        for t, y_d in (signals.triangle(u_min=lo, u_max=hi, n_cycles=2),
                       signals.decaying_triangles(u_min=lo, u_max=hi)):
            span = y_d.max() - y_d.min()
            beam.reset()
            measured = beam.run(pihyst.compensate(model, y_d).voltage, t)
            compensated.append(100 * np.mean(np.abs(measured - y_d)) / span)
            beam.reset()
            measured = beam.run(np.clip((y_d - y_d[0]) / gain, 0, 150), t)
            uncompensated.append(100 * np.mean(np.abs(measured - y_d)) / span)
    return {"compensated_pct": {"min": min(compensated), "max": max(compensated)},
            "uncompensated_pct": {"min": min(uncompensated), "max": max(uncompensated)}}


@source(slow=True, data=True)
def p885_commands(options):
    """The README's commands on the P-885 stack as written (Measured data): fit
    Model_Vi_Do.dat (--voltage 1 --displacement 5 --lag 1 --rate 200), then compensate
    examples/desired_triangle_200Hz.csv --relative; what they print: the model's delay,
    operators, the rest point the relative frame starts from and the displacement the
    model reaches within its voltage range (in the relative and in the model's frame)."""
    import os
    import re
    import tempfile

    from pihyst.io import datasets

    data = _data_root() / datasets.P885_DIR
    with tempfile.TemporaryDirectory() as tmp:
        model = os.path.join(tmp, "p885.json")
        fitted = _run_cli("fit", str(data / "Model_Vi_Do.dat"), "--voltage", "1",
                          "--displacement", "5", "--lag", "1", "--rate", "200", "-o", model)
        comp = _run_cli("compensate", model,
                        str(_repo() / "examples" / "desired_triangle_200Hz.csv"),
                        "--relative", "-o", os.path.join(tmp, "u.csv"))
    m = re.search(r"wrote \S+: \S+ model, (\d+) operators, input delay (\d+) samples", fitted)
    rest = re.search(r"rest point at \S+ V \(([-\d.e]+) µm in the model's frame", comp)
    reach = re.search(r"reachable displacement: \[([-\d.e]+), ([-\d.e]+)\] µm", comp)
    if not (m and rest and reach):
        raise RuntimeError(f"pihyst fit/compensate printed something else:\n{fitted}\n{comp}")
    y0 = float(rest.group(1))
    lo, hi = float(reach.group(1)), float(reach.group(2))
    return {"n_operators": int(m.group(1)), "delay": int(m.group(2)), "rest_um": y0,
            "reach": {"min": lo, "max": hi}, "reach_abs": {"min": y0 + lo, "max": y0 + hi}}


def _run_cli(*args):
    """``pihyst ARGS`` in this process: what it prints (exit status 0, else an error)."""
    import contextlib
    import io

    from pihyst.cli import main

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        status = main(list(args))
    if status != 0:
        raise RuntimeError(f"pihyst {' '.join(args)}: exit status {status}")
    return buf.getvalue()


@source(slow=True)
def learning_stages(options):
    """The README's learning table, as benchmarks/bench_learn.py computes it (its own
    functions): per named stage and scan rate (10, 50, 100 Hz; the tuned paper-beam stage
    at 100 Hz), the static inverse's RMS error, the learned voltages' replay after 10
    trials, the replay in multiples of the sensor noise, and the static inverse's error
    (trial 0's, as the benchmark prints its gain) over the replay's."""
    import warnings

    from pihyst.exceptions import PihystWarning

    bench = _benchmark("bench_learn")
    keys = {"paper-beam": "paper_beam", "lens": "lens", "s-shaped": "s_shaped",
            "remanent": "remanent"}
    out = {"noise_um": bench.NOISE_UM, "trials": bench.TRIALS}
    for _label, name, modes, seed, _tuned in bench.STAGES:
        def make(r, noise=True, name=name, modes=modes, seed=seed):
            return bench.named_stage(name, modes, seed if r == bench.CLOCK_HZ else seed + 100,
                                     r, noise)
        rates = [100.0] if name == "paper-beam" else [10.0, 50.0, 100.0]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PihystWarning)
            rows, _ = bench.run_stage(make, modes[0][0], rates)
        entry = {}
        for rate, _n, res, replay, outside, _sent, _secs, _ham, static in rows:
            entry[f"hz{rate:g}"] = {"static": static, "t0": float(res.rms[0]),
                                    "replay": replay, "x_noise": replay / bench.NOISE_UM,
                                    "x_below": float(res.rms[0]) / replay,
                                    "x_below_static": static / replay, "outside": outside}
        out[keys[name]] = entry
    return out


def _hammerstein_summary(bench, stages):
    """``bench_learn.py --no-learning``'s summary over ``stages`` ((make, fmode) pairs, its
    rates: 1, 10, 50, 100 Hz, fmode/8, fmode/20): at or below fmode/20 how many rates
    the Hammerstein inverse is not above the static inverse and the worst ratio, above
    fmode/20 how many it is below and the best and worst ratio, the voltages outside
    the limits."""
    import warnings

    from pihyst.exceptions import PihystWarning

    below, above, outside = [], [], 0
    for make, fmode in stages:
        rates = [1.0, 10.0, 50.0, 100.0]
        rates += [] if fmode / 8 in rates else [fmode / 8]
        rates += [] if fmode / 20 in rates else [fmode / 20]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PihystWarning)
            rows, _ = bench.run_stage(make, fmode, rates, learn=False)
        for rate, _n, static, ham, out, _true in rows:
            (above if rate > fmode / 20 else below).append(ham / static)
            outside += out
    return {"below": {"n": len(below), "not_above": sum(r <= 1 for r in below),
                      "worst": max(below)},
            "above": {"n": len(above), "below": sum(r < 1 for r in above),
                      "best": min(above), "worst": max(above)},
            "outside": outside}


@source(slow=True)
def hammerstein_stages(options):
    """The README's Hammerstein-inverse row for the four named stages, as
    ``bench_learn.py --no-learning`` computes it (its own functions; about a minute):
    :func:`_hammerstein_summary`."""
    bench = _benchmark("bench_learn")
    stages = []
    for _label, name, modes, seed, _tuned in bench.STAGES:
        def make(r, noise=True, name=name, modes=modes, seed=seed):
            return bench.named_stage(name, modes, seed if r == bench.CLOCK_HZ else seed + 100,
                                     r, noise)
        stages.append((make, modes[0][0]))
    return _hammerstein_summary(bench, stages)


@source(script=True)
def hammerstein_random(options):
    """The README's Hammerstein-inverse rows for the random stages, as
    ``bench_learn.py --no-learning --fresh 10 SEED`` computes them (minutes): per set of
    ten seeds from 7000, 7300, 7500 and 7600, :func:`_hammerstein_summary`."""
    bench = _benchmark("bench_learn")
    out = {}
    for first in (7000, 7300, 7500, 7600):
        stages = []
        for seed in range(first, first + 10):
            def make(r, noise=True, seed=seed):
                return bench.random_stage(seed, r, bench.RANDOM_RANGE_UM, noise)[0]
            stages.append((make, bench.random_stage(seed)[1][0][0]))
        out[f"s{first}"] = _hammerstein_summary(bench, stages)
    return out


@source(slow=True)
def creep_holds(options):
    """docs/theory/creep.md's table, as benchmarks/bench_creep.py computes it: every
    simulated beam (seed 1) fitted on decaying triangles without creep (no sample times)
    and with creep (creep=True), judged on staircases held 10 s and 60 s per level
    (validation: the voltage staircase predicted; tracking: a staircase of desired
    displacements over 2-95 % of the model's rise through its compensator), mean absolute
    error in % of the range; the fitted creep's gain sum and lag count; and, over the
    three Preisach beams, the smallest and largest error without and with creep."""
    import warnings

    import pihyst
    from pihyst.exceptions import PihystWarning
    from pihyst.sim import PLANT_NAMES, make_plant, signals

    def pct(err, ref):
        return 100.0 * float(np.mean(np.abs(err))) / float(np.ptp(ref))

    out = {}
    for name in PLANT_NAMES:
        beam = make_plant(name, seed=1)
        t, u = signals.decaying_triangles()
        y = beam.run(u, t)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PihystWarning)
            models = (pihyst.fit(u, y).model, pihyst.fit(u, y, t=t, creep=True).model)
        entry = {"gain_sum": float(models[1].creep.gain.sum()),
                 "n_lags": models[1].creep.n_lags}
        for hold in (10.0, 60.0):
            ts, us = signals.staircase(step_s=hold)
            row = {}
            for key, m in zip(("without", "with"), models):
                beam.reset()
                ys = beam.run(us, ts)
                val = pct(m.predict(us, t=ts) - ys, ys)
                rise = m.predict(np.array([0.0, m.input_range[1]]))
                lo = rise[0] + 0.02 * (rise[1] - rise[0])
                hi = rise[0] + 0.95 * (rise[1] - rise[0])
                td, yd = signals.staircase(u_min=lo, u_max=hi, step_s=hold)
                comp = pihyst.compensate(m, yd, t=td)
                beam.reset()
                row[key] = {"validation": val, "tracking": pct(beam.run(comp.voltage, td) - yd, yd)}
            entry[f"hold{hold:g}"] = row
        out[name.replace("-", "_")] = entry
    preisach = [out[n] for n in ("paper_beam", "lens", "s_shaped")]
    for key in ("without", "with"):
        vals = [e[h][key][j] for e in preisach for h in ("hold10", "hold60")
                for j in ("validation", "tracking")]
        out[f"preisach_{key}"] = {"min": min(vals), "max": max(vals)}
    rem = [out["remanent"][h]["with"][j] for h in ("hold10", "hold60")
           for j in ("validation", "tracking")]
    out["remanent_with"] = {"min": min(rem), "max": max(rem)}
    return out


@source(script=True)
def learning_fresh(options):
    """bench_learn.py --fresh 4 3000 (its own functions): four random stages it never
    saw (random_plant's hysteresis and creep scaled to 45 µm, one or two modes from
    500 Hz - 2 kHz), each at 10, 50, 100 Hz and fmode/8: the first mode (Hz, damping %),
    the replay after 10 trials, in multiples of the noise, trial 0's error (the static
    inverse) and its ratio to the replay; over the stages that meet the targets (<= 3x
    the noise at 10, 50, 100 Hz, >= 25x below the static inverse at 100 Hz) the range of
    those figures, and the one that fails."""
    import warnings

    from pihyst.exceptions import PihystWarning

    bench = _benchmark("bench_learn")
    out, met, failed = {}, [], []
    for seed in range(3000, 3004):
        modes = bench.random_stage(seed)[1]

        def make(r, noise=True, seed=seed):
            return bench.random_stage(seed, r, bench.RANDOM_RANGE_UM, noise)[0]
        fmode = modes[0][0]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PihystWarning)
            rows, _ = bench.run_stage(make, fmode, [10.0, 50.0, 100.0, fmode / 8])
        entry = {"mode_hz": fmode, "mode_khz": fmode / 1e3, "damping_pct": 100 * modes[0][1]}
        for (_rate, _n, res, replay, _out, _sent, _secs, _ham, _static), key in zip(
                rows, ("hz10", "hz50", "hz100", "fmode8")):
            entry[key] = {"replay": replay, "x_noise": replay / bench.NOISE_UM,
                          "t0": float(res.rms[0]), "x_below": float(res.rms[0]) / replay}
        ok = (all(entry[k]["x_noise"] <= 3 for k in ("hz10", "hz50", "hz100"))
              and entry["hz100"]["x_below"] >= 25)
        (met if ok else failed).append(entry)
        out[f"s{seed}"] = entry
    noise = [e[k]["x_noise"] for e in met for k in ("hz10", "hz50", "hz100")]
    below = [e["hz100"]["x_below"] for e in met]
    out["met"] = {"n": len(met), "x_noise": {"min": min(noise, default=np.nan),
                                             "max": max(noise, default=np.nan)},
                  "x_below_100": {"min": min(below, default=np.nan),
                                  "max": max(below, default=np.nan)}}
    out["failed"] = failed[0] if len(failed) == 1 else {"n": len(failed)}
    return out


@source(slow=True)
def rig_commands(options):
    """The rig commands of the README and docs/rig.md as written (emulated instruments,
    virtual time): record the loop, fit it, track examples/rig/desired_triangle.csv open
    loop and with --feedback 1,10, and open loop with `pihyst fit --model multislope`'s
    model of the same loop; the tracking errors as the command prints them."""
    import contextlib
    import io
    import os
    import re
    import tempfile

    from pihyst.cli import main

    config = str(_repo() / "examples" / "rig" / "emulated.toml")
    desired = str(_repo() / "examples" / "rig" / "desired_triangle.csv")
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        def run(*args):
            buf = io.StringIO()
            with contextlib.redirect_stdout(buf):
                status = main(list(args))
            if status != 0:
                raise RuntimeError(f"pihyst {' '.join(args)}: exit status {status}")
            return buf.getvalue()

        loop, model = os.path.join(tmp, "loop.csv"), os.path.join(tmp, "model.json")
        multislope = os.path.join(tmp, "multislope.json")
        run("rig", "record", "--config", config, "-o", loop)
        run("fit", loop, "-o", model)
        run("fit", loop, "--model", "multislope", "-o", multislope)
        with open(multislope, encoding="utf-8") as f:
            out["multislope_n_operators"] = len(json.load(f)["weights"])
        for key, fitted, extra in (("open_loop", model, ()),
                                   ("feedback", model, ("--feedback", "1,10")),
                                   ("multislope_open_loop", multislope, ())):
            text = run("rig", "track", fitted, desired, "--config", config, *extra,
                       "-o", os.path.join(tmp, f"{key}.csv"))
            m = re.search(r"mean absolute ([\d.e-]+) µm.*; RMS ([\d.e-]+) µm; max "
                          r"([\d.e-]+) µm", text)
            if m is None:
                raise RuntimeError(f"pihyst rig track printed no tracking error: {text!r}")
            out[key] = {"mean_abs": float(m.group(1)), "rms": float(m.group(2)),
                        "max_abs": float(m.group(3))}
    return out


def _demo_derived(metrics):
    """The metrics plus the ratios the text quotes."""
    val = metrics["validation"]
    rev = metrics["tracking"]["reversals"]["errors"]
    metrics["derived"] = {
        "validation_multislope_over_best": val["multislope"]["mean_abs"] / val["best"]["mean_abs"],
        "validation_classical_over_best": val["classical"]["mean_abs"] / val["best"]["mean_abs"],
        "reversals_multislope_mean_abs": rev["multislope"]["mean_abs"],
        "reversals_best_mean_abs": rev["best"]["mean_abs"],
        "validation_best_mean_abs": val["best"]["mean_abs"],
    }
    return metrics


def _repo():
    from pathlib import Path
    return Path(__file__).resolve().parents[1]
