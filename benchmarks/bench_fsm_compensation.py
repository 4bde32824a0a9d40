"""Feedforward on the CubeSpec fine steering mirror's one model for all levels: the
scheduled compensator against the compensator of one linear model.

The models are those of ``bench_fsm.py --scheduled --order=40 --penalty=1`` (the same
calls): one linear state-space model of order 40 fitted on the 100 mV and 300 mV
training records together, and the amplitude-scheduled model
(pihyst.dynamics.fit_scheduled_state_space, penalty 1, window 1024 samples) from it.
Desired trajectories, "100 mV-like" and "300 mV-like" (and 200 mV when its records are
present): the scheduled model's periodic output for each test realisation's input at
that level (one period, 8192 samples at 6.4 kHz; reachable by construction). Each is
compensated by

- "scheduled": pihyst.dynamics.compensate_scheduled (the schedule a fixed point of the
  voltages, each step an exact solve of the time-varying model);
- "first pass": the scheduled model frozen at the mean amplitude of its own inverse's
  voltages (``model.at(abar)``, inverted per harmonic: the fixed point's start);
- "linear": the linear model of both levels inverted per harmonic (what compensate_mimo
  does for a StateSpaceHammerstein with no hysteresis);

every voltage clipped to +-1.5x the largest test input of any level, and judged by
simulating the scheduled model on it (its periodic steady state): RMS tracking error
over the period, all outputs pooled, um and % of the desired's RMS.

The fit takes about 10 minutes on this shared machine: ``--cache=DIR`` keeps the two
models there (fsm_linear_order40.json, fsm_scheduled_order40_penalty1.json; the
scheduled one in pihyst's scheduled-state-space file format) and reads them back on the
next run.

Run: PIHYST_DATA=/path/to/data python benchmarks/bench_fsm_compensation.py [--cache=DIR]
"""

import json
import sys
import time
from pathlib import Path

import numpy as np
from bench_fsm import (
    FSM_DIR,
    FSM_SCHEDULE_NFEV,
    FSM_SCHEDULE_WINDOW,
    PERIOD,
    fsm_levels,
    fsm_records,
)

from pihyst.dynamics import (
    StateSpace,
    compensate_scheduled,
    fit_scheduled_state_space,
    fit_state_space,
    load_scheduled_state_space,
    save_scheduled_state_space,
)
from pihyst.dynamics._compensate_scheduled import periodic_response
from pihyst.io import datasets

ORDER, PENALTY = 40, 1.0
LIMIT_MARGIN = 1.5      # voltage limits: +- this times the largest test input


def models(root, cache):
    """(linear, scheduled): read from ``cache`` when there, else fitted (and saved)."""
    lin_path = cache / f"fsm_linear_order{ORDER}.json" if cache else None
    sched_path = cache / f"fsm_scheduled_order{ORDER}_penalty{PENALTY:g}.json" if cache else None
    if cache and lin_path.is_file() and sched_path.is_file():
        print(f"models read from {cache}")
        return (StateSpace.from_dict(json.loads(lin_path.read_text())),
                load_scheduled_state_space(sched_path))
    levels = ("100mV", "300mV")
    train = [r for level in levels for r in fsm_records(root, level, "train")]
    n = len(train) // len(levels)
    t0 = time.perf_counter()
    lin = fit_state_space(train, PERIOD, order=ORDER, discard=0)
    sched = fit_scheduled_state_space([train[:n], train[n:]], PERIOD, linear=lin,
                                      window=FSM_SCHEDULE_WINDOW, discard=0,
                                      max_nfev=FSM_SCHEDULE_NFEV, penalty=PENALTY)
    print(f"models fitted in {time.perf_counter() - t0:.0f} s")
    if cache:
        cache.mkdir(parents=True, exist_ok=True)
        lin_path.write_text(json.dumps(lin.to_dict()))
        save_scheduled_state_space(sched, sched_path)
    return lin, sched


def harmonic_inverse(G, r):
    """U(k) = G(z_k)^+ R(k) on every rfft line of one period r (N, p)."""
    R = np.fft.rfft(r, axis=0)
    U = np.einsum("kij,kj->ki", np.linalg.pinv(G, rcond=1e-12), R)
    return np.fft.irfft(U, n=r.shape[0], axis=0)


def main(cache):
    root = datasets.data_root()
    if root is None or not (root / FSM_DIR).is_dir():
        print(f"FSM data not found ({FSM_DIR} in $PIHYST_DATA or ../shared/data): skipped")
        return
    lin, sched = models(root, cache)
    tests = {lv: fsm_records(root, lv, "test") for lv in fsm_levels(root)}
    limit = LIMIT_MARGIN * max(np.abs(u).max() for recs in tests.values() for u, _ in recs)
    w = 2 * np.pi * np.arange(PERIOD // 2 + 1) / PERIOD
    G_lin = lin.response(w)
    print(f"anchors {', '.join(f'{a:.4f}' for a in sched.amplitudes)} V RMS, window "
          f"{sched.window:g} samples; voltage limits +-{limit:.3f} V")
    print("tracking error on the scheduled model (RMS over the period, all outputs), um "
          "(% of the desired's RMS); per test realisation")
    print(f"{'level':>6} {'real.':>5} {'desired':>8} {'scheduled':>19} {'first pass':>19} "
          f"{'linear':>19} {'iter.':>5} {'time':>6}")
    for lv, recs in tests.items():
        for i, (u, _) in enumerate(recs):
            desired = periodic_response(sched, u[PERIOD:])
            size = np.sqrt(np.mean(desired ** 2))
            t0 = time.perf_counter()
            res = compensate_scheduled(sched, desired, u_min=-limit, u_max=limit)
            elapsed = time.perf_counter() - t0
            first = harmonic_inverse(sched.at(res.amplitude).response(w), desired)
            linear = harmonic_inverse(G_lin, desired)
            cells = []
            for v in (res.voltage, first, linear):
                v = np.clip(v, -limit, limit)
                e = np.sqrt(np.mean((periodic_response(sched, v) - desired) ** 2))
                cells.append(f"{e:9.2e} ({100 * e / size:6.3f} %)")
            flag = "" if res.converged else (" saturated" if res.saturated else " not conv.")
            print(f"{lv:>6} {i + 1:>5} {size:8.3f} " + " ".join(f"{c:>19}" for c in cells)
                  + f" {res.iterations:>5} {elapsed:5.1f}s{flag}")


if __name__ == "__main__":
    print(__doc__.split("\n\n")[0])
    opts = dict(a[2:].split("=", 1) for a in sys.argv[1:] if a.startswith("--") and "=" in a)
    main(Path(opts["cache"]) if "cache" in opts else None)
