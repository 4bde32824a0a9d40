"""Whether a record's creep started at rest (identify/_record_start.py,
docs/theory/creep.md): the decays of a start away from rest are exact, and the default
fit with times says when a record carries them."""

import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import pihyst
from pihyst.exceptions import InsufficientDataWarning
from pihyst.identify import cycled_state
from pihyst.identify._creep import log_t_basis
from pihyst.identify._record_start import (
    UNSETTLED_SHARE,
    start_columns,
    start_decay,
)
from pihyst.model import ClassicalPI, Creep
from pihyst.sim import signals

TAU = 0.3 * 10 ** (0.5 * np.arange(6))          # 0.3 s .. 95 s
_PI = ClassicalPI([0.0, 10.0, 25.0, 45.0], [0.15, 0.06, 0.04, 0.03],
                  creep=Creep(TAU, log_t_basis(TAU.size) @ np.array([0.006, 0.004]), dt=0.1))
# at rest at 0 V after a full cycle, as a record is taken to start
TRUTH = _PI.replace(initial_state=cycled_state(_PI, 150.0))


@given(st.integers(0, 2**32 - 1))
def test_a_start_away_from_rest_adds_exactly_the_decays(seed):
    """y with the lags started at rest + delta_i, minus y from rest, is E @ e for some e,
    on uneven sample times (every lag within the record: no ramp column)."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.05, 0.3, 1500))
    u = 75.0 + 75.0 * np.sin(2 * np.pi * t / rng.uniform(5.0, 40.0))
    rest = TRUTH.predict(u, t=t)
    settled = np.full(TAU.size, TRUTH.hysteresis_output(TRUTH.initial_state))
    away = TRUTH.predict(u, t=t, creep_state=settled + rng.normal(0.0, 2.0, TAU.size))
    E = start_columns(t, TAU, t[-1] - t[0])
    assert E.shape == (t.size, TAU.size)
    coef = np.linalg.lstsq(E, away - rest, rcond=None)[0]
    assert np.max(np.abs(E @ coef - (away - rest))) < 1e-9 * max(1.0, np.ptp(away - rest))


def test_slower_lags_than_the_record_share_a_ramp_column():
    t = np.linspace(0.0, 10.0, 101)
    E = start_columns(t, np.array([1.0, 3.0, 100.0, 1000.0]), 10.0)
    assert E.shape == (101, 3)
    np.testing.assert_allclose(E[:, 0], np.exp(-t))
    np.testing.assert_allclose(E[:, 2], t / 10.0)


def test_share_is_small_for_periodic_error_and_large_for_a_decay():
    t = np.linspace(0.0, 60.0, 6001)
    periodic = np.sin(2 * np.pi * t / 5.0) + 0.3 * np.sign(np.sin(2 * np.pi * t / 5.0))
    decay = 2.0 * np.exp(-t / 12.0) + 0.1 * periodic
    assert start_decay(periodic, t, TAU, 60.0)[0] < 0.05
    share, rms = start_decay(decay, t, TAU, 60.0)
    assert share > 0.9 and rms == pytest.approx(np.std(2.0 * np.exp(-t / 12.0)), rel=0.05)
    assert start_decay(np.zeros(t.size), t, TAU, 60.0) == (0.0, 0.0)


def _record(history):
    """Decaying triangles of the true model with creep, after ``history`` (a hold of the
    top of the range for that many seconds, or None: at rest)."""
    t, u = signals.decaying_triangles(period_s=20.0, dt=0.05)
    state = None
    if history:
        th = np.arange(0.0, history, 0.05)
        uh = np.r_[np.linspace(0, 150, 20), np.full(th.size - 40, 150.0),
                   np.linspace(150, 0, 20)]
        state = TRUTH.simulate(uh, t=th).final_creep_state
    y = TRUTH.predict(u, t=t, creep_state=state)
    return t, u, y + np.random.default_rng(1).normal(0.0, 0.002, u.size)


def _start_of(result):
    creep = result.model.metadata["fit"]["creep"]
    return creep.get("record_start") or creep["decision"]["record_start"]


def test_a_record_after_a_hold_is_said_not_to_start_at_rest():
    t, u, y = _record(history=60.0)
    with pytest.warns(InsufficientDataWarning, match="did not start at rest"):
        result = pihyst.fit(u, y, t=t, family="classical")
    start = _start_of(result)
    assert not start["settled"] and start["decay_share"] > UNSETTLED_SHARE
    assert result.report.to_dict()["creep"]["record_start"] == start


def test_a_record_at_rest_is_not_flagged():
    t, u, y = _record(history=None)
    with warnings.catch_warnings():
        warnings.simplefilter("error", InsufficientDataWarning)
        result = pihyst.fit(u, y, t=t, family="classical")
    start = _start_of(result)
    assert start["settled"] and start["decay_share"] < UNSETTLED_SHARE


def _duhem_from_zero(u):
    """A user's Coleman-Hodgdon (Duhem) actuator (not pihyst's code):
    dy/du = 0.02 |du|/du (0.35 u - y) + 0.2, explicit Euler in 10 steps per sample,
    y = 0 at the first sample (its initial loading curve, not at rest after a cycle)."""
    y, out = 0.0, np.empty(len(u))
    for k in range(len(u)):
        step = 0.0 if k == 0 else (u[k] - u[k - 1]) / 10
        x = u[k - 1] if k else u[0]
        for _ in range(10):
            y += 0.02 * abs(step) * (0.35 * x - y) + 0.2 * step
            x += step
        out[k] = y
    return out


def _bouc_wen_from_z0(u):
    """A user's Bouc-Wen actuator (not pihyst's code): y = 0.4 u + z,
    dz/du = 0.6 - (0.02 sign(du z) + 0.005) |z|, RK4 in steps of at most 0.5 V, z = 0
    at the first sample (a simulation started there: not at rest after a cycle)."""
    def g(z, s):
        return 0.6 - (0.02 * np.sign(s * z) + 0.005) * abs(z)

    z, out = 0.0, np.empty(len(u))
    for k in range(len(u)):
        step = 0.0 if k == 0 else u[k] - u[k - 1]
        m = max(1, int(np.ceil(abs(step) / 0.5)))
        h = step / m
        for _ in range(m if step else 0):
            k1 = g(z, h)
            k2 = g(z + h * k1 / 2, h)
            k3 = g(z + h * k2 / 2, h)
            z += h * (k1 + 2 * k2 + 2 * k3 + g(z + h * k3, h)) / 6
        out[k] = 0.4 * u[k] + z
    return out


@pytest.mark.parametrize("truth, start", [(_duhem_from_zero, "bottom"),
                                          (_bouc_wen_from_z0, "top")])
def test_a_hysteresis_start_away_from_rest_is_no_creep_to_flag(truth, start):
    # no creep at all: the loading curve from the bottom (which the Bouc-Wen fit takes
    # as a free start of z), or a Bouc-Wen z from 0 at the top (which the first sweep
    # settles). Judged from rest, that start was read as a creep decay and flagged
    # (100 % and 97 % of the error, 2.2 % and 0.12 % of range RMS)
    tri = np.r_[np.linspace(0, 150, 500, endpoint=False),
                np.linspace(150, 0, 500, endpoint=False)]
    u = np.r_[np.tile(tri, 2), 0.0]
    if start == "top":
        u = np.r_[np.linspace(150, 0, 250, endpoint=False), u]
    y = truth(u) + np.random.default_rng(1).normal(0.0, 0.02, u.size)
    t = np.arange(u.size) * 1e-3
    with warnings.catch_warnings():
        warnings.simplefilter("error", InsufficientDataWarning)
        result = pihyst.fit(u, y, t=t, family="bouc-wen")
    check = _start_of(result)
    assert check["settled"] and check["decay_share"] < UNSETTLED_SHARE
    assert len(result.model.metadata["fit"]["record_start"]) == 2
