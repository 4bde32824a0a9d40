"""The Bouc-Wen family: fitted alone or compared with the PI families on the same cycles."""

import itertools

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pihyst import FitError, compensate, fit
from pihyst.identify import FAMILY_NAMES, BoucWen
from pihyst.identify._boucwen import _nnls, start_sensitivity
from pihyst.model import BoucWenModel
from pihyst.model._boucwen import cycled_z, trajectory
from pihyst.sim import make_plant
from pihyst.sim.signals import decaying_triangles


def record(model, n_triangles=3):
    t, u = decaying_triangles(n_triangles=n_triangles, dt=1.0)
    return u, model.predict(u)


TRUE = BoucWenModel(beta=6.0, gamma=1.5, n=1.0, hysteretic=-12.0, linear=40.0,
                    quadratic=3.0, offset=0.2)


def test_recovers_a_bouc_wen_model_from_its_own_output():
    u, y = record(TRUE)
    res = fit(u, y, family="bouc-wen")
    m = res.model
    assert isinstance(m, BoucWenModel) and res.report.chosen == "bouc-wen"
    assert np.sqrt(np.mean((m.predict(u) - y) ** 2)) < 1e-3 * np.ptp(y)
    assert m.is_monotone
    # the fitted model predicts a new input with minor loops as well
    rng = np.random.default_rng(4)
    v = np.clip(np.cumsum(rng.normal(0, 6, 400)) % 300, 0, 300)
    v = np.where(v > 150, 300 - v, v)
    assert np.max(np.abs(m.predict(v) - TRUE.predict(v))) < 5e-3 * np.ptp(y)


def _nnls_every_active_set(G, b):
    """The plain twin: min v'Gv - 2 b'v over v >= 0 by trying every active set."""
    best, best_v = np.inf, np.zeros(b.size)
    for r in range(b.size + 1):
        for free in itertools.combinations(range(b.size), r):
            v = np.zeros(b.size)
            if free:
                idx = list(free)
                sol = np.linalg.lstsq(G[np.ix_(idx, idx)], b[idx], rcond=1e-12)[0]
                if np.any(sol < 0):
                    continue
                v[idx] = sol
            obj = float(v @ G @ v - 2 * b @ v)
            if obj < best:
                best, best_v = obj, v
    return best_v


@given(st.integers(0, 2**32 - 1), st.sampled_from(["full", "collinear", "zero column"]))
def test_nnls_reaches_the_minimum_of_every_active_set(seed, kind):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(40, 3)) * rng.uniform(1e-3, 1e3, 3)
    if kind == "collinear":
        X[:, 2] = 2.0 * X[:, 0]
    elif kind == "zero column":
        X[:, 1] = 0.0
    y = rng.normal(size=40) * rng.uniform(1e-3, 1e3)
    fast, plain = _nnls(X, y), _nnls_every_active_set(X.T @ X, X.T @ y)
    assert np.all(fast >= 0) and np.all(np.isfinite(fast))
    if kind == "zero column":
        assert fast[1] == 0.0

    def rss(v):
        return float(np.sum((X @ v - y) ** 2))

    assert rss(fast) <= rss(plain) * (1 + 1e-9) + 1e-12 * float(y @ y)


@given(st.floats(0.5, 60.0), st.floats(-0.8, 0.8), st.floats(1.0, 3.0),
       st.integers(0, 2**32 - 1))
def test_start_sensitivity_is_the_derivative_of_z_by_its_start(beta, ratio, n, seed):
    """The exact variational product (ratios of g_s along z) against a finite
    difference of two C-core trajectories, on random inputs with reversals (they differ
    by the core's Runge-Kutta error, up to ~1e-4 where z crosses 0 with n near 1)."""
    gamma = ratio * beta
    rng = np.random.default_rng(seed)
    x = np.abs(np.sin(np.cumsum(rng.uniform(0.0, 0.08, 300))))
    x[rng.integers(0, 300, 20)] = x[rng.integers(0, 300, 20)]   # repeated samples
    z0 = cycled_z(beta, gamma, n)
    z = trajectory(x, 0.0, z0, beta, gamma, n)
    s = start_sensitivity(x, 0.0, z0, z, beta, gamma, n)
    h = -np.sign(z0) * 1e-7 * (beta + gamma) ** (-1.0 / n)   # towards 0: within |z| <= z_max
    diff = (trajectory(x, 0.0, z0 + h, beta, gamma, n) - z) / h
    assert np.all((s >= 0) & (s <= 1))
    assert np.max(np.abs(s - diff)) < 1e-3


