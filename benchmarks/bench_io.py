"""Records in and out: CSV reading and writing speed, `pihyst predict` end to end, and the
peak memory of the streamed commands against the record's length.

Measured in one run, beside references from the same run:

- read 10^6 rows (time_s, voltage_V, displacement_um) with pihyst's reader, pyarrow
  engine and NumPy engine, against ``np.loadtxt`` on the same file;
- write 10^6 rows with pihyst's C writer, pyarrow's writer and the ``repr`` twin, against
  ``np.savetxt(fmt="%.17g")``;
- `pihyst predict` on 10^6 rows end to end (a fresh process: start, read, run, write,
  sidecar) as the default install runs it (``pip install pihyst``, no extras: pyarrow,
  pandas, h5py, ... hidden from the process; the package byte-compiled, as pip does when
  it installs), against ``np.loadtxt`` reading the same file, both in this process (as
  measured under "reading") and in a fresh process (Python and NumPy started too), and
  against the model alone on the same voltages;
- peak memory (max RSS of the child process) of `pihyst predict` and `pihyst compensate`
  on 10^5, 10^6 and 10^7 rows; with ``--hour`` also 3.6 x 10^7 rows (an hour at
  10 kHz, a 2 GB file: minutes) and a classical `pihyst fit` on it.

Targets (the records issue): reading and writing at >= 2 x 10^6 rows/s; 10^6 rows through
`predict` with the default install within 1.5 x ``np.loadtxt`` on the same file; an hour
at 10 kHz through predict, compensate and a classical fit in less than 1 GB.

    python benchmarks/bench_io.py [--hour | --no-memory]
"""

import compileall
import io
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import pihyst
from pihyst.io import ColumnWriter, _text_engines, read_record

ROWS = 10**6
MODEL = Path(__file__).resolve().parents[1] / "examples" / "paper_table1_classical.json"


def signal(n, seed=0):
    """A 10 kHz record: decaying triangles with noise, 0-150 V."""
    t = np.arange(n) / 1e4
    phase = (t % 2.0) / 2.0
    u = 150 * (1 - np.abs(2 * phase - 1)) * (0.6 + 0.4 * np.cos(t / 300.0) ** 2)
    y = pihyst.load_model(MODEL).predict(u)
    y = y + np.random.default_rng(seed).normal(0, 0.01, n)
    return t, u, y


def write_record(path, n, engine=None):
    block = 1 << 20
    with ColumnWriter(path, ["time_s", "voltage_V", "displacement_um"],
                      comments=["bench_io"], engine=engine) as w:
        for start in range(0, n, block):
            t, u, y = signal(min(block, n - start), seed=start)
            w.write({"time_s": t + start / 1e4, "voltage_V": u, "displacement_um": y})


def best_time(fn, repeats):
    """(wall, CPU) seconds of the call with the least wall time: on a shared machine the
    CPU time (all threads) says what the work costs, the wall time what a user waits."""
    best = (float("inf"), float("inf"))
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        fn()
        best = min(best, (time.perf_counter() - w0, time.process_time() - c0))
    return best


def child(cmd):
    """(max RSS in MB, wall s, CPU s) of a command, measured by a fresh Python that runs
    it."""
    probe = ("import resource, subprocess, sys, time; t = time.perf_counter(); "
             "r = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL); "
             "t = time.perf_counter() - t; u = resource.getrusage(resource.RUSAGE_CHILDREN); "
             "print(r.returncode, u.ru_maxrss, t, u.ru_utime + u.ru_stime)")
    out = subprocess.run([sys.executable, "-c", probe, *cmd], capture_output=True, text=True,
                         check=True).stdout.split()
    if out[0] != "0":
        raise RuntimeError(f"{cmd} failed")
    return int(out[1]) / 1024, float(out[2]), float(out[3])


def reading(folder):
    path = folder / "r1e6.csv"
    write_record(path, ROWS)
    size = path.stat().st_size
    print(f"\nreading {ROWS:.0e} rows ({size / 1e6:.0f} MB), best of 3 (rows/s by wall and "
          "by CPU time):")
    ref = best_time(lambda: np.loadtxt(path, delimiter=",", skiprows=1), 3)
    rows = [("np.loadtxt (reference)", ref)]
    for engine in ("c", "pyarrow", "numpy"):
        if engine == "c" and _text_engines._fast() is None:
            continue
        if engine == "pyarrow" and _text_engines._arrow() is None:
            continue
        saved = _text_engines.engine_name
        _text_engines.engine_name = lambda e=engine: e
        try:
            rows.append((f"pihyst, {engine} engine",
                         best_time(lambda: read_record(path, need=("voltage",
                                                                   "displacement")), 3)))
        finally:
            _text_engines.engine_name = saved
    for label, (w, c) in rows:
        print(f"  {label:<28}{w:>8.3f} s{ROWS / w / 1e6:>7.2f} M/s wall{c:>8.3f} s"
              f"{ROWS / c / 1e6:>7.2f} M/s CPU{ref[0] / w:>7.1f} x loadtxt")
    return path, ref


def writing(folder):
    t, u, y = signal(ROWS)
    cols = {"time_s": t, "voltage_V": u, "displacement_um": y}
    print(f"\nwriting {ROWS:.0e} rows, best of 3 (rows/s by wall and by CPU time):")
    data = np.column_stack([t, u, y])
    ref = best_time(lambda: np.savetxt(io.StringIO(), data, delimiter=",", fmt="%.17g"), 2)
    rows = [("np.savetxt %.17g (reference)", ref)]
    for engine in ("c", "pyarrow", "numpy"):
        if engine == "pyarrow" and _text_engines._arrow() is None:
            continue
        if engine == "c" and _text_engines._fast() is None:
            continue

        def write(e=engine):
            with ColumnWriter(folder / "w.csv", list(cols), engine=e) as w:
                w.write(cols)
        rows.append((f"pihyst, {engine}", best_time(write, 3)))
    for label, (w, c) in rows:
        print(f"  {label:<30}{w:>8.3f} s{ROWS / w / 1e6:>7.2f} M/s wall{c:>8.3f} s"
              f"{ROWS / c / 1e6:>7.2f} M/s CPU{ref[0] / w:>7.1f} x savetxt")


