"""Dynamics after a given static model (fit_dynamics), the periodic stable inverse, and
Hammerstein model files."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.signal import lfilter

from pihyst.dynamics import (
    HammersteinModel,
    compensate_hammerstein,
    fit_dynamics,
    load_hammerstein,
    periodic_inverse_dynamics,
)
from pihyst.exceptions import InvalidArgumentError, InvalidModelError
from pihyst.inverse import compensate
from pihyst.model import BoucWenModel, ClassicalPI

N = 1000


def mode(r=0.97, theta=0.2):
    return np.poly([r * np.exp(1j * theta), r * np.exp(-1j * theta)]).real


def periodic_output(a, b, h, periods=60):
    """The last period of B/A driven by h repeated (steady state)."""
    return lfilter(b, a, np.tile(h, periods))[-h.size:]


def static_model():
    return ClassicalPI([0, 15, 30, 45], [0.3, 0.25, 0.15, 0.1], input_range=(0.0, 150.0))


def records(H, a, b, gain=1.0):
    out = []
    for k, rate in enumerate((3, 7, 13)):
        t = np.arange(N)
        u = 75 + 60 * np.sin(2 * np.pi * rate * t / N + k) * np.cos(2 * np.pi * t / N)
        h = H.predict(np.tile(u, 2))[N:]
        out.append((np.tile(u, 2), np.tile(gain * periodic_output(a, b, h), 2)))
    return out


@pytest.mark.parametrize("b", [[0.0, 0.9, 0.5], [0.0, 0.5, 0.9]])   # zero inside, outside
def test_the_periodic_inverse_is_exact(b):
    a = mode()
    t = np.arange(N)
    ref = 20 + 10 * np.sin(2 * np.pi * 3 * t / N) + 2 * np.cos(2 * np.pi * 40 * t / N)
    h = periodic_inverse_dynamics(a, b, ref)
    assert np.max(np.abs(periodic_output(a, b, h, 200) - ref)) < 1e-9 * np.ptp(ref)


@pytest.mark.parametrize("gain", [1.0, 0.9])
def test_fit_dynamics_recovers_the_dynamics_with_unit_static_gain(gain):
    """Noise-free records of a known Hammerstein system: the dynamics come back, scaled to
    unit static gain whatever gain the records add (the static model keeps the gain)."""
    H, a = static_model(), mode()
    b = np.array([0.0, 0.9, 0.5]) * a.sum() / 1.4
    model = fit_dynamics(H, records(H, a, b, gain), N, orders=((2, 2), (2, 3), (4, 4)))
    assert np.allclose(model.static_gain(), 1.0)
    assert model.a[0].size == 3 and model.b[0].shape == (1, 3)
    assert np.allclose(model.a[0], a, atol=1e-8)
    assert np.allclose(model.b[0][0], b, atol=1e-8)


def test_the_hammerstein_inverse_becomes_the_static_inverse_at_low_rates():
    """Unit static gain: on a slow periodic trajectory the Hammerstein inverse's
    voltages are the static inverse's (to the dynamics' effect at that rate)."""
    H, a = static_model(), mode()
    b = np.array([0.0, 0.9, 0.5]) * a.sum() / 1.4 * 0.8      # dynamics with gain 0.8
    model = fit_dynamics(H, records(H, a, b), N, validation=None, orders=((2, 3),))
    t = np.arange(20 * N)
    desired = 20 + 10 * np.sin(2 * np.pi * t / t.size)
    u_ham = compensate_hammerstein(model, desired, periodic=True)[0]
    u_static = compensate(H, np.tile(desired, 2)).voltage[t.size:]
    assert np.max(np.abs(u_ham - u_static)) < 0.01 * np.ptp(u_static)


def test_fit_dynamics_takes_any_static_family_and_drops_creep_and_delay():
    bw = BoucWenModel(beta=0.02, gamma=0.01, n=1.0, hysteretic=0.2, linear=0.25,
                      input_range=(0.0, 150.0), delay=2, sample_period=1e-3)
    a = mode()
    b = np.array([0.0, 0.9, 0.5]) * a.sum() / 1.4
    model = fit_dynamics(bw, records(bw.replace(delay=0), a, b), N, orders=((2, 3),),
                         validation=None)
    assert model.hysteresis[0].family == "bouc-wen" and model.hysteresis[0].delay == 0
    assert np.allclose(model.a[0], a, atol=1e-6)


def test_fit_dynamics_refuses_records_that_are_not_whole_periods():
    H = static_model()
    with pytest.raises(InvalidArgumentError, match="record 0: 1500 input"):
        fit_dynamics(H, [(np.ones(1500), np.ones(1500))], N, validation=None)
    with pytest.raises(InvalidArgumentError, match="at least two records"):
        fit_dynamics(H, [(np.ones(N), np.ones(N))], N)


def test_hammerstein_files_round_trip(tmp_path):
    H, a = static_model(), mode()
    model = HammersteinModel(hysteresis=(H,), a=(a,), b=(np.array([[0.0, 0.9, 0.5]]),))
    path = tmp_path / "ham.json"
    model.save(path)
    back = load_hammerstein(path)
    u = np.linspace(0, 150, 300)
    assert np.array_equal(back.predict(u), model.predict(u))
    assert json.loads(path.read_text())["family"] == "hammerstein"


@pytest.mark.parametrize("change, message", [
    (lambda d: d.update(family="classical"), "key 'family' must be 'hammerstein'"),
    (lambda d: d.update(a=[]), "key 'a' must be a non-empty list"),
    (lambda d: d.update(a=[[2.0, 0.1]]), "a[0] must start with 1"),
    (lambda d: d.update(a=[[1.0, -2.5, 1.5]]), "unstable"),
    (lambda d: d.update(b=[[["x"]]]), "b[0] must be a list of lists of numbers"),
    (lambda d: d.update(b=[[[0.1], [0.2]]]), "b[0] needs one row per input (1)"),
    (lambda d: d["hysteresis"][0].update(thresholds=[0, 30, 15, 45]), "hysteresis[0]"),
])
def test_broken_hammerstein_files_are_one_line_errors(tmp_path, change, message):
    d = HammersteinModel(hysteresis=(static_model(),), a=(mode(),),
                         b=(np.array([[0.0, 0.9, 0.5]]),)).to_dict()
    change(d)
    path = tmp_path / "ham.json"
    path.write_text(json.dumps(d))
    with pytest.raises(InvalidModelError, match=r"ham\.json: ") as err:
        load_hammerstein(path)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_invalid_json_reports_line_and_column(tmp_path):
    path = tmp_path / "ham.json"
    path.write_text('{"family": "hammerstein",\n "a": [1, }')
    with pytest.raises(InvalidModelError, match=r"ham\.json:2:"):
        load_hammerstein(path)


@settings(max_examples=20, deadline=None)
@given(desired=st.lists(st.floats(-1e3, 1e3), min_size=8, max_size=120),
       lo=st.floats(0, 60), width=st.floats(1, 90))
def test_periodic_compensation_stays_within_the_limits(desired, lo, width):
    a = mode()
    model = HammersteinModel(hysteresis=(static_model(),), a=(a,),
                             b=(np.array([[0.0, 0.5, 0.9]]) * a.sum() / 1.4,))
    u = compensate_hammerstein(model, desired, u_min=lo, u_max=lo + width, periodic=True)[0]
    assert u.size == len(desired) and np.all((u >= lo) & (u <= lo + width))