@pytest.mark.parametrize("peak", [0.2, 0.5])
def test_record_after_a_partial_cycle_fits_the_actuator_at_rest(peak):
    """A record that starts at 0 V but not at rest after a full cycle (a partial cycle
    to ``peak`` of the range before it, as of an actuator used a moment earlier), of a
    Bouc-Wen actuator whose z forgets its start slowly: the fit takes the start of z as
    unknown (a free column along dz/dz0) and still finds the actuator, which it then
    predicts from rest within 0.5 % of the range (0.11-0.20 %). Taking the start for the
    rest state erred 10-14 % of the range here."""
    slow = BoucWenModel(beta=2.0, gamma=0.5, n=1.0, hysteretic=-12.0, linear=40.0,
                        quadratic=3.0, offset=0.2)
    history = np.r_[np.linspace(0, 150 * peak, 200), np.linspace(150 * peak, 0, 200)]
    state = slow.simulate(history).final_state
    u, _ = record(slow, n_triangles=2)
    y = slow.replace(initial_state=state).predict(u)
    m = fit(u, y, family="bouc-wen").model
    rng = np.random.default_rng(4)
    v = np.clip(np.cumsum(rng.normal(0, 6, 400)) % 300, 0, 300)
    v = np.where(v > 150, 300 - v, v)
    assert np.max(np.abs(m.predict(v) - slow.predict(v))) < 5e-3 * np.ptp(y)


@pytest.mark.slow
def test_compared_with_the_pi_families_by_default_and_wins_on_a_remanent_beam():
    t, u = decaying_triangles(dt=1.0)
    y = make_plant("remanent", seed=1, creep=False).run(u, t)
    assert "bouc-wen" in FAMILY_NAMES              # in the default comparison
    res = fit(u, y)
    rep = res.report.to_dict()
    assert {f["family"] for f in rep["families"]} == set(FAMILY_NAMES)
    assert res.report.chosen == "bouc-wen"
    assert isinstance(res.model, BoucWenModel)
    assert res.model.metadata["fit"]["family"] == "bouc-wen"
    out = compensate(res.model, np.linspace(5, 40, 50))
    assert np.all(out.reached)


def test_options_it_cannot_honour_are_errors():
    u, y = record(TRUE, n_triangles=2)
    with pytest.raises(FitError, match="drop thresholds"):
        fit(u, y, family="bouc-wen", thresholds=[0, 10])
    with pytest.raises(FitError, match="fixed offset"):
        fit(u, y, family="bouc-wen", offset=0.0)


def test_latency_of_a_bouc_wen_model_is_measured_on_its_c_compensator(monkeypatch):
    from pihyst.identify._latency import measure_latency
    from pihyst.inverse._boucwen import BoucWenCompensatorTwin

    def twin_step(self, y_desired):
        raise AssertionError("the latency must be that of the C compensator, not the twin")

    monkeypatch.setattr(BoucWenCompensatorTwin, "step", twin_step)
    lat = measure_latency(TRUE)
    assert 0 < lat.typical < 1e-2 and 0 < lat.worst < 1e-2
    assert "(C)" in lat.to_dict()["measured"]
    # and the fit report carries it
    u, y = record(TRUE, n_triangles=2)
    entry = fit(u, y, family="bouc-wen").report.family("bouc-wen")
    assert entry["latency"]["typical_us"] > 0 and entry["latency"]["worst_us"] > 0


@pytest.mark.slow
def test_a_lagged_bouc_wen_record_gives_a_delayed_bouc_wen_model():
    truth = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)
    legs = [(0, 150, 100), (150, 0, 100), (0, 110, 80), (110, 40, 50), (40, 150, 80),
            (150, 0, 100)]
    u = np.concatenate([np.linspace(a, b, n) for a, b, n in legs] * 3)
    y = truth.replace(delay=2).predict(u)
    res = fit(u, y, family="bouc-wen")
    assert isinstance(res.model, BoucWenModel) and res.model.delay == 2
    e = res.model.predict(u) - y
    assert np.sqrt(np.mean(e ** 2)) < 0.01 * np.ptp(y)


