"""The C core's Bouc-Wen model (csrc/pihyst_boucwen.c) against its Python twin
(src/pihyst/model/_boucwen.py) on many models and signals: the same arithmetic, so the
outputs and states agree to rounding (1e-12 of the output scale; bit for bit where the C
build does not contract to FMA, as on x86-64), in one run or in chunks, sample by sample
(the stepper) or in blocks."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pihyst import _boucwen_core
from pihyst.exceptions import InvalidModelError
from pihyst.model import BoucWenModel
from pihyst.model._boucwen import advance

RTOL = 1e-12


@st.composite
def models(draw):
    # beta + |gamma| up to 80 here (the twin's substeps are Python: 32 (beta + |gamma|) per
    # unit of input); the stiffest models allowed get a test of their own below
    beta = draw(st.floats(0.05, 40))
    gamma = draw(st.floats(-0.99, 0.99)) * beta
    lo = draw(st.floats(-100, 100))
    return BoucWenModel(beta=beta, gamma=gamma, n=draw(st.sampled_from([1.0, 2.0])
                                                          | st.floats(1, 10)),
                        hysteretic=draw(st.floats(-30, 30)), linear=draw(st.floats(-50, 50)),
                        quadratic=draw(st.floats(-10, 10)), offset=draw(st.floats(-5, 5)),
                        input_range=(lo, lo + draw(st.floats(0.5, 300))))


def signals(model, kind, seed, n=80):
    """Inputs in the model's range: random jumps (long Runge-Kutta steps), a slow walk
    (one substep per sample, many kinks at z = 0), decaying triangles, holds."""
    lo, hi = model.input_range
    rng = np.random.default_rng(seed)
    if kind == "jumps":
        x = rng.uniform(0, 1, n)
    elif kind == "walk":
        x = np.abs((np.cumsum(rng.normal(0, 0.01, n)) + 0.5) % 2 - 1)
    elif kind == "triangles":
        x = np.abs(np.sin(np.linspace(0, 12, n))) * np.linspace(1, 0.1, n)
    else:
        x = np.repeat(rng.uniform(0, 1, n // 10 + 1), 10)[:n]
    return np.clip(lo + (hi - lo) * x, lo, hi)


def scale(model):
    return (abs(model.offset) + abs(model.linear) + abs(model.quadratic)
            + abs(model.hysteretic) * model.z_max)


@settings(max_examples=40)
@given(model=models(), kind=st.sampled_from(["jumps", "walk", "triangles", "holds"]),
       seed=st.integers(0, 2**16))
def test_c_predict_equals_the_twin(model, kind, seed):
    u = signals(model, kind, seed)
    c = model.simulate(u)
    twin = model.twin_simulation(u)
    np.testing.assert_allclose(c.output, twin.output, rtol=0, atol=RTOL * scale(model))
    assert c.final_state[0] == twin.final_state[0]
    assert abs(c.final_state[1] - twin.final_state[1]) <= RTOL * model.z_max


@settings(max_examples=20)
@given(model=models(), seed=st.integers(0, 2**16))
def test_chunks_stepper_and_block_agree(model, seed):
    u = signals(model, "walk", seed)
    whole = model.simulate(u)
    first = model.simulate(u[:57])
    rest = model.simulate(u[57:], initial_state=first.final_state)
    assert np.array_equal(np.r_[first.output, rest.output], whole.output)
    stepper = model.stepper()
    assert np.array_equal([stepper.step(v) for v in u], whole.output)
    assert np.array_equal(stepper.state, whole.final_state)


@settings(max_examples=40)
@given(model=models(), z=st.floats(-1, 1), dx=st.floats(-1, 1))
def test_c_advance_equals_the_twin(model, z, dx):
    z *= model.z_max
    core = model._core(model.initial_state)
    c = core.advance(z, dx)
    twin = advance(z, dx, model.beta, model.gamma, model.n)
    assert abs(c - twin) <= RTOL * model.z_max
    assert abs(c) <= model.z_max * (1 + 1e-9)


@pytest.mark.parametrize("beta, gamma, n", [(990.0, -9.0, 1.0), (600.0, 399.0, 3.5)])
def test_the_stiffest_models_agree(beta, gamma, n):
    m = BoucWenModel(beta=beta, gamma=gamma, n=n, hysteretic=3.0, linear=10.0)
    u = signals(m, "jumps", 7, n=6)
    np.testing.assert_allclose(m.predict(u), m.twin_simulation(u).output, rtol=0,
                               atol=RTOL * scale(m))


def test_initial_rest_state_equals_the_c_rest_state():
    m = BoucWenModel(beta=5.0, gamma=1.0, n=1.7, hysteretic=-8.0, linear=40.0)
    assert m._core(m.initial_state).rest_z == pytest.approx(m.initial_state[1], rel=1e-14)


def test_the_core_refuses_what_the_model_refuses():
    core = BoucWenModel(beta=5.0, gamma=1.0, hysteretic=-8.0, linear=40.0)._core((0.0, 0.0))
    with pytest.raises(_boucwen_core.CoreError, match="z_max"):
        core.state = (0.0, 1.0)          # beyond z_max = 1/6
    with pytest.raises(_boucwen_core.CoreError):
        _boucwen_core.BoucWen(1.0, 2.0, 1.0, 1.0, 1.0, 0.0, 0.0, (0.0, 1.0), (0.0, 0.0))
    with pytest.raises(_boucwen_core.CoreError):
        _boucwen_core.BoucWen(2.0, 1.0, 0.5, 1.0, 1.0, 0.0, 0.0, (0.0, 1.0), (0.0, 0.0))
    with pytest.raises(_boucwen_core.CoreError):
        _boucwen_core.BoucWen(2.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, (1.0, 1.0), (1.0, 0.0))
    # beta + gamma so small that z_max = (beta + gamma)^(-1/n) is beyond use (found by
    # fuzzing: |z|^n overflowed to NaN); the model refuses it too
    with pytest.raises(_boucwen_core.CoreError):
        _boucwen_core.BoucWen(5e-324, 0.0, 4.8, 1.0, 1.0, 0.0, 0.0, (0.0, 1.0), (0.0, 0.0))
    with pytest.raises(InvalidModelError, match="beta \\+ gamma >= 1e-09"):
        BoucWenModel(beta=5e-324, gamma=0.0, n=4.8, hysteretic=1.0, linear=1.0)


def test_a_delayed_model_runs_the_delayed_input_in_c():
    m = BoucWenModel(beta=5.0, gamma=1.0, n=1.5, hysteretic=-8.0, linear=40.0).replace(delay=3)
    u = signals(m, "walk", 5)
    c, twin = m.simulate(u), m.twin_simulation(u)
    assert np.array_equal(c.output, twin.output)
    assert np.array_equal(c.final_state, twin.final_state)
    assert np.array_equal(c.pending_input, twin.pending_input)
    stepper = m.stepper()
    assert np.array_equal([stepper.step(v) for v in u], c.output)
