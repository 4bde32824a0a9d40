"""The default fit end to end, as a user runs it (the identification issue's targets).

1. `pihyst fit` on the P-885 identification file (the README's command), default
   against `--model classical` in the same run (target: <= 3x and <= 2 s), and on the
   SmartHysteresis raw file (target <= 3 s); measured data from ../shared/data or
   $PIHYST_DATA (skipped if absent).
2. The same file fitted twice: identical model files (no clock in any decision), and
   the README's `--max-latency` example on it twice: the same answer.
3. 10^6 rows with a time column, `pihyst fit FILE.csv` end to end against
   `np.loadtxt` of the same file (target <= 20x, peak memory <= 1 GB).
4. `pihyst.fit(u, y)` on 10^6 samples without times (random level ramps) against one
   `scipy.optimize.nnls` of a 10^6 x 16 matrix (target <= 3x).
5. `pihyst fit-many` on a folder of three copies of the P-885 file, per record, against
   `pihyst fit` of it (part 1), and the model files compared with it (target: identical,
   <= 1.5x per record).

Times are CPU seconds of the process (user + system; wall beside them): on a shared
machine the wall time also counts other jobs' share of the cores. Each figure is the
best of REPEAT runs, the runs of a ratio's two sides interleaved (as timeit takes the
best: other jobs only ever add time, and on this 2-core machine they add up to half).

Run: python benchmarks/bench_fit.py [--quick] [--repeat N]   (--quick: parts 1 and 2
only; --repeat: runs per figure, default 3)
"""

import compileall
import filecmp
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.optimize import nnls

import pihyst
from pihyst.io import datasets
from pihyst.sim import make_plant

REPEAT = int(sys.argv[sys.argv.index("--repeat") + 1]) if "--repeat" in sys.argv else 3


def best(runs):
    """The run with the least CPU time of ``runs`` (tuples starting with CPU seconds)."""
    return min(runs, key=lambda run: run[0])


def run_cli(args):
    """(cpu s, wall s, peak RSS MB, stdout) of `pihyst ARGS` in a child process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "pihyst", *args], capture_output=True,
                         text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode:
        raise SystemExit(f"pihyst {' '.join(args)} failed:\n{out.stderr}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall, after.ru_maxrss / 1024, out.stdout


def measured(tmp):
    root = datasets.data_root()
    if root is None:
        print("measured data not found (../shared/data or $PIHYST_DATA): skipped")
        return
    p885, smart = root / datasets.P885_DIR, root / datasets.SMART_DIR
    p885_args = [str(p885 / "Model_Vi_Do.dat"), "--voltage", "1", "--displacement", "5",
                 "--lag", "1", "--rate", "200"]
    print(f"1. pihyst fit, end to end (CPU s / wall s, best of {REPEAT})")
    classical, default = [], []
    for _ in range(REPEAT):
        classical.append(run_cli(["fit", *p885_args, "--model", "classical", "-o",
                                  str(tmp / "c.json")]))
        default.append(run_cli(["fit", *p885_args, "-o", str(tmp / "a.json")]))
    cpu_c, wall_c, _, _ = best(classical)
    cpu_d, wall_d, _, text = best(default)
    chosen = next((line for line in text.splitlines() if line.startswith("wrote")), "")
    print(f"  P-885 --model classical : {cpu_c:6.2f} / {wall_c:6.2f}")
    print(f"  P-885 default           : {cpu_d:6.2f} / {wall_d:6.2f}   "
          f"{cpu_d / cpu_c:.1f}x classical (target <= 3x, <= 2 s)")
    print(f"    {chosen}")
    smart_args = [str(smart / "hysteresis_v_150_1hz.csv"), "--time", "2", "--displacement",
                  "3", "--voltage", "4", "--skip-until", "4.26"]
    cpu_s, wall_s, _, _ = best(run_cli(["fit", *smart_args, "-o", str(tmp / "s.json")])
                               for _ in range(REPEAT))
    print(f"  SmartHysteresis default : {cpu_s:6.2f} / {wall_s:6.2f}   (target <= 3 s)")

    print("2. the same model every time")
    run_cli(["fit", *p885_args, "-o", str(tmp / "b.json")])
    same = filecmp.cmp(tmp / "a.json", tmp / "b.json", shallow=False)
    print(f"  P-885 fitted twice: model files {'identical' if same else 'DIFFERENT'}")
    answers = []
    for name in ("l1.json", "l2.json"):
        run_cli(["fit", *p885_args, "--max-operators", "8", "--max-latency", "5e-7", "-o",
                 str(tmp / name)])
        answers.append(pihyst.load_model(tmp / name).metadata["fit"]["family"])
    print(f"  --max-operators 8 --max-latency 5e-7 twice: {answers[0]}, {answers[1]} "
          f"({'the same' if answers[0] == answers[1] else 'DIFFERENT'}; files "
          f"{'identical' if filecmp.cmp(tmp / 'l1.json', tmp / 'l2.json', False) else 'differ'})")

    print("5. pihyst fit-many, per record")
    folder = tmp / "fleet"
    folder.mkdir()
    for k in range(3):
        (folder / f"p885-{k}.dat").write_bytes((p885 / "Model_Vi_Do.dat").read_bytes())
    cpu_m, wall_m, _, _ = run_cli(["fit-many", str(folder), "-o", str(tmp / "models"),
                                   *p885_args[1:]])
    same = all(_fitted(tmp / "a.json") == _fitted(path)
               for path in sorted((tmp / "models").glob("p885-*.json")))
    print(f"  fit-many, 3 records : {cpu_m:6.2f} / {wall_m:6.2f}   {cpu_m / 3:.2f} CPU s per "
          f"record, {cpu_m / 3 / cpu_d:.2f}x pihyst fit (target <= 1.5x); model files "
          f"{'identical to' if same else 'DIFFERENT from'} pihyst fit's (but for the "
          f"command and record they name)")


def _fitted(path):
    """A model file's model and fit, without its provenance (command, file read)."""
    data = pihyst.load_model(path).to_dict()
    data.get("metadata", {}).pop("source", None)
    return data


