"""What the export tests share: the C compiler under the firmware flags, the C core
compiled once per module, a driver program built against a generated header and run on
a voltage signal and a desired trajectory, and the shared library."""

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
CSRC = REPO / "csrc"
CC = shutil.which("cc") or shutil.which("gcc")
FIRMWARE_FLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2"]


def needs_compiler():
    if CC is None or not CSRC.is_dir():
        pytest.skip("needs a C compiler and the source tree's csrc/")


def export_signals(model, n=1500, seed=1):
    """(u, y_desired): a voltage signal through random levels of the model's input
    range, and its output with noise of 5 % of its span (reachable and not)."""
    rng = np.random.default_rng(seed)
    lo, hi = model.input_range
    u = np.interp(np.linspace(0, 1, n), np.linspace(0, 1, 12),
                  np.r_[lo, rng.uniform(lo, hi, 10), lo])
    y = model.predict(u)
    return u, y + rng.normal(0, 0.05 * np.ptp(y), n)


def compile_core(tmp_path_factory, sources):
    """The C core's ``sources`` (in csrc/) compiled with the firmware flags: objects."""
    needs_compiler()
    out = tmp_path_factory.mktemp("core")
    objects = []
    for source in sources:
        obj = out / source.replace(".c", ".o")
        subprocess.run([CC, *FIRMWARE_FLAGS, f"-I{CSRC}", "-c", str(CSRC / source), "-o",
                        str(obj)], check=True, capture_output=True, text=True)
        objects.append(str(obj))
    return objects


def compile_driver(tmp_path, header_name, header_text, driver_text, objects):
    """The driver program built against the header (written as ``header_name``)."""
    (tmp_path / header_name).write_text(header_text)
    (tmp_path / "driver.c").write_text(driver_text)
    exe = tmp_path / "driver"
    subprocess.run([CC, *FIRMWARE_FLAGS, f"-I{CSRC}", f"-I{tmp_path}",
                    str(tmp_path / "driver.c"), *objects, "-lm", "-o", str(exe)],
                   check=True, capture_output=True, text=True)
    return exe


def run_driver(exe, u, yd):
    """The numbers the driver prints, given n, the n voltages and n desired values."""
    stdin = "\n".join(f"{v!r}" for v in [u.size, *u.tolist(), *yd.tolist()]) + "\n"
    out = subprocess.run([str(exe)], input=stdin, check=True, capture_output=True, text=True)
    return np.array(out.stdout.split(), dtype=float)


def shared_library():
    """csrc/libpihyst.so, built by make, loaded with ctypes, every function typed."""
    import ctypes

    needs_compiler()
    subprocess.run(["make", "-s", "-C", str(CSRC), "shared"], check=True, capture_output=True)
    so = ctypes.CDLL(str(CSRC / "libpihyst.so"))
    dp = ctypes.POINTER(ctypes.c_double)
    ip = ctypes.POINTER(ctypes.c_int32)
    i32, vp, real = ctypes.c_int32, ctypes.c_void_p, ctypes.c_double
    so.pihyst_lib_create.restype = vp
    so.pihyst_lib_create.argtypes = [i32, i32, dp, dp, real, real, real, dp, ip, dp, dp, ip,
                                     dp, dp, dp, ip]
    so.pihyst_lib_create_boucwen.restype = vp
    so.pihyst_lib_create_boucwen.argtypes = [dp, ip]
    so.pihyst_lib_load.restype = vp
    so.pihyst_lib_load.argtypes = [ctypes.c_char_p, ip]
    so.pihyst_lib_free.argtypes = [vp]
    so.pihyst_lib_n_operators.argtypes = [vp]
    so.pihyst_lib_predict.argtypes = [vp, dp, dp, i32]
    so.pihyst_lib_get_state.argtypes = [vp, dp, i32]
    so.pihyst_lib_reset.argtypes = [vp, dp, i32]
    so.pihyst_lib_compensator_start.argtypes = [vp, real, real, real, real]
    so.pihyst_lib_compensate.argtypes = [vp, dp, dp, ctypes.POINTER(ctypes.c_uint8), i32]
    so.pihyst_lib_set_creep.argtypes = [vp, dp, dp, i32, real]
    so.pihyst_lib_n_creep_lags.argtypes = [vp]
    so.pihyst_lib_get_creep_state.argtypes = [vp, dp, i32]
    so.pihyst_lib_set_creep_state.argtypes = [vp, dp, i32]
    so.pihyst_lib_status_text.restype = ctypes.c_char_p
    return so
