"""Benchmark of the KP (Krasnosel'skii-Pokrovskii) operator kernel (issue items 2-3):
a piecewise-linear model of K = 132 saturated ramps built as pihyst.identify builds its
KP kernels (R = sat((v - c_j)/w + 1/2), F = sat((v - c_i)/w + 1/2), c_i <= c_j on a
16-point grid over [0, 150]). The core detects the ramp shape at init and updates the
operators with a branch-free loop; the reference in the same run is the same model with
one extra point on the flat part of every polyline (the same function, which the core
runs through its generic polyline path: binary search per polyline, as before).

Rows (best CPU time of 5): forward model (predict) per sample; compensator per sample
while tracking (ramps between random levels at 0.25 V per sample, as
bench_compensate.py) and in the worst case (a random
reachable value every sample); also a random walk of 0.5 V steps, a reversal about
every other sample. On the ramp model the compensator uses its saturated-ramp path
(docs/c-core.md): operators sorted by ramp once, a search and a model step that visit
only the operators with a ramp where the voltage moves; on the reference model the
generic event-list walk (collect and sort the breakpoints at every reversal) and the
generic model step. Targets (issue item 2): compensator <= 200 ns per sample tracking
and <= 2 us worst case at K ~ 130.

Second table: the C compensator's block run (the binding's _core.Compensator.run: the
compensator alone, not what pihyst.compensate adds around it) against a classical K = 16
one (as bench_compensate.py builds it) on the same trajectories in the same run, scaled
to each model's input range:
the synthetic model above and, when the measured data sets are present ($PIHYST_DATA or
../shared/data), the models the default fit produces for them (`pihyst fit` with the
record's columns only, the commands of csrc/m4f/models.sh; hysteresis part, creep lags
left out). Targets (issue 20 item 5): within 4x the classical K = 16 compensator while
tracking, 20x in the worst case.

Part 2 (the identification issue, item 5): the KP models the default fit produces for
the measured records (P-885 and SmartHysteresis; ../shared/data or $PIHYST_DATA, skipped
if absent), with their kernels reduced (identify/_kernel_pruning.py) and, for the gain,
the same fit without the reduction (PRUNE_TOLERANCE = 0), against a classical K = 16
compensator on the same input range and the same voltage trajectories (with the model's
creep lags, if it has them): compensator time per sample, tracking (ramps between random
levels, 1/600 of the range per sample) and worst case (a random reachable value every
sample), best CPU time of 9 runs interleaved over the rows. Targets: <= 4x
the classical K = 16 while tracking, <= 20x in the worst case.

Run: python benchmarks/bench_kp.py [--fitted]   (--fitted: part 2 only)
"""

import json
import pathlib
import subprocess
import sys
import tempfile
import time
import warnings

import numpy as np
from timing import best_cpu_time

import pihyst
from pihyst import _core
from pihyst.io import datasets

U = 150.0
N = 20_000
REPEATS = 9



def kp_models(grid=16, k=132, seed=0):
    rng = np.random.default_rng(seed)
    centres = np.linspace(0, U, grid)
    w = U / (grid - 1)
    pairs = [(i, j) for i in range(grid) for j in range(i, grid)][:k]

    def ramp(c, extra):
        x = np.array([c - 1.5 * w, c - 0.5 * w, c + 0.5 * w, c + 1.5 * w])
        y = np.array([0.0, 0.0, 1.0, 1.0])
        if extra:  # the same function with a point on the low flat part
            x, y = np.r_[x[0], x[0] + 0.25 * w, x[1:]], np.r_[0.0, y]
        return x, y

    weights = rng.uniform(0.0, 0.1, len(pairs))
    models = []
    for extra in (False, True):
        rising = [ramp(centres[j], extra) for _, j in pairs]
        falling = [ramp(centres[i], extra) for i, _ in pairs]
        models.append(pihyst.PiecewiseLinearPI(rising, falling, weights,
                                               input_range=(0.0, U)))
    return models


def ramps(n, rng, step=0.25):
    """Ramps between random levels at `step` volts per sample (as bench_compensate.py):
    tracking with a reversal at every level, minor loops of every size."""
    pieces, total, level = [], 0, 0.0
    while total < n:
        target = rng.uniform(0, U)
        m = max(int(abs(target - level) / step), 1)
        pieces.append(np.linspace(level, target, m + 1)[1:])
        total += m
        level = target
    return np.concatenate(pieces)[:n]