def level_ramps(n, seed=0, per_level=200):
    rng = np.random.default_rng(seed)
    levels = np.r_[0.0, 150.0, 0.0, rng.uniform(0, 150, n // per_level)]
    u = np.concatenate([np.linspace(a, b, per_level, endpoint=False)
                        for a, b in zip(levels[:-1], levels[1:])])
    return u[:n]


def large(tmp, n=1_000_000):
    beam = make_plant("paper-beam", seed=1)
    u = level_ramps(n)
    t = np.arange(n) * 1e-3
    y = beam.run(u, t)
    path = tmp / "large.csv"
    np.savetxt(path, np.column_stack([t, u, y]), delimiter=",", fmt="%.9g",
               header="time_s,voltage_V,displacement_um", comments="")
    print(f"3. 10^6 rows with a time column ({path.stat().st_size / 1e6:.0f} MB CSV, best "
          f"of {REPEAT})")
    loads, fits = [], []
    for _ in range(REPEAT):
        t0, c0 = time.perf_counter(), time.process_time()
        np.loadtxt(path, delimiter=",", skiprows=1)
        loads.append((time.process_time() - c0, time.perf_counter() - t0))
        fits.append(run_cli(["fit", str(path), "-o", str(tmp / "large.json")]))
    cpu_l, wall_l = best(loads)
    cpu_f, wall_f, rss, _ = best(fits)
    print(f"  np.loadtxt        : {cpu_l:6.2f} / {wall_l:6.2f}")
    print(f"  pihyst fit        : {cpu_f:6.2f} / {wall_f:6.2f}   {cpu_f / cpu_l:.1f}x "
          f"loadtxt (target <= 20x), peak memory {rss:.0f} MB (target <= 1024)")

    print(f"4. pihyst.fit(u, y), 10^6 samples, no times (best of {REPEAT})")
    rng = np.random.default_rng(1)
    A = np.abs(rng.normal(size=(n, 16)))
    b = A @ rng.uniform(0, 1, 16) + rng.normal(0, 0.01, n)
    references, fits = [], []
    for _ in range(REPEAT):
        c0 = time.process_time()
        nnls(A, b)
        references.append((time.process_time() - c0,))
        c0 = time.process_time()
        res = pihyst.fit(u, y)
        fits.append((time.process_time() - c0,))
    cpu_n, cpu_p = best(references)[0], best(fits)[0]
    print(f"  scipy nnls 10^6 x 16 : {cpu_n:6.2f} CPU s")
    print(f"  pihyst.fit           : {cpu_p:6.2f} CPU s   {cpu_p / cpu_n:.1f}x nnls "
          f"(target <= 3x); chosen {res.report.chosen}, {res.model.n_operators} operators")


def main():
    os.environ.setdefault("PIHYST_PROGRESS", "0")
    # the package byte-compiled, as pip installs it (PYTHONDONTWRITEBYTECODE, set on some
    # machines, would make every command compile it again: half a second of each run)
    compileall.compile_dir(str(Path(pihyst.__file__).parent), quiet=1)
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        measured(tmp)
        if "--quick" not in sys.argv:
            large(tmp)


if __name__ == "__main__":
    main()
