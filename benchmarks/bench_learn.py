"""Learning feedforward on resonant stages (pihyst.learn.learn_periodic; the scanning
issue, items 1 and 5).

Per simulated stage (a beam's hysteresis and creep, then modes of 500 Hz - 2 kHz, one
tick of converter delay, a 20 kHz clock, 0.005 um sensor noise; pihyst.sim.make_stage)
and per scan rate (1, 10, 50, 100 Hz and fmode/8): a band-limited triangle (harmonics
below fmode/2) over 80 % of the stage's range, tracked with

The scan covers 80 % of the range the stage reaches at that rate (driven 0-150 V by the
same band-limited triangle, settled; with creep that is less than the settled loop).

- the static inverse: the default ``pihyst.fit`` model (fitted with creep on a slow
  record, 1 s decaying triangles at 200 Hz) inverted exactly (its periodic inverse, with
  creep), played periodically on a stage settled on it ("static"); the learning's trial
  0 is the same inverse on a stage settled on the plain inverse ("t0": the learning's
  own figures, the gain against it);
- the Hammerstein inverse (no learning): that model followed by dynamics measured on
  the stage (``pihyst.dynamics.fit_dynamics``: one drive shape, a triangle's first 15
  harmonics over 10-140 V, played at 1 Hz and at 20, 50, 100, 200 and 80 Hz, each fast
  record held back in turn to choose the order (the lowest unless a higher one is clearly
  better) and to find, per harmonic order, from which rate the dynamics' correction
  brings the output closer than the static model alone; the ratio of the fast periods'
  harmonics to the slow one's, which the hysteresis does not enter, taken relative to
  the creep the static model predicts between the rates (``sample_period=``; the
  inverse undoes that creep itself); unit static gain, so the static model keeps the
  gain at rest), the dynamics inverted
  exactly per harmonic of the scan, their correction faded out below the band they
  were measured in (``HammersteinModel.trusted_from``, the 20 Hz record's fundamental:
  none up to 20 Hz, all from 80 Hz, over two octaves; on harmonic k of the scan from
  where the held-back records showed the correction to help on harmonic k,
  ``HammersteinModel.order_trusted_from``; ``--no-fade``: the whole inverse
  everywhere), then the same periodic hysteresis
  inverse (with creep) as the static inverse's; the static model's mean error on the
  1 Hz record (``HammersteinModel.static_offset``) bounds the share of the correction
  applied (``mean_error_share``) and how far the voltage's mean moves (``held_mean``);
- the learned feedforward: ``learn_periodic`` from that model, 10 trials; the RMS per
  trial, and the learned voltages played once more afterwards ("replay", fresh noise:
  the best trial's own figure is the lowest of several noisy measurements).

Each stage first settles on the static inverse's drive (``Stage.settle_on``: as if it had
scanned for hours, the slow creep settled): creep that keeps drifting is a
non-repeating disturbance no learning removes (docs/theory/learning.md). Every voltage
of every trial is checked against 0-150 V.

Targets: after 10 trials RMS <= 3 x the sensor noise at 10, 50 and 100 Hz; >= 25 x below
the static inverse at 100 Hz; every voltage within the limits. The learning was tuned on
the paper-beam stage (800 Hz, 4 %) and, for the second probe, on the s-shaped stage at
10 Hz; the lens and remanent stages, and the random stages of --fresh (hysteresis and
creep of ``random_plant(seed)``, one or two modes drawn from 500 Hz - 2 kHz and 1 - 10 %
damping; their hysteresis scaled to the issue's stages' 45 um range unless --unscaled),
are held out.

Run: python benchmarks/bench_learn.py [--quick] [--fresh N [FIRST_SEED]] [--unscaled]
     [--no-learning [--true-dynamics]] [--ratio-only] [--no-fade]
     [--learn-from-hammerstein] [--no-creep-ratio] [--former-rules] [--no-mean-rules]
     (--quick: 10, 50, 100 Hz and fmode/8 only; --fresh: N random stages from FIRST_SEED
     (default 1000) instead of the four named ones, at those rates; --no-learning: the
     static and Hammerstein inverses only, at 1, 10, 50, 100 Hz, fmode/8 and fmode/20
     (with --quick or --fresh too); --true-dynamics: beside them, the static model
     behind the stage's true modes and delay inverted per harmonic; --ratio-only: the
     Hammerstein model's dynamics from the ratio of rates alone, without the numerator's
     refit on the static model; --learn-from-hammerstein: learn from the Hammerstein
     model, its hysteresis with the static model's creep, instead of the static model;
     --no-creep-ratio: the dynamics measured without the static model's creep, as
     before; --former-rules: the Hammerstein model's order chosen on the 80 Hz record
     alone, its correction applied on every harmonic of the scan and the mean voltage
     as the inverse gives it, as before the held-back rules of fit_dynamics;
     --no-mean-rules: the held-back rules without those of the static model's mean
     error, as before mean_error_share and held_mean)
"""