FITS = {  # the default fit's commands for the measured records (csrc/m4f/models.sh)
    "P-885": ("dbo-pi-p885-micromanipulator/Model_Vi_Do.dat",
              ["--voltage", "1", "--displacement", "5", "--lag", "1", "--rate", "200"]),
    "SmartHysteresis": ("smarthysteresis-piezo-sine150V1Hz/hysteresis_v_150_1hz.csv",
                        ["--time", "2", "--displacement", "3", "--voltage", "4",
                         "--skip-until", "4.26"]),
}


def default_fit_models():
    """{name: model} the default fit gives for the measured records (hysteresis part), or
    {} without the data"""
    root = datasets.data_root()
    if root is None:
        return {}
    pihyst_cmd = pathlib.Path(sys.executable).with_name("pihyst")
    models = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, (path, options) in FITS.items():
            out = pathlib.Path(tmp) / "model.json"
            subprocess.run([str(pihyst_cmd), "fit", str(pathlib.Path(root) / path), *options,
                            "-o", str(out)], check=True, capture_output=True)
            model = json.loads(out.read_text())
            model.pop("creep", None)
            models[name] = pihyst.load_model(model)
    return models


def classical_k16():
    """the classical K = 16 model of bench_compensate.py, on [0, U]"""
    rng = np.random.default_rng(0)
    w = 0.1 * rng.uniform(size=16)
    w[0] += 0.2
    return pihyst.ClassicalPI(U * np.arange(16) / 16, w)


def trajectories(rng, lo=0.0, hi=U):
    """tracking (ramps), walk and noise voltages on [0, U], mapped onto [lo, hi]"""
    walk = U - np.abs(np.cumsum(rng.normal(0, 0.5, N)) % (2 * U) - U)
    scaled = {"tracking": ramps(N, rng), "walk": walk, "noise": rng.uniform(0, U, N)}
    return {name: lo + (hi - lo) * u / U for name, u in scaled.items()}


def core_run_time(model, u):
    """best CPU time of 5 per sample of the C compensator's block run (the binding's
    _core.Compensator.run, as bench_compensate.py's second table) on the model's outputs
    for u, from the model's initial state at u[0]: the compensator alone, without what
    pihyst.compensate adds around it (building the bank, a delay's preview)"""
    yd = model.predict(u)
    lo, hi = model.input_range
    best = np.inf
    for _ in range(5):
        comp = _core.Compensator(model._new_bank(model.initial_state), lo, hi, np.inf,
                                 float(u[0]))
        t0 = time.process_time()
        comp.run(yd)
        best = min(best, time.process_time() - t0)
    return best / len(u)


def against_classical(fast):
    reference = classical_k16()
    models = {f"synthetic K = {fast.n_operators}": fast, **default_fit_models()}
    print("\ncompensator against classical K = 16 on the same trajectories (ns per sample; "
          "targets: tracking <= 4x, noise <= 20x)")
    print(f"   {'model':<26} {'K':>4} {'trajectory':<9} {'KP':>7} {'K16':>7} {'ratio':>7}")
    for name, model in models.items():
        lo, hi = model.input_range
        rng = np.random.default_rng(2)
        for kind, u in trajectories(rng, lo, hi).items():
            t_kp = core_run_time(model, u)
            t_16 = core_run_time(reference, (u - lo) / (hi - lo) * U)
            limit = 4.0 if kind == "tracking" else (20.0 if kind == "noise" else None)
            verdict = "" if limit is None else (
                f"  (<= {limit:.0f}x: {'met' if t_kp / t_16 <= limit else 'NOT met'})")
            print(f"   {name:<26} {model.n_operators:>4} {kind:<9} {1e9 * t_kp:>7.0f} "
                  f"{1e9 * t_16:>7.0f} {t_kp / t_16:>6.1f}x{verdict}")