# what `pip install pihyst` leaves out: the optional extras and what they bring
EXTRAS = ("pyarrow", "pandas", "h5py", "nptdms", "openpyxl", "distributed", "dask", "control")
DEFAULT_INSTALL = ("import sys; sys.modules.update(dict.fromkeys({extras!r})); "
                   "from pihyst.cli import main; sys.argv[0] = 'pihyst'; sys.exit(main())")


def predict_end_to_end(folder, path, loadtxt):
    """`pihyst predict` in a fresh process against np.loadtxt on the same file; returns
    the command that runs pihyst (for :func:`memory`)."""
    beside = Path(sys.executable).with_name("pihyst")
    pihyst_cmd = str(beside) if beside.exists() else shutil.which("pihyst")
    # the .pyc files pip writes when it installs (an editable install has none; and
    # PYTHONDONTWRITEBYTECODE would make every run compile the package again)
    compileall.compile_dir(str(Path(pihyst.__file__).parent), quiet=1)
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
    u = read_record(path, need=("voltage",)).voltage
    model = pihyst.load_model(MODEL)
    alone = best_time(lambda: model.predict(u), 3)[0]
    out = folder / "pred.csv"
    default = [sys.executable, "-c", DEFAULT_INSTALL.format(extras=EXTRAS)]
    cases = [("pihyst predict, default install", default),
             ("pihyst predict, all extras", [pihyst_cmd])]
    fresh_loadtxt = min((child([sys.executable, "-c", "import sys, numpy; numpy.loadtxt("
                                "sys.argv[1], delimiter=',', skiprows=1)", str(path)])
                         for _ in range(3)), key=lambda r: r[1])
    print(f"\npihyst predict on {ROWS:.0e} rows, end to end (fresh process), best of 3:")
    print(f"  {'':<36}{'wall':>9}{'CPU':>9}{'wall ratio':>12}{'CPU ratio':>11}")
    print(f"  {'np.loadtxt, this process (reference)':<36}{loadtxt[0]:>8.3f}s{loadtxt[1]:>8.3f}s")
    print(f"  {'np.loadtxt, fresh process':<36}{fresh_loadtxt[1]:>8.3f}s"
          f"{fresh_loadtxt[2]:>8.3f}s")
    print(f"  {'the model alone':<36}{alone:>8.3f}s")
    for label, cmd in cases:
        runs = [child([*cmd, "predict", str(MODEL), str(path), "-o", str(out)])
                for _ in range(3)]
        _, wall, cpu = min(runs, key=lambda r: r[1])
        print(f"  {label:<36}{wall:>8.3f}s{cpu:>8.3f}s{wall / loadtxt[0]:>10.2f} x"
              f"{cpu / loadtxt[1]:>9.2f} x   (x np.loadtxt in this process; "
              f"{wall / fresh_loadtxt[1]:.2f} x / {cpu / fresh_loadtxt[2]:.2f} x a fresh one)")
    return pihyst_cmd


def memory(folder, pihyst_cmd, sizes, fit):
    print("\npeak memory (max RSS of the process) against rows:")
    print("  (MB: max RSS; s: wall / CPU seconds)")
    print(f"  {'rows':>10}{'file (MB)':>11}{'predict (MB)':>14}{'s':>14}"
          f"{'compensate (MB)':>17}{'s':>14}" + (f"{'fit classical (MB)':>20}{'s':>14}"
                                                  if fit else ""))
    for n in sizes:
        path = folder / f"m{n}.csv"
        write_record(path, n)
        out = folder / "out.csv"
        pred, tp, cp = child([pihyst_cmd, "predict", str(MODEL), str(path), "-o", str(out)])
        comp, tc, cc = child([pihyst_cmd, "compensate", str(MODEL), str(out), "-o",
                              str(folder / "comp.csv")])
        line = (f"  {n:>10.1e}{path.stat().st_size / 1e6:>11.0f}{pred:>14.0f}"
                f"{tp:>7.1f} /{cp:>5.1f}{comp:>17.0f}{tc:>7.1f} /{cc:>5.1f}")
        if fit:
            mem, tf, cf = child([pihyst_cmd, "fit", str(path), "--model", "classical",
                                 "-o", str(folder / "m.json")])
            line += f"{mem:>20.0f}{tf:>7.1f} /{cf:>5.1f}"
        print(line, flush=True)
        for p in (path, out, folder / "comp.csv"):
            p.unlink(missing_ok=True)


def main():
    hour = "--hour" in sys.argv
    arrow = _text_engines._arrow()
    print(f"pihyst {pihyst.__version__}, NumPy {np.__version__}, pyarrow "
          f"{'not installed' if arrow is None else arrow[0].__version__}, "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        path, loadtxt = reading(folder)
        writing(folder)
        pihyst_cmd = predict_end_to_end(folder, path, loadtxt)
        if "--no-memory" not in sys.argv:
            sizes = [10**5, 10**6, 10**7] + ([36 * 10**6] if hour else [])
            memory(folder, pihyst_cmd, sizes, fit=hour)
    print(f"\n(self: {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB peak)")


if __name__ == "__main__":
    main()
