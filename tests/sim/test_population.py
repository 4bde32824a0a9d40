"""Random actuators (pihyst.sim.random_plant), the Bouc-Wen exponent n, the growing sine,
and (slow) the population study on a handful of actuators with a loose bound."""

import copy

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pihyst.sim import random_plant, signals
from pihyst.sim._boucwen import BoucWen


def test_random_plant_is_deterministic_and_described():
    kinds, strong = set(), []
    for seed in range(12):
        a, da = random_plant(seed)
        if seed < 3:   # the same seed, the same actuator and the same output
            b, db = random_plant(seed)
            assert da == db
            t = np.arange(400) * 1e-3
            u = 75 + 70 * np.sin(np.linspace(0, 6 * np.pi, 400))
            np.testing.assert_array_equal(a.run(u, t), b.run(u, t))
        assert 200 <= da["rate_hz"] <= 10_000
        assert da["range_um"] > 0 and da["noise_um"] > 0
        kinds.add(da["kind"])
        if da["kind"] == "bouc-wen":
            assert 1 <= da["n"] <= 2
            assert 1.0 <= da["remanence_pct"] <= 20.0
            strong += [da["remanence_pct"]] if da["strong_remanence"] else []
            # the remanence is what the plant (creep, noise and supply steps aside) shows
            # at rest after the full cycle
            bare = a.__class__(a.name, copy.deepcopy(a.hysteresis))
            rest = bare.run(np.zeros(1), np.zeros(1))[0]
            assert 100 * rest / da["range_um"] == pytest.approx(da["remanence_pct"],
                                                                abs=0.5)
    assert kinds == {"preisach", "bouc-wen"}
    assert strong and all(10 <= r <= 20 for r in strong)


def test_bouc_wen_exponent_one_matches_the_closed_form():
    u = np.r_[np.linspace(0, 150, 301), np.linspace(149.5, 40, 220), np.linspace(40.5, 120, 160)]
    closed = BoucWen(150.0, d=0.3, alpha=0.4, beta=0.03, gamma=0.005)
    numeric = BoucWen(150.0, d=0.3, alpha=0.4, beta=0.03, gamma=0.005, n=1 + 1e-12)
    np.testing.assert_allclose(numeric.run(u), closed.run(u), atol=1e-8)


@settings(max_examples=25)
@given(st.floats(1.0, 2.0), st.floats(-0.6, 0.6), st.floats(0.3, 1.0), st.integers(0, 999))
def test_bouc_wen_any_exponent_is_monotone_and_bounded(n, rho, a_frac, seed):
    alpha = a_frac * (1 + rho) / 2
    h_sat = 10.0
    beta = alpha * 0.3 / (h_sat ** n * (1 + rho))
    bw = BoucWen(150.0, d=0.3, alpha=alpha, beta=beta, gamma=rho * beta, n=n)
    assert bw.h_saturation == pytest.approx(h_sat)
    rng = np.random.default_rng(seed)
    levels = rng.uniform(0, 150, 8)
    u = np.concatenate([np.linspace(a, b, 60) for a, b in zip(np.r_[0, levels], levels)])
    y = bw.run(u)
    du, dy = np.diff(u), np.diff(y)
    assert np.all(dy * np.sign(du) >= -1e-9)       # never runs against the voltage
    assert abs(bw.state[1]) <= h_sat * (1 + 1e-6)


def test_growing_sine_grows_to_the_full_range():
    t, u = signals.growing_sine(u_min=10.0, u_max=110.0, period_s=10.0, n_cycles=4, dt=0.05)
    assert u[0] == 10.0 and u.min() >= 10.0 and u.max() <= 110.0
    peaks = [u[(t >= k * 10) & (t < (k + 1) * 10)].max() for k in range(4)]
    assert np.all(np.diff(peaks) > 0) and peaks[-1] > 0.95 * 110.0 - 0.05 * 10.0


