"""Exported models with creep in the shared library (docs/export.md): predict and compensate
through the plain C ABI (csrc/libpihyst.so, called with ctypes in blocks), in ns per
sample, for a model with creep against the same model without creep measured in the same
run (ratio creep / none: the cost of the lags), and against pihyst.compensate with creep
(the Python entry to the same C core) as a yardstick.

Models: the paper's multislope PI (4 operators) and a classical PI of 16 operators, each
with 3 and with 8 creep lags (dt = 1 ms). Signal: a 0-150 V sine of 2000 samples per
cycle (compensate: its displacements as the desired outputs), 200 000 samples per call.

Run: python benchmarks/bench_export.py
"""

import ctypes
import subprocess
import tempfile
from pathlib import Path

import numpy as np
from timing import best_cpu_time

import pihyst
from pihyst.io._export import flat_text
from pihyst.model import Creep

CSRC = Path(__file__).resolve().parents[1] / "csrc"
N = 200_000
REPEATS = 7


def library():
    subprocess.run(["make", "-s", "-C", str(CSRC), "shared"], check=True)
    so = ctypes.CDLL(str(CSRC / "libpihyst.so"))
    dp = ctypes.POINTER(ctypes.c_double)
    so.pihyst_lib_load.restype = ctypes.c_void_p
    so.pihyst_lib_load.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.c_int32)]
    so.pihyst_lib_free.argtypes = [ctypes.c_void_p]
    so.pihyst_lib_predict.argtypes = [ctypes.c_void_p, dp, dp, ctypes.c_int32]
    so.pihyst_lib_reset.argtypes = [ctypes.c_void_p, dp, ctypes.c_int32]
    so.pihyst_lib_compensator_start.argtypes = [ctypes.c_void_p] + [ctypes.c_double] * 4
    so.pihyst_lib_compensate.argtypes = [ctypes.c_void_p, dp, dp,
                                         ctypes.POINTER(ctypes.c_uint8), ctypes.c_int32]
    return so


def _ptr(a):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))


def lib_times(so, model, folder, u, yd):
    """(predict, compensate) in ns per sample through the library, and its voltages."""
    path = Path(folder) / "m.pihyst"
    path.write_text(flat_text(model))
    status = ctypes.c_int32(1)
    h = so.pihyst_lib_load(str(path).encode(), ctypes.byref(status))
    assert status.value == 0, status.value
    y, volts = np.empty_like(u), np.empty_like(yd)

    def predict():
        so.pihyst_lib_reset(h, None, 0)
        so.pihyst_lib_predict(h, _ptr(u), _ptr(y), u.size)

    def compensate():
        so.pihyst_lib_reset(h, None, 0)
        so.pihyst_lib_compensator_start(h, np.nan, np.nan, 0.0, 0.0)
        so.pihyst_lib_compensate(h, _ptr(yd), _ptr(volts), None, yd.size)

    try:
        t_pred = best_cpu_time(predict, REPEATS)
        t_comp = best_cpu_time(compensate, REPEATS)
    finally:
        so.pihyst_lib_free(h)
    return 1e9 * t_pred / u.size, 1e9 * t_comp / yd.size, volts


def main():
    so = library()
    u = 75.0 - 75.0 * np.cos(2 * np.pi * np.arange(N) / 2000.0)
    rng = np.random.default_rng(0)
    base = {
        "multislope K=4": pihyst.load_model(Path(__file__).resolve().parents[1] / "examples"
                                            / "paper_table1_multislope.json"),
        "classical K=16": pihyst.ClassicalPI(np.linspace(0, 140, 16),
                                             rng.uniform(0.01, 0.1, 16)),
    }
    print(f"shared library, ns per sample ({N} samples per call, best of {REPEATS} CPU "
          f"times); ratio to the same model without creep")
    print(f"{'model':<16} {'lags':>4}  {'predict':>8} {'ratio':>6}  {'compensate':>10} "
          f"{'ratio':>6}  {'pihyst.compensate':>17}")
    with tempfile.TemporaryDirectory() as folder:
        for label, model in base.items():
            yd = model.predict(u)
            p0, c0, _ = lib_times(so, model, folder, u, yd)
            print(f"{label:<16} {0:>4}  {p0:>8.1f} {1.0:>6.2f}  {c0:>10.1f} {1.0:>6.2f}")
            for n in (3, 8):
                tau = np.logspace(-1, 2, n)
                creep = Creep(tau, np.full(n, 0.06 / n), dt=1e-3)
                with_creep = model.replace(creep=creep)
                yd = with_creep.predict(u)
                p, c, volts = lib_times(so, with_creep, folder, u, yd)
                py = best_cpu_time(lambda m=with_creep, d=yd: pihyst.compensate(m, d), 3)
                ref = pihyst.compensate(with_creep, yd).voltage
                assert np.max(np.abs(volts - ref)) <= 1e-12 * 150.0
                print(f"{label:<16} {n:>4}  {p:>8.1f} {p / p0:>6.2f}  {c:>10.1f} "
                      f"{c / c0:>6.2f}  {1e9 * py / N:>14.1f} ns")


if __name__ == "__main__":
    main()