import dataclasses
import sys
import time
import warnings

import numpy as np

import pihyst
from pihyst.dynamics import (
    fit_dynamics,
    held_mean,
    mean_error_share,
    periodic_inverse_dynamics,
)
from pihyst.dynamics._compensate import FADE_OCTAVES
from pihyst.exceptions import PihystWarning
from pihyst.inverse import compensate
from pihyst.learn import learn_periodic
from pihyst.learn._model_parts import model_parts, periodic_inverse
from pihyst.sim import Stage, make_stage, random_plant
from pihyst.sim.signals import band_limited_triangle, decaying_triangles

CLOCK_HZ = 20_000.0
NOISE_UM = 0.005
U_MIN, U_MAX = 0.0, 150.0
TRIALS = 10
RANDOM_RANGE_UM = 45.0
#: (label, beam, modes, seed, tuned on)
STAGES = [
    ("paper-beam 800 Hz 4 %", "paper-beam", ((800.0, 0.04),), 11, True),
    ("lens 500 Hz 2 %", "lens", ((500.0, 0.02),), 12, False),
    ("s-shaped 1.2 kHz 6 % + 3 kHz", "s-shaped", ((1200.0, 0.06, 0.8), (3000.0, 0.02, 0.2)),
     13, False),
    ("remanent 2 kHz 1 %", "remanent", ((2000.0, 0.01),), 14, False),
]


def named_stage(name, modes, seed, rate_hz=CLOCK_HZ, noise=True):
    return make_stage(name, modes=modes, rate_hz=rate_hz, delay_samples=1,
                      noise_um=NOISE_UM if noise else 0.0, seed=seed)


class ScaledHysteresis:
    """A hysteresis model's output times ``gain`` (the same loop shape, another range)."""

    def __init__(self, hysteresis, gain):
        self.hysteresis, self.gain, self.u_max = hysteresis, float(gain), hysteresis.u_max

    def reset(self):
        self.hysteresis.reset()

    def run(self, u):
        return self.gain * self.hysteresis.run(u)


def random_stage(seed, rate_hz=CLOCK_HZ, range_um=RANDOM_RANGE_UM, noise=True):
    """The hysteresis (scaled to a ``range_um`` rise from 0 V to 150 V, the issue's
    stages' range; None: as drawn) and creep of random_plant(seed), then one or two modes
    from 500 Hz - 2 kHz with 1 - 10 % damping (log-uniform), at the benchmark's clock."""
    plant, d = random_plant(seed)
    hysteresis = plant.hysteresis
    if range_um is not None:
        hysteresis = ScaledHysteresis(hysteresis, range_um / d["range_um"])
    rng = np.random.default_rng([0xBE7C, seed])
    f1 = float(10 ** rng.uniform(np.log10(500.0), np.log10(2000.0)))
    modes = [(f1, float(10 ** rng.uniform(-2, -1)), 1.0)]
    if rng.random() < 0.5:
        modes = [(f1, modes[0][1], 0.8), (f1 * float(rng.uniform(1.5, 4.0)),
                                          float(10 ** rng.uniform(-2, -1)), 0.2)]
    return Stage(f"random-{seed}", hysteresis, modes=modes, rate_hz=rate_hz,
                 delay_samples=1, creep_per_decade=d["creep_per_decade"],
                 noise_um=NOISE_UM if noise else 0.0,
                 quantum_V=0.01, seed=seed), modes