@pytest.mark.slow
def test_population_handful_within_a_loose_bound():
    """Four Preisach actuators of the benchmark's population recorded with minor loops
    (decaying triangles): with creep in the model, validation and tracking errors stay
    within 0.5 % of range each, and creep in the model helps where the actuator creeps.
    (The benchmark prints the distribution over 30, Bouc-Wen and triangle records
    included.)"""
    import warnings

    from pihyst.exceptions import PihystWarning
    from pihyst.study._population import evaluate_plant

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PihystWarning)
        results = [evaluate_plant(seed, samples_per_cycle=3000) for seed in (0, 3, 5, 11)]
    for r in results:
        assert r.description["kind"] == "preisach" and r.record == "decaying-triangles"
        for task in ("validation", "tracking"):
            assert r.mean(True, task) < 0.5, (r.seed, task, r.errors)
            if r.description["creep_per_decade"] > 0.005:
                assert r.mean(True, task) < r.mean(False, task), (r.seed, task, r.errors)


@pytest.mark.slow
def test_population_bouc_wen_actuators_that_creep():
    """Bouc-Wen actuators of the population that creep (1.7-2.4 %/decade), one recorded
    on decaying triangles and one on the two-cycle triangle: the default fit with the
    record's sample times keeps Bouc-Wen with creep and stays within 0.1 % of range on
    ramps and 10-60 s staircases, validation and tracking (without creep in the model:
    about 1 %)."""
    import warnings

    from pihyst.exceptions import PihystWarning
    from pihyst.study._population import evaluate_plant

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PihystWarning)
        results = [evaluate_plant(seed, samples_per_cycle=3000) for seed in (8, 16)]
    for r in results:
        assert r.description["kind"] == "bouc-wen" and r.families[True] == "bouc-wen"
        assert r.description["creep_per_decade"] > 0.015 and r.creep_gain > 0
        for task in ("validation", "tracking"):
            assert r.mean(True, task) < 0.1, (r.seed, task, r.errors)
            assert r.mean(False, task) > 0.5, (r.seed, task, r.errors)


@pytest.mark.slow
def test_population_preisach_on_a_triangle_keeps_its_own_creep_estimate():
    """A Preisach actuator of the population (2 terms, 2.2 %/decade) recorded on the
    two-cycle triangle, where Bouc-Wen fits the major loop best without creep: creep is
    estimated with each kind of model (Bouc-Wen and PI operators), and the structure
    chosen on the record without the PI estimate wins the held-back cycles. The Bouc-Wen
    estimate alone led to Bouc-Wen with creep: on this shorter record (3000 samples per
    cycle) 0.97 % of range in validation and 1.16 % in tracking, now 0.43 and 0.44 %
    (the benchmark's full record: 1.04 / 1.12 % before, 0.22 / 0.21 % now)."""
    import warnings

    from pihyst.exceptions import PihystWarning
    from pihyst.study._population import evaluate_plant

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PihystWarning)
        r = evaluate_plant(28, samples_per_cycle=3000)
    assert r.description["kind"] == "preisach" and r.record == "triangle"
    assert r.families[False] == "bouc-wen" and r.families[True] != "bouc-wen"
    for task in ("validation", "tracking"):
        assert r.mean(True, task) < 0.6, (task, r.errors)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [24, 14])
def test_population_preisach_on_a_triangle_minor_loops_from_the_kp_prior(seed):
    """Preisach actuators of the population recorded on the two-cycle triangle only: the
    minor loops of ramps and staircases are left to the kp basis's prior. Pulled towards
    a PI-type density it erred (this shorter record, validation / tracking) 1.00 / 1.35 %
    (seed 24) and 0.55 / 1.03 % (seed 14); the mean of a separable and a product-form
    density: 0.41 / 0.53 % and 0.26 / 0.42 %."""
    import warnings

    from pihyst.exceptions import PihystWarning
    from pihyst.study._population import evaluate_plant

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PihystWarning)
        r = evaluate_plant(seed, samples_per_cycle=3000)
    assert r.description["kind"] == "preisach" and r.record == "triangle"
    assert r.families[True] == "kp"
    for task in ("validation", "tracking"):
        assert r.mean(True, task) < 0.65, (task, r.errors)
