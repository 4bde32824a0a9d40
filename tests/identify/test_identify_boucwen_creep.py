"""fit(u, y, t=..., family="bouc-wen", creep=...) (docs/theory/creep.md): a Bouc-Wen
actuator with log-t creep is recovered (shape, linear part and creep gains), its creep
predicts held levels the rate-independent fit cannot, the default creep="auto" keeps it
on such a record and leaves it out of one without creep, and the result is a valid,
invertible, saveable model."""

import numpy as np
import pytest

import pihyst
from pihyst.identify._creep import _joint_qp_boucwen, log_t_basis
from pihyst.model import BoucWenModel, Creep
from pihyst.sim import signals

TAU = 0.3 * 10 ** (0.5 * np.arange(5))          # 0.3 s .. 30 s
SHAPE = {"beta": 4.0, "gamma": 1.0, "n": 1.5, "hysteretic": -5.0, "linear": 40.0,
         "quadratic": 3.0, "offset": 0.2}


@pytest.fixture(scope="module")
def truth():
    gains = log_t_basis(TAU.size) @ np.array([0.008, 0.006])
    return BoucWenModel(**SHAPE, creep=Creep(TAU, gains, dt=0.1))


@pytest.fixture(scope="module")
def record(truth):
    t, u = signals.decaying_triangles(period_s=40.0, dt=0.1)
    y = truth.predict(u, t=t) + np.random.default_rng(0).normal(0, 0.002, u.size)
    return t, u, y


@pytest.fixture(scope="module")
def fitted(record):
    t, u, y = record
    kw = {"family": "bouc-wen", "input_range": (0.0, 150.0)}
    return pihyst.fit(u, y, **kw).model, pihyst.fit(u, y, t=t, creep=TAU, **kw).model


def test_joint_qp_recovers_the_linear_part_and_gains_for_the_true_shape(truth, record):
    t, u, y = record
    start = truth.replace(creep=None, hysteretic=-3.0, linear=30.0, quadratic=0.0)
    dt = np.r_[0.1, np.diff(t)]
    hyst, gains, passes = _joint_qp_boucwen(start, u, y, dt, TAU, start=0, offset=True)
    np.testing.assert_allclose(gains, truth.creep.gain, atol=1e-3)
    for k in ("hysteretic", "linear", "quadratic", "offset"):
        assert getattr(hyst, k) == pytest.approx(SHAPE[k], abs=0.02 * abs(SHAPE[k]) + 0.01)
    assert 1 <= passes <= 6 and hyst.is_monotone


def test_creep_recovered_and_predicts_held_levels(truth, fitted):
    plain, model = fitted
    assert isinstance(model, BoucWenModel) and model.creep is not None
    np.testing.assert_allclose(model.creep.tau, TAU)
    assert model.creep.gain.sum() == pytest.approx(truth.creep.gain.sum(), rel=0.25)
    info = model.metadata["fit"]["creep"]
    assert info["rms_with_creep"] < 0.5 * info["rms_without_creep"]
    assert model.is_monotone
    # held levels: a staircase with 20 s holds
    t, u = signals.staircase(u_min=0.0, u_max=150.0, n_steps=5, step_s=20.0, dt=0.1)
    y = truth.predict(u, t=t)
    err_creep = np.mean(np.abs(model.predict(u, t=t) - y))
    err_plain = np.mean(np.abs(plain.predict(u) - y))
    assert err_creep < 0.3 * err_plain
    # and its exact inverse tracks the staircase on the truth
    comp = pihyst.compensate(model, np.clip(y, y.min() + 1, y.max() - 1), t=t)
    assert np.all((comp.voltage >= 0.0) & (comp.voltage <= 150.0))
    tracked = truth.predict(comp.voltage, t=t)
    assert np.mean(np.abs(tracked - comp.desired)) < 0.3 * err_plain


def test_model_with_creep_round_trips(fitted, tmp_path):
    _, model = fitted
    path = tmp_path / "bw.json"
    model.save(path)
    assert pihyst.load_model(path) == model


# the rule that keeps creep or leaves it out is the same for every family
# (_creep._judge): quick with a classical PI in test_identify_creep.py; Bouc-Wen's joint
# creep fit quick above (test_creep_recovered_and_predicts_held_levels)
@pytest.mark.slow
def test_default_fit_keeps_creep_where_held_back_cycles_need_it(record):
    t, u, y = record
    res = pihyst.fit(u, y, t=t, family="bouc-wen", input_range=(0.0, 150.0))
    decision = res.model.metadata["fit"]["creep"]["decision"]
    assert decision["kept"] and res.model.creep is not None, decision["reason"]
    assert decision["held_back_rms_with"] < decision["held_back_rms_without"]
    assert res.report.to_dict()["creep"]["kept"]


@pytest.mark.slow
def test_default_fit_leaves_out_creep_an_actuator_does_not_have(truth, record):
    t, u, _ = record
    y = truth.replace(creep=None).predict(u) + \
        np.random.default_rng(1).normal(0, 0.002, u.size)
    res = pihyst.fit(u, y, t=t, family="bouc-wen", input_range=(0.0, 150.0))
    assert res.model.creep is None
    assert not res.model.metadata["fit"]["creep"]["decision"]["kept"]


def test_creep_true_with_a_fixed_exponent_and_without_times(record):
    t, u, y = record
    res = pihyst.fit(u, y, t=t, family=pihyst.identify.BoucWen(n=1.5), creep=True,
                     input_range=(0.0, 150.0))
    assert res.model.creep is not None and res.model.n == 1.5
    assert res.model.metadata["fit"]["creep"]["creep_total"] > 0
    with pytest.raises(pihyst.FitError, match="sample times"):
        pihyst.fit(u, y, family="bouc-wen", creep=True)