def main():
    fast, generic = kp_models()
    rng = np.random.default_rng(1)
    walk = np.abs(np.cumsum(rng.normal(0, 0.5, N)) % (2 * U) - U)
    walk = U - walk
    noise = rng.uniform(0, U, N)
    tracking = ramps(N, rng)
    k = fast.n_operators
    print(f"KP model, K = {k} saturated ramps, {N} samples, best CPU time of 5 "
          "(ns per sample)")
    print(f"   {'':<22} {'ramp path':>12} {'generic':>12}   ratio")
    t_f = best_cpu_time(lambda: fast.predict(walk), 5) / N
    t_g = best_cpu_time(lambda: generic.predict(walk), 5) / N
    same = np.array_equal(fast.predict(walk), generic.predict(walk))
    print(f"   {'predict':<22} {1e9 * t_f:>12.0f} {1e9 * t_g:>12.0f}   {t_g / t_f:.1f}x"
          f"   (outputs equal: {same})")
    for name, u in (("compensate, tracking", tracking), ("compensate, walk", walk),
                    ("compensate, noise", noise)):
        yd = fast.predict(u)
        t_f = best_cpu_time(lambda yd=yd: pihyst.compensate(fast, yd), 5) / N
        t_g = best_cpu_time(lambda yd=yd: pihyst.compensate(generic, yd), 5) / N
        r = pihyst.compensate(fast, yd)
        err = np.max(np.abs(r.displacement - yd))
        limit = 200e-9 if "tracking" in name else 2000e-9
        met = "met" if t_f <= limit else "NOT met"
        print(f"   {name:<22} {1e9 * t_f:>12.0f} {1e9 * t_g:>12.0f}   {t_g / t_f:.1f}x"
              f"   (max |y - y_d| {err:.1e}; target <= {1e9 * limit:.0f} ns: {met})")
    against_classical(fast)


def fitted_models():
    """Part 2 (module notes)."""
    from pihyst.exceptions import PihystWarning
    from pihyst.identify import _constants
    from pihyst.io import datasets

    root = datasets.data_root()
    if root is None:
        print("\nfitted models: measured data not found (../shared/data or $PIHYST_DATA): "
              "skipped")
        return
    print(f"\nKP models of the default fit, compensator ns per sample (best CPU time of "
          f"{REPEATS}, interleaved), "
          f"{N} samples; ratio to a classical K = 16 on the same range and voltages")
    print(f"   {'record':<16} {'model':<22} {'kernels':>7} {'tracking':>9} {'ratio':>6} "
          f"{'worst':>8} {'ratio':>6}")
    # P-885 with its 200 Hz sample times, as `pihyst fit` fits the file (creep kept)
    p885 = datasets.p885(root)
    records = (("P-885", p885 + (np.arange(p885[0].size) / 200.0,)),
               ("SmartHysteresis", datasets.smarthysteresis(root) + (None,)))
    for name, (u, y, t) in records:
        models = {}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PihystWarning)
            models["default fit"] = pihyst.fit(u, y, t=t).model
            reduction, _constants.PRUNE_TOLERANCE = _constants.PRUNE_TOLERANCE, 0.0
            try:
                models["without reduction"] = pihyst.fit(u, y, t=t).model
            finally:
                _constants.PRUNE_TOLERANCE = reduction
        lo, hi = models["default fit"].input_range
        rng = np.random.default_rng(2)
        # the reference carries the model's creep lags, if any: the same work per sample
        # but for the hysteresis operators
        classical = pihyst.ClassicalPI(np.arange(16) * (hi - lo) / 32,
                                       0.1 * rng.uniform(size=16) + 0.02, input_range=(lo, hi),
                                       creep=models["default fit"].creep)
        volts = (lo + ramps(N, rng, step=U / 600) * (hi - lo) / U, rng.uniform(lo, hi, N))
        rows = [("classical K = 16", classical)] + [
            (label, m) for label, m in models.items() if m.metadata["fit"]["family"] == "kp"]
        # without the delay (a preview shift of the trajectory, no compensator work)
        runs = {(label, i): (m.replace(delay=0), m.replace(delay=0).predict(v))
                for label, m in rows for i, v in enumerate(volts)}
        best = dict.fromkeys(runs, np.inf)
        for _ in range(REPEATS):          # interleaved: a slow spell hits every row
            for key, (m, yd) in runs.items():
                best[key] = min(best[key], best_cpu_time(
                    lambda m=m, yd=yd: pihyst.compensate(m, yd), 1) / N)
        ref = [best[("classical K = 16", i)] for i in (0, 1)]
        for label, m in rows:
            t = [best[(label, i)] for i in (0, 1)]
            met = t[0] <= 4 * ref[0] and t[1] <= 20 * ref[1]
            print(f"   {name:<16} {label:<22} {m.n_operators:>7} {1e9 * t[0]:>9.0f} "
                  f"{t[0] / ref[0]:>6.1f} {1e9 * t[1]:>8.0f} {t[1] / ref[1]:>6.1f}"
                  + ("" if m is classical else
                     f"   (<= 4x / 20x: {'met' if met else 'NOT met'})"))
        for label, m in models.items():
            if m.metadata["fit"]["family"] != "kp":
                print(f"   {name:<16} {label:<22} not kp: {m.metadata['fit']['family']}")

if __name__ == "__main__":
    if "--fitted" not in sys.argv[1:]:
        main()
    fitted_models()
