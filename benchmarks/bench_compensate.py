"""Benchmark of the exact inverse (compensator): C per-sample latency, batch throughput of
pihyst.compensate, against a bisection baseline and the NumPy reference, same run.

1. C step latency, K = 4, 16, 64, classical and multislope: bench_compensate.c (next to
   this file) is compiled with gcc -O3 together with csrc/pihyst_*.c and times
   pihyst_compensator_step over 10^6 samples of reachable trajectories with minor loops
   (best of 3), and a bisection to 1e-12 V on the same model and trajectory. Three
   trajectories: a walk and ramps (tracking: the compensator keeps its breakpoints while
   the direction holds) and noise (a random voltage every sample: a reversal two samples
   in three, far from the last voltage, the worst case). The operator state is allocated
   as a user would (its own malloc block); a second table repeats the noise at K = 16
   with the state at several offsets from a cache line (the compensator works on an
   aligned copy, so the offset should not matter).
2. The block run through the binding (_core.Compensator.run) over 10^6 samples.
3. pihyst.compensate on 10^6 samples (the Python API, everything included).
4. The NumPy reference (pihyst._reference.Compensator) on a few hundred samples, per
   sample, and the ratio.

Targets (issue 4): <= 50 ns per sample at K = 16 in the C step; <= 80 ms for 10^6
samples through pihyst.compensate.

Run: python benchmarks/bench_compensate.py
"""

import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np
from timing import best_time

import pihyst
from pihyst import _core, _reference

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent
N = 1_000_000
N_REFERENCE = 300
U = 150.0


def model_for(family, k, seed=0):
    rng = np.random.default_rng(seed)
    w = 0.1 * rng.uniform(size=k)
    w[0] += 0.2
    if family == "classical":
        return pihyst.ClassicalPI(U * np.arange(k) / k, w)
    return pihyst.MultislopePI(50.0 * np.arange(k) / k, w)


def ramps(n, seed=1, step=0.25):
    """Ramps between random levels in [0, U] at `step` volts per sample: minor loops."""
    rng = np.random.default_rng(seed)
    pieces, total, level = [], 0, 0.0
    while total < n:
        target = rng.uniform(0, U)
        m = max(int(abs(target - level) / step), 1)
        pieces.append(np.linspace(level, target, m + 1)[1:])
        total += m
        level = target
    return np.concatenate(pieces)[:n]


def compile_harness(folder):
    gcc = shutil.which("gcc")
    if gcc is None:
        return None
    exe = folder / "bench_compensate"
    cmd = [gcc, "-std=c99", "-O3", "-ffp-contract=fast", "-D_POSIX_C_SOURCE=199309L",
           f"-I{ROOT / 'csrc'}", str(HERE / "bench_compensate.c"),
           *map(str, sorted((ROOT / "csrc").glob("pihyst_*.c"))), "-lm", "-o", str(exe)]
    subprocess.run(cmd, check=True)
    return exe


TRAJECTORIES = {0: "walk", 1: "ramps", 2: "noise"}


def c_latency(folder):
    exe = compile_harness(folder)
    print("1. C step latency, ns per sample (harness compiled with gcc -O3; 10^6 samples, "
          "best of 3; bisection to 1e-12 V on 10^5 samples, scaled). Desired = the model's "
          "output for: walk = random steps <= 0.5 V, reversals at random levels (1 %); "
          "ramps = 0.25 V per sample between random levels; noise = a random voltage every "
          "sample (worst case: a reversal two samples in three)")
    if exe is None:
        print("   gcc not found: skipped")
        return {}
    print(f"   {'family':<11} {'K':>3} {'trajectory':<10} {'exact':>7} {'bisection':>10} "
          f"{'ratio':>7} {'max|y-y_d| exact':>17} {'bisection':>10}")
    figures = {}
    for fam_id, family in enumerate(("classical", "multislope")):
        for k in (4, 16, 64):
            for kind, name in TRAJECTORIES.items():
                out = subprocess.run([str(exe), str(fam_id), str(k), str(N), "3", str(kind)],
                                     check=True, capture_output=True, text=True).stdout.split()
                exact, bisect, err_exact, err_bisect = map(float, out)
                figures[family, k, name] = exact
                target = "  (target <= 50 ns)" if k == 16 else ""
                print(f"   {family:<11} {k:>3} {name:<10} {exact:>7.1f} {bisect:>10.1f} "
                      f"{bisect / exact:>6.1f}x {err_exact:>17.2g} {err_bisect:>10.2g}{target}")
    print("\n   noise, K = 16, ns per sample by where the operator state lies: its own malloc "
          "block (as above), or 0/1/4 doubles past a 64-byte boundary")
    print(f"   {'family':<11} {'malloc':>7} {'+0':>7} {'+1':>7} {'+4':>7}")
    for fam_id, family in enumerate(("classical", "multislope")):
        times = []
        for offset in (-1, 0, 1, 4):
            out = subprocess.run([str(exe), str(fam_id), "16", str(N), "3", "2", str(offset)],
                                 check=True, capture_output=True, text=True).stdout.split()
            times.append(float(out[0]))
        print(f"   {family:<11} " + " ".join(f"{t:>7.1f}" for t in times))
    return figures


def binding_and_api():
    print("\n2./3. Through Python, 10^6 samples of ramps between random levels (0.25 V per "
          "sample); NumPy reference on", N_REFERENCE, "samples")
    print(f"   {'family':<11} {'K':>3} {'run ns/sample':>14} {'compensate ms':>14} "
          f"{'NumPy us/sample':>16} {'ratio':>7}  check")
    u = ramps(N)
    for family in ("classical", "multislope"):
        for k in (4, 16, 64):
            model = model_for(family, k)
            y_d = model.predict(u)
            lo, hi = model.input_range

            def core_run():
                comp = _core.Compensator(model._new_bank(model.initial_state), lo, hi, np.inf,
                                         0.0)
                return comp.run(y_d)

            t_run = best_time(core_run, 3)
            t_api = best_time(lambda: pihyst.compensate(model, y_d), 3)
            result = pihyst.compensate(model, y_d)
            err = np.max(np.abs(result.displacement - y_d))
            args = dict(family=family, thresholds=model.thresholds, weights=model.weights,
                        offset=0.0, u_min=lo, u_max=hi)
            if family == "multislope":
                args["shape"] = (model.U, model.a, model.b, model.h)
            ref = _reference.Compensator(_reference.Bank(**args), lo, hi, np.inf, 0.0)
            t0 = time.perf_counter()
            u_ref, _, _ = ref.run(y_d[:N_REFERENCE])
            t_ref = (time.perf_counter() - t0) / N_REFERENCE
            agree = np.max(np.abs(u_ref - result.voltage[:N_REFERENCE]))
            target = "  (target <= 80 ms)" if k == 16 else ""
            print(f"   {family:<11} {k:>3} {1e9 * t_run / N:>14.1f} {1e3 * t_api:>14.1f} "
                  f"{1e6 * t_ref:>16.1f} {t_ref * N / t_api:>6.0f}x  "
                  f"max|y-y_d| {err:.1g}, |u-u_ref| {agree:.1g}{target}")


def main():
    print(f"exact inverse (compensator), pihyst {pihyst.__version__}, Python "
          f"{sys.version.split()[0]}, NumPy {np.__version__}")
    with tempfile.TemporaryDirectory() as tmp:
        c_latency(pathlib.Path(tmp))
    binding_and_api()


if __name__ == "__main__":
    main()
