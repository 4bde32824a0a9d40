"""Benchmark of the multi-channel bank (issue item 5): N = 1000 actuators, each its own
classical K = 16 model (thresholds and weights differ per channel), compensated tick by
tick with one call per tick, in actuator-samples per second, against references measured
in the same run.

Rows (best of several runs each; T ticks of N channels):
- bank: pihyst.inverse.CompensatorBank.run on a (T, N) block: the C loop
  pihyst_bank_compensate once per tick (one call per sample vector).
- separate, per tick: what a user without a bank does in Python: N Compensator.step
  calls per tick (on fewer ticks).
- separate, per channel: every channel's whole record at once (Compensator.run per
  column): the same C work with the best cache locality, but not causal across channels
  (a controller does not have tick t+1 before it applies tick t).
- NumPy reference (pihyst._reference.Compensator), a few ticks of a few channels, per
  actuator-sample.
Also the model bank (ModelBank.run, pihyst_bank_step) against per-channel predict.

Two trajectories: tracking (each channel follows its own smooth reachable signal) and
noise (a random reachable value on every channel every tick: the worst case, a reversal
two ticks in three). Target (issue item 5): >= 5e7 actuator-samples/s for the bank
compensating 1000 channels of K = 16 classical.

Run: python benchmarks/bench_bank.py
"""

import time

import numpy as np
from timing import best_cpu_time

import pihyst
from pihyst import _reference
from pihyst.inverse import CompensatorBank
from pihyst.model import ModelBank

N_CH = 1000
K = 16
T = 2000
T_STEP = 20
U = 150.0



def channel_models(n, k, seed=0):
    rng = np.random.default_rng(seed)
    models = []
    for _ in range(n):
        r = np.sort(rng.uniform(0, U, k))
        r[0] = 0.0
        w = 0.1 * rng.uniform(size=k)
        w[0] += 0.2
        models.append(pihyst.ClassicalPI(r, w))
    return models


def voltages(kind, t, n, seed=1):
    rng = np.random.default_rng(seed)
    if kind == "noise":
        return rng.uniform(0, U, (t, n))
    phase = rng.uniform(0, 2 * np.pi, n)
    freq = rng.uniform(0.5, 2.0, n) * 2 * np.pi / 1000
    tt = np.arange(t)[:, None]
    # a swept sine with decaying amplitude around mid-range: minor loops, slow reversals
    return U / 2 + U / 2.2 * np.sin(freq * tt + phase) * np.cos(0.37 * freq * tt)


def main():
    models = channel_models(N_CH, K)
    print(f"bank of {N_CH} channels, classical K = {K} each, {T} ticks "
          f"(best CPU time of 5; actuator-samples per second)")
    print(f"   {'trajectory':<10} {'bank':>10} {'per tick':>10} {'per chan':>10} "
          f"{'numpy ref':>10}   bank / per tick, / per chan, / numpy")
    for kind in ("tracking", "noise"):
        u = voltages(kind, T, N_CH)
        desired = np.column_stack([m.predict(u[:, i]) for i, m in enumerate(models)])
        bank = CompensatorBank(models)

        def run_bank(bank=bank, desired=desired):
            bank.reset()
            return bank.run(desired)

        t_bank = best_cpu_time(run_bank, 5) / (T * N_CH)
        u_bank, y_bank, flags = run_bank()
        err = np.max(np.abs(y_bank - desired))

        chans = [pihyst.Compensator(m) for m in models]

        def per_tick(chans=chans, desired=desired):
            for c in chans:
                c.reset()
            for row in desired[:T_STEP]:
                for c, yd in zip(chans, row, strict=True):
                    c.step(yd)

        t_tick = best_cpu_time(per_tick, 3) / (T_STEP * N_CH)

        def per_channel(chans=chans, desired=desired):
            for i, c in enumerate(chans):
                c.reset()
                c.run(desired[:, i])

        t_chan = best_cpu_time(per_channel, 5) / (T * N_CH)

        n_ref, t_ref_ticks = 4, 50
        t0 = time.thread_time()
        for i, m in enumerate(models[:n_ref]):
            ref = _reference.Compensator(
                _reference.Bank("classical", thresholds=m.thresholds, weights=m.weights,
                                offset=0.0, u_min=0.0, u_max=U), 0.0, U, np.inf, 0.0)
            u_ref, _, _ = ref.run(desired[:t_ref_ticks, i])
            assert np.max(np.abs(u_ref - u_bank[:t_ref_ticks, i])) < 1e-9
        t_ref = (time.thread_time() - t0) / (n_ref * t_ref_ticks)
        target = "  (target >= 5e7/s)"
        print(f"   {kind:<10} {1 / t_bank:>10.3g} {1 / t_tick:>10.3g} {1 / t_chan:>10.3g} "
              f"{1 / t_ref:>10.3g}   {t_tick / t_bank:.0f}x, {t_chan / t_bank:.2f}x, "
              f"{t_ref / t_bank:.0f}x   ({1e9 * t_bank:.1f} ns per actuator-sample, "
              f"max |y - y_d| {err:.1e}, {int(np.count_nonzero(flags))} flagged){target}")

    print(f"\nmodel bank: {N_CH} channels, classical K = {K}, {T} ticks (best of 5)")
    print(f"   {'trajectory':<10} {'bank':>10} {'per chan':>10}   bank / per chan")
    for kind in ("tracking", "noise"):
        u = voltages(kind, T, N_CH)
        mbank = ModelBank(models)

        def run_mbank(mbank=mbank, u=u):
            mbank.reset()
            return mbank.run(u)

        t_mbank = best_cpu_time(run_mbank, 5) / (T * N_CH)
        cols = [np.ascontiguousarray(u[:, i]) for i in range(N_CH)]
        t_pred = best_cpu_time(lambda cols=cols: [m.predict(c) for m, c in
                                              zip(models, cols, strict=True)], 5) / (T * N_CH)
        y = run_mbank()
        assert all(np.array_equal(y[:, i], models[i].predict(cols[i])) for i in range(20))
        print(f"   {kind:<10} {1 / t_mbank:>10.3g} {1 / t_pred:>10.3g}   "
              f"{t_pred / t_mbank:.2f}x  ({1e9 * t_mbank:.1f} ns per actuator-sample)")


if __name__ == "__main__":
    main()
