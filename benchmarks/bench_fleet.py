"""Fleet benchmark: fitting many records (one per actuator) with pihyst.fit_many on a
Dask LocalCluster of this machine's cores, against a serial loop of pihyst.fit over the
same records measured in the same run.

Records: simulated beams (each plant with its own seed: noise, and the plant's
variant), full triangle + decaying triangles at dt = 0.5 s, as ``pihyst simulate``
records them; fitted with the default options (every family, the best kept). Prints the
serial time, the cluster's start-up time, the parallel time, the speed-up (serial /
parallel, start-up excluded and included) and checks that every model is bit-identical
to the serial one.

BLAS: Dask starts its worker processes with OMP/OPENBLAS/MKL_NUM_THREADS=1; this script
sets the same before NumPy loads, so the serial reference runs the same arithmetic (the
kp family's regularization choice can flip on last-bit differences between BLAS thread
counts) and is not slowed by BLAS threads fighting over two cores (on this machine the
serial loop took 3x longer with OpenBLAS's default threads).

Run: python benchmarks/bench_fleet.py [N_RECORDS] [N_WORKERS] [REPEATS]   (8, 2, 2)
"""

import os
import sys
import time
import warnings

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"   # as in Dask's worker processes; before NumPy loads

import numpy as np  # noqa: E402

import pihyst  # noqa: E402
from pihyst.exceptions import PihystWarning  # noqa: E402
from pihyst.sim import PLANT_NAMES, make_plant  # noqa: E402
from pihyst.sim.signals import decaying_triangles  # noqa: E402


def records(n):
    t, u = decaying_triangles(dt=0.5)
    out = {}
    for k in range(n):
        name = PLANT_NAMES[k % len(PLANT_NAMES)]
        out[f"{name}-{k}"] = (u, make_plant(name, seed=k).run(u, t))
    return out


def _spin(n):
    s = 0
    for i in range(n):
        s += i * i
    return s


def available_parallelism(client, workers, n=3_000_000):
    """Speed-up of plain CPU-bound Python on the same workers: the ceiling for the fleet's
    (on a shared machine, other work takes its share of the cores)."""
    t0 = time.perf_counter()
    for _ in range(workers):
        _spin(n)
    t_serial = time.perf_counter() - t0
    t0 = time.perf_counter()
    client.gather(client.map(_spin, [n] * workers, pure=False))
    return t_serial / (time.perf_counter() - t0)


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 8
    workers = int(sys.argv[2]) if len(sys.argv) > 2 else 2
    repeats = int(sys.argv[3]) if len(sys.argv) > 3 else 2
    from distributed import Client, LocalCluster

    fleet = records(n)
    samples = next(iter(fleet.values()))[0].size
    print(f"fleet: {n} records of {samples} samples, default fit options (every family); "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}; BLAS in one "
          f"thread everywhere; best of {repeats} runs, serial and parallel interleaved")

    def serial_loop():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PihystWarning)
            return {name: pihyst.fit(u, y) for name, (u, y) in fleet.items()}

    t0 = time.perf_counter()
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                      dashboard_address=":0") as cluster, Client(cluster) as client:
        client.run(lambda: __import__("pihyst"))   # workers ready, pihyst imported
        t_start = time.perf_counter() - t0
        t_serial = t_in = t_par = float("inf")
        ceiling = []
        for _ in range(repeats):
            ceiling.append(available_parallelism(client, workers))
            t0 = time.perf_counter()
            serial = serial_loop()
            t_serial = min(t_serial, time.perf_counter() - t0)
            t0 = time.perf_counter()
            parallel = pihyst.fit_many(fleet, client=client)
            t_par = min(t_par, time.perf_counter() - t0)
            t0 = time.perf_counter()
            in_process = pihyst.fit_many(fleet)
            t_in = min(t_in, time.perf_counter() - t0)
    print(f"  serial loop of pihyst.fit (reference): {t_serial:6.2f} s "
          f"({t_serial / n:.2f} s per record)")
    print(f"  fit_many, client=None (in process):   {t_in:6.2f} s  "
          f"(x{t_serial / t_in:.2f} of the loop's speed)")
    print(f"  LocalCluster start, {workers} worker processes: {t_start:6.2f} s")
    print(f"  fit_many on the cluster:              {t_par:6.2f} s  "
          f"speed-up x{t_serial / t_par:.2f} over the serial loop "
          f"(x{t_serial / (t_par + t_start):.2f} counting the start)")
    print(f"  control: plain CPU-bound Python on the same {workers} workers: speed-up "
          f"x{max(ceiling):.2f} over serial, the ceiling on this machine now (load average "
          f"{os.getloadavg()[0]:.1f}); the fleet reached {t_serial / t_par / max(ceiling):.0%} "
          f"of it")

    differ = [name for name in fleet
              if not (parallel[name].model == serial[name].model
                      and np.array_equal(parallel[name].model.weights,
                                         serial[name].model.weights)
                      and _without_timings(parallel[name].result.report.to_dict())
                      == _without_timings(serial[name].report.to_dict())
                      and in_process[name].model == serial[name].model)]
    print(f"  models and reports (measured latencies aside) bit-identical to the serial "
          f"loop's: "
          f"{n - len(differ)} of {n}" + (f" (differ: {', '.join(differ)})" if differ else ""))
    if differ or not parallel.ok:
        sys.exit(1)


def _without_timings(value):
    """A report without its measured compensator latencies (wall-clock, never equal)."""
    if isinstance(value, dict):
        return {k: _without_timings(v) for k, v in value.items() if k != "latency"}
    if isinstance(value, list):
        return [_without_timings(v) for v in value]
    return value


if __name__ == "__main__":
    main()
