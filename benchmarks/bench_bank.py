"""Benchmark of the multi-channel bank (issue item 5): N = 1000 actuators, each its own
classical K = 16 model (thresholds and weights differ per channel), compensated tick by
tick with one call per tick, in actuator-samples per second, against references measured
in the same run.

Columns (best of several runs each; T ticks of N channels):
- fast bank: CompensatorBank(fast=True).run on a (T, N) block: pihyst_compbank_compensate
  once per tick, the structure-of-arrays bank whose classical channels step their
  model's analytic inverse vectorized across channels (csrc/pihyst_bank_soa.c); its
  largest voltage difference from the exact bank is printed.
- bank: pihyst.inverse.CompensatorBank.run (exact): the C loop pihyst_bank_compensate
  once per tick, one single-compensator step per channel.
- separate, per tick: what a user without a bank does in Python: N Compensator.step
  calls per tick (on fewer ticks).
- separate, per channel: every channel's whole record at once (Compensator.run per
  column): the same C work with the best cache locality, but not causal across channels
  (a controller does not have tick t+1 before it applies tick t).
- NumPy reference (pihyst._reference.Compensator), a few ticks of a few channels, per
  actuator-sample.
Also the model bank: ModelBank(fast=True).run (pihyst_modelbank, structure-of-arrays,
bit for bit) and ModelBank.run (pihyst_bank_step) against per-channel predict.

Two trajectories: tracking (each channel follows its own smooth reachable signal) and
noise (a random reachable value on every channel every tick: the worst case, a reversal
two ticks in three). Target (issue item 5): >= 5e7 actuator-samples/s for the bank
compensating 1000 channels of K = 16 classical; the ratios are to the per-channel
single-compensator reference (per chan) and to the exact bank, measured in the same run.

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
    print(f"   {'trajectory':<10} {'fast bank':>10} {'bank':>10} {'per tick':>10} "
          f"{'per chan':>10} {'numpy ref':>10}   fast / per chan, / bank")
    for kind in ("tracking", "noise"):
        u = voltages(kind, T, N_CH)
        desired = np.column_stack([m.predict(u[:, i]) for i, m in enumerate(models)])
        bank = CompensatorBank(models)
        fast = CompensatorBank(models, fast=True)

        def run_bank(bank=bank, desired=desired):
            bank.reset()
            return bank.run(desired)

        t_bank = best_cpu_time(run_bank, 5) / (T * N_CH)
        u_bank, y_bank, flags = run_bank()
        err = np.max(np.abs(y_bank - desired))
        t_fast = best_cpu_time(lambda fast=fast, d=desired: run_bank(fast, d), 5) / (T * N_CH)
        u_fast, y_fast, flags_fast = run_bank(fast, desired)
        du = np.max(np.abs(u_fast - u_bank))
        assert du < 1e-9 * U and np.array_equal(flags_fast, flags)
        assert fast.n_fast == N_CH

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
        met = "met" if 1 / t_fast >= 5e7 else "NOT met"
        print(f"   {kind:<10} {1 / t_fast:>10.3g} {1 / t_bank:>10.3g} {1 / t_tick:>10.3g} "
              f"{1 / t_chan:>10.3g} {1 / t_ref:>10.3g}   {t_chan / t_fast:.2f}x, "
              f"{t_bank / t_fast:.2f}x   (fast {1e9 * t_fast:.1f} ns, bank {1e9 * t_bank:.1f} ns "
              f"per actuator-sample; max |u_fast - u_bank| {du:.1e} V, max |y - y_d| {err:.1e}, "
              f"{int(np.count_nonzero(flags))} flagged; target >= 5e7/s {met})")

    print(f"\nmodel bank: {N_CH} channels, classical K = {K}, {T} ticks (best of 5)")
    print(f"   {'trajectory':<10} {'fast bank':>10} {'bank':>10} {'per chan':>10}   "
          f"fast / per chan, / bank")
    for kind in ("tracking", "noise"):
        u = voltages(kind, T, N_CH)
        mbank = ModelBank(models)
        fbank = ModelBank(models, fast=True)

        def run_mbank(mbank=mbank, u=u):
            mbank.reset()
            return mbank.run(u)

        t_mbank = best_cpu_time(run_mbank, 5) / (T * N_CH)
        t_fbank = best_cpu_time(lambda fbank=fbank, u=u: run_mbank(fbank, u), 5) / (T * N_CH)
        cols = [np.ascontiguousarray(u[:, i]) for i in range(N_CH)]
        t_pred = best_cpu_time(lambda cols=cols: [m.predict(c) for m, c in
                                              zip(models, cols, strict=True)], 5) / (T * N_CH)
        y = run_mbank()
        assert np.array_equal(run_mbank(fbank, u), y)  # the same bits
        assert all(np.array_equal(y[:, i], models[i].predict(cols[i])) for i in range(20))
        print(f"   {kind:<10} {1 / t_fbank:>10.3g} {1 / t_mbank:>10.3g} {1 / t_pred:>10.3g}   "
              f"{t_pred / t_fbank:.2f}x, {t_mbank / t_fbank:.2f}x  (fast {1e9 * t_fbank:.1f} ns, "
              f"bank {1e9 * t_mbank:.1f} ns per actuator-sample)")

if __name__ == "__main__":
    main()