def fitted_model(make):
    """The default pihyst.fit model of a slow record (200 Hz) of the stage ``make(rate)``
    builds (with its creep)."""
    stage = make(200.0)
    t, u = decaying_triangles(U_MIN, U_MAX, period_s=1.0, n_triangles=4, dt=1 / 200.0)
    return pihyst.fit(u, stage.run(u), t=t).model


#: identification: one drive shape (a triangle's first ID_HARMONICS harmonics, ID_SPAN_V)
#: at a slow rate and at faster ones (Hz; the last chooses the order)
ID_SLOW_HZ = 1.0
ID_RATES = (20.0, 50.0, 100.0, 200.0, 80.0)
ID_SPAN_V = (10.0, 140.0)
ID_HARMONICS = 15


#: --former-rules: the order chosen on the last record alone within 1 %, the correction
#: on every harmonic from the slowest record's fundamental (pihyst before the
#: held-back rules; the figures' "before")
FORMER_RULES = "--former-rules" in sys.argv[1:]
#: --no-mean-rules: the Hammerstein inverse without the rules of the static model's mean
#: error (HammersteinModel.static_offset None: the whole correction where the held-back
#: rules allow it, the voltage's mean as the inverse gives it; pihyst before them)
MEAN_RULES = "--no-mean-rules" not in sys.argv[1:]


def hammerstein_model(make, model, numerator_on_static=True, keep_creep=False, fade=True,
                      no_creep=False):
    """``model`` followed by the stage's dynamics (``fit_dynamics``: the band-limited
    triangle of ID_HARMONICS harmonics over ID_SPAN_V at ID_SLOW_HZ and at ID_RATES, the
    stage settled on each; one period each)."""
    def period(rate):
        _, u = band_limited_triangle(*ID_SPAN_V, period_s=1 / rate,
                                     max_hz=(ID_HARMONICS + 0.5) * rate, dt=1 / CLOCK_HZ)
        stage = make(CLOCK_HZ)
        stage.settle_on(u)
        return u, stage.run_periodic(u)
    ham = fit_dynamics(model, period(ID_SLOW_HZ), [period(rate) for rate in ID_RATES],
                       numerator_on_static=numerator_on_static, keep_creep=keep_creep,
                       fade=fade, sample_period=None if no_creep else 1 / CLOCK_HZ,
                       **({"validation": -1, "tolerance": 0.01} if FORMER_RULES else {}))
    if FORMER_RULES:
        return dataclasses.replace(ham, order_trusted_from=(), static_offset=None)
    return ham if MEAN_RULES else dataclasses.replace(ham, static_offset=None)


def scan(make, rate_hz, fmode):
    """One period of the band-limited triangle over 80 % of the stage's range at that
    scan: the span a settled, noise-free copy of the stage covers when driven 0-150 V by
    the same band-limited triangle (the slow creep then sits at the scan's mean, so the
    range is less than the settled loop's)."""
    stage = make(CLOCK_HZ, noise=False)
    _, drive = band_limited_triangle(U_MIN, U_MAX, period_s=1 / rate_hz, max_hz=fmode / 2,
                                     dt=1 / CLOCK_HZ)
    stage.settle_on(drive)
    y = stage.run_periodic(drive)
    lo, hi = float(y.min()), float(y.max())
    span = hi - lo
    _, desired = band_limited_triangle(lo + 0.1 * span, lo + 0.9 * span, period_s=1 / rate_hz,
                                       max_hz=fmode / 2, dt=1 / CLOCK_HZ)
    return desired