def test_a_long_record_is_fitted_on_its_extrema_and_evenly_spaced_samples(monkeypatch):
    from pihyst.identify._boucwen import FAMILY_SAMPLES
    from pihyst.identify._family_fit import FamilyFitter
    t, u = decaying_triangles(n_triangles=3, dt=0.01)
    assert u.size > 2 * FAMILY_SAMPLES
    y = TRUE.predict(u)
    subsampled = []                   # (limit, samples before, samples after) per call
    real = FamilyFitter.subsampled

    def spy(self, max_samples, note=None):
        out = real(self, max_samples, note)
        subsampled.append((max_samples, self.rec.u.size, out.rec.u.size))
        return out
    monkeypatch.setattr(FamilyFitter, "subsampled", spy)
    res = fit(u, y, family=BoucWen())
    assert [(limit, before) for limit, before, _ in subsampled] == [(FAMILY_SAMPLES, u.size)]
    assert subsampled[0][2] < 1.1 * FAMILY_SAMPLES
    # z at the kept samples is that of the whole record: the model is recovered
    sub = u[:: u.size // 2000]
    assert np.max(np.abs(res.model.predict(sub) - TRUE.predict(sub))) < 2e-3 * np.ptp(y)


@given(st.floats(-60.0, 60.0), st.floats(-60.0, 60.0), st.floats(-5.0, 15.0),
       st.sampled_from([None, 1.0, 2.5]))
def test_shape_search_points_are_models_or_refused(log_beta, atanh_ratio, n, fixed_n):
    """Every point of the shape search maps to a shape the model (and its C core)
    accepts, or to None: tanh rounds to exactly 1 beyond about 19, and gamma = beta
    once reached the C core from the search and ended the fit in a CoreError."""
    from pihyst.identify._boucwen import searched_shape

    shape = searched_shape(np.array([log_beta, atanh_ratio, n]), fixed_n)
    if shape is None:
        return
    beta, gamma, nn = shape
    model = BoucWenModel(beta=beta, gamma=gamma, n=nn, hysteretic=1.0, linear=0.0,
                         input_range=(0.0, 1.0))
    assert np.all(np.isfinite(model.predict(np.array([0.0, 1.0, 0.3]))))
    if fixed_n is not None:
        assert nn == fixed_n


def test_shape_search_refuses_the_rounded_edge():
    from pihyst.identify._boucwen import searched_shape

    assert searched_shape(np.array([0.0, 30.0, 1.0])) is None     # gamma = beta
    assert searched_shape(np.array([0.0, -30.0, 1.0])) is None    # gamma = -beta
    assert searched_shape(np.array([0.0, 0.5, 1.0])) is not None


def test_the_shape_is_refined_only_where_bouc_wen_can_come_near_the_best_family(monkeypatch):
    """Nelder-Mead after the grid costs most of a Bouc-Wen fit; in the comparison of
    families it runs only where the grid's best shape is within REFINE_REACH of the best
    PI family's judged RMS (identify/_boucwen.py)."""
    import scipy.optimize

    from pihyst import ClassicalPI
    from pihyst.identify._boucwen import REFINE_REACH

    refined = []                 # Bouc-Wen's Nelder-Mead runs of the fit, in order
    real = scipy.optimize.minimize

    def spy(fun, *args, **kwargs):
        owner = type(getattr(fun, "__self__", None)).__module__
        refined.append(owner == "pihyst.identify._boucwen" and
                       kwargs.get("method") == "Nelder-Mead")
        return real(fun, *args, **kwargs)
    monkeypatch.setattr(scipy.optimize, "minimize", spy)

    def refines(*args, **kwargs):
        refined.clear()
        report = fit(*args, **kwargs).report
        return any(refined), report

    u, y_true = record(TRUE)
    pi = ClassicalPI([0, 20, 50], [0.2, 0.1, 0.05])
    y = pi.predict(u) + np.random.default_rng(0).normal(0, 1e-4, u.size)
    did, report = refines(u, y)
    best_pi = min(f["judged_rms"] for f in report.families if f["family"] != "bouc-wen")
    assert not did and report.family("bouc-wen")["judged_rms"] > REFINE_REACH * best_pi
    assert refines(u, y, family="bouc-wen")[0]      # alone: nothing to come near
    did, report = refines(u, y_true)
    assert did and report.family("bouc-wen")["judged_rms"] < 1e-3 * np.ptp(y_true)