class CheckedStage:
    """The stage's periodic player, counting the voltages outside the limits."""

    def __init__(self, stage):
        self.stage, self.outside, self.sent = stage, 0, 0

    def __call__(self, u):
        self.outside += int(np.count_nonzero((u < U_MIN) | (u > U_MAX)))
        self.sent += u.size
        return self.stage.run_periodic(u)


def rms(e):
    return float(np.sqrt(np.mean(np.square(e))))


def inverse_error(make, model, ham, desired):
    """RMS error of the Hammerstein inverse (``ham`` None: the static inverse, learning's
    trial 0) played periodically on a fresh stage settled on it, and the number of its
    voltages outside the limits."""
    parts = model_parts(model, 1 / CLOCK_HZ)
    u = periodic_inverse(parts, desired, U_MIN, U_MAX, None)
    if ham is not None:
        h_d = periodic_inverse_dynamics(ham.a[0], ham.b[0][0], desired, ham.trusted_from,
                                        ham.order_trusted_from)
        # the share of the correction the static model's mean error allows, then the
        # voltage's mean moved only as far as it allows
        h_d = desired + mean_error_share(desired, h_d, ham.static_offset) * (h_d - desired)
        u = held_mean(periodic_inverse(parts, h_d, U_MIN, U_MAX, None), u, desired,
                      ham.static_offset, U_MIN, U_MAX)
    stage = make(CLOCK_HZ)
    stage.settle_on(u)
    player = CheckedStage(stage)
    return rms(player(u) - desired), player.outside


def true_dynamics_error(make, model, modes, desired):
    """RMS error of the static model behind the stage's *true* dynamics, inverted per
    harmonic: its modes' continuous-time response sum_i g_i w_i^2 / (s^2 + 2 zeta_i w_i s
    + w_i^2) (shares normalised) times one tick of converter delay."""
    f = np.fft.rfftfreq(desired.size, 1 / CLOCK_HZ)
    s = 2j * np.pi * f
    shares = np.array([m[2] if len(m) > 2 else 1.0 for m in modes])
    G = sum(g / shares.sum() * (2 * np.pi * m[0]) ** 2
            / (s ** 2 + 4 * np.pi * m[1] * m[0] * s + (2 * np.pi * m[0]) ** 2)
            for g, m in zip(shares, modes)) * np.exp(-s / CLOCK_HZ)
    h_d = np.fft.irfft(np.fft.rfft(desired) / G, desired.size)
    u = periodic_inverse(model_parts(model, 1 / CLOCK_HZ), h_d, U_MIN, U_MAX, None)
    stage = make(CLOCK_HZ)
    stage.settle_on(u)
    player = CheckedStage(stage)
    return rms(player(u) - desired), player.outside


def run_stage(make, fmode, rates, learn=True, numerator_on_static=True, from_ham=False,
              fade=True, true_modes=None, no_creep=False):
    model = fitted_model(make)
    ham = hammerstein_model(make, model, numerator_on_static, fade=fade, no_creep=no_creep)
    learn_from = (hammerstein_model(make, model, numerator_on_static, keep_creep=True,
                                    no_creep=no_creep)
                  if from_ham else model)
    rows = []
    for rate in rates:
        desired = scan(make, rate, fmode)
        ham_rms, ham_out = inverse_error(make, model, ham, desired)
        static_rms, static_out = inverse_error(make, model, None, desired)
        if not learn:
            true_rms, true_out = (true_dynamics_error(make, model, true_modes, desired)
                                  if true_modes else (np.nan, 0))
            rows.append((rate, desired.size, static_rms, ham_rms,
                         static_out + ham_out + true_out, true_rms))
            continue
        stage = make(CLOCK_HZ)
        player = CheckedStage(stage)
        player.outside += ham_out + static_out
        t0 = time.perf_counter()
        start = compensate(model.replace(creep=None), desired, u_min=U_MIN, u_max=U_MAX)
        stage.settle_on(start.voltage)
        res = learn_periodic(player, desired, 1 / CLOCK_HZ, model=learn_from, u_min=U_MIN,
                             u_max=U_MAX, trials=TRIALS)
        replay = rms(player(res.voltage) - desired)
        rows.append((rate, desired.size, res, replay, player.outside, player.sent,
                     time.perf_counter() - t0, ham_rms, static_rms))
    return rows, ham


def main():
    quick = "--quick" in sys.argv[1:]
    learn = "--no-learning" not in sys.argv[1:]
    warnings.simplefilter("ignore", PihystWarning)
    t_all = time.perf_counter()
    print(f"stages: {CLOCK_HZ / 1000:g} kHz clock, 1 tick converter delay, sensor noise "
          f"{NOISE_UM} um RMS (3 x = {3 * NOISE_UM:.3f} um); RMS errors in um; "
          f"'replay': the learned voltages played again")
    checks = []
    scale = None if "--unscaled" in sys.argv[1:] else RANDOM_RANGE_UM
    args = [a for a in sys.argv[1:]
            if a not in ("--quick", "--unscaled", "--no-learning", "--ratio-only",
                         "--learn-from-hammerstein", "--no-fade", "--true-dynamics",
                         "--no-creep-ratio", "--former-rules", "--no-mean-rules")]
    if args and args[0] == "--fresh":
        n, first = int(args[1]), int(args[2]) if len(args) > 2 else 1000
        quick = True
        stages = []
        for seed in range(first, first + n):
            modes = random_stage(seed)[1]
            label = f"random {seed}: " + " + ".join(f"{m[0]:.0f} Hz {100 * m[1]:.1f} %"
                                                    for m in modes)
            stages.append((label, lambda r, noise=True, seed=seed: random_stage(
                seed, r, scale, noise)[0], modes, seed, False))
    else:
        stages = [(label, lambda r, noise=True, name=name, modes=modes, seed=seed: named_stage(
            name, modes, seed if r == CLOCK_HZ else seed + 100, r, noise), modes, seed, tuned)
                  for label, name, modes, seed, tuned in STAGES]
    for label, make, modes, seed, tuned in stages:
        fmode = modes[0][0]
        rates = [10.0, 50.0, 100.0] if quick and learn else [1.0, 10.0, 50.0, 100.0]
        rates += [] if fmode / 8 in rates else [fmode / 8]
        # without learning (cheap): also the boundary, fmode/20
        rates += [] if learn or fmode / 20 in rates else [fmode / 20]
        tag = "tuned on" if tuned else "held out"
        print(f"\n{label} (seed {seed}, {tag})")
        rows, ham = run_stage(make, fmode, rates, learn, "--ratio-only" not in sys.argv[1:],
                              "--learn-from-hammerstein" in sys.argv[1:],
                              "--no-fade" not in sys.argv[1:],
                              modes if "--true-dynamics" in sys.argv[1:] else None,
                              "--no-creep-ratio" in sys.argv[1:])
        print(f"  Hammerstein: na {ham.a[0].size - 1}, nb {ham.b[0].shape[1]}; poles "
              + ", ".join(f"{abs(np.log(p)) * CLOCK_HZ / (2 * np.pi):.0f} Hz"
                          for p in np.roots(ham.a[0]) if p.imag >= 0)
              + f"; correction faded in from {ham.trusted_from * CLOCK_HZ:g} Hz to "
                f"{2 ** FADE_OCTAVES * ham.trusted_from * CLOCK_HZ:g} Hz"
              + ("; on harmonics 1, 3, 5, 7 from " + ", ".join(
                  "never" if t >= 0.5 else f"{t * CLOCK_HZ:g} Hz"
                  for t in ham.order_trusted_from[0:7:2]) if ham.order_trusted_from else ""))
        if not learn:
            print(f"{'rate Hz':>8} {'N':>6} {'static':>7} {'hammer':>7} {'ratio':>6}"
                  + (f" {'true G':>7} {'ratio':>6}" if "--true-dynamics" in sys.argv else ""))
            for rate, n, static_rms, ham_rms, outside, true_rms in rows:
                print(f"{rate:8.4g} {n:6d} {static_rms:7.4f} {ham_rms:7.4f} "
                      f"{ham_rms / static_rms:6.3f}"
                      + (f" {true_rms:7.4f} {true_rms / static_rms:6.3f}"
                         if "--true-dynamics" in sys.argv else ""))
                checks.append((tuned, rate, None, None, outside, static_rms, ham_rms, fmode))
            continue
        print(f"{'rate Hz':>8} {'N':>6} {'static':>7} {'hammer':>7} {'t0':>7} "
              + " ".join(f"{'t' + str(j):>6}" for j in range(1, TRIALS + 1))
              + f" {'replay':>7} {'/noise':>6} {'gain':>6} {'V out':>5} {'s':>5}  stop")
        for rate, n, res, replay, outside, _, secs, ham_rms, static_rms in rows:
            improvement = res.rms[0] / replay
            print(f"{rate:8.4g} {n:6d} {static_rms:7.4f} {ham_rms:7.4f} {res.rms[0]:7.4f} "
                  + " ".join(f"{e:6.4f}" for e in res.rms[1:])
                  + " " * 7 * (TRIALS - res.rms.size + 1)
                  + f" {replay:7.4f} {replay / NOISE_UM:6.2f} {improvement:6.1f} "
                    f"{outside:5d} {secs:5.1f}  {res.reason[:40]}")
            checks.append((tuned, rate, replay, improvement, outside, static_rms, ham_rms,
                           fmode))
    above = [c for c in checks if c[1] > c[7] / 20]
    below = [c for c in checks if c[1] <= c[7] / 20]
    print(f"\nHammerstein inverse (all stages): below the static inverse at every rate above "
          f"fmode/20: {sum(c[6] < c[5] for c in above)} of {len(above)}; not above it at "
          f"or below fmode/20: {sum(c[6] <= c[5] for c in below)} of {len(below)}; "
          f"ratio to the static: {min(c[6] / c[5] for c in checks):.4f} - "
          f"{max(c[6] / c[5] for c in checks):.4f}; worst at or below fmode/20 "
          f"{max(c[6] / c[5] for c in below):.5f}, worst above "
          f"{max(c[6] / c[5] for c in above):.4f}")
    held = [c for c in checks if not c[0]]
    if not learn:
        print(f"voltages outside {U_MIN:g}-{U_MAX:g} V: {sum(c[4] for c in checks)}")
        return
    print(f"\ntargets on the held-out stages ({len({c[1] for c in held})} rates):")
    at = [c for c in held if c[1] in (10.0, 50.0, 100.0)]
    ok_noise = sum(c[2] <= 3 * NOISE_UM for c in at)
    ok_gain = sum(c[3] >= 25 for c in held if c[1] == 100.0)
    n100 = sum(1 for c in held if c[1] == 100.0)
    print(f"  replay <= 3 x noise at 10, 50, 100 Hz: {ok_noise} of {len(at)}; worst "
          f"{max(c[2] for c in at) / NOISE_UM:.2f} x noise")
    print(f"  >= 25 x below the static inverse at 100 Hz: {ok_gain} of {n100}; least "
          f"{min(c[3] for c in held if c[1] == 100.0):.1f} x")
    print(f"  voltages outside {U_MIN:g}-{U_MAX:g} V in any trial, any stage: "
          f"{sum(c[4] for c in checks)}")
    print(f"total {time.perf_counter() - t_all:.0f} s wall, {time.process_time():.0f} s CPU")


if __name__ == "__main__":
    main()
