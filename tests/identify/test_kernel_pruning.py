"""Fewer kernels for the same KP model (identify/_kernel_pruning.py): the reduced model
follows its reference within the tolerance on the record and on reversal curves over the
whole Preisach plane, keeps the fit's constraints, and is the same on every run."""

from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import pihyst
from pihyst.identify import KrasnoselskiiPokrovskii, _constants
from pihyst.identify._family_fit import cycled_state
from pihyst.identify._gram import accumulate
from pihyst.identify._kernel_pruning import probe_gram, prune_kernels, reversal_curves

S = 150.0


def _levels(seed, n=12):
    rng = np.random.default_rng(seed)
    levels = [0.0, S, 0.0]
    for _ in range(n):
        levels.append(float(rng.uniform(0, S)))
    return np.concatenate([np.linspace(a, b, 30, endpoint=False) for a, b in
                           zip(levels[:-1], levels[1:])] + [levels[-1:]])


def _setup(grid, weights, offset=0.5):
    fam = KrasnoselskiiPokrovskii(grid)
    pairs = fam.pairs()
    template = fam.template(pairs, S)
    state0 = cycled_state(template, S)
    model = template.replace(weights=weights, offset=offset, initial_state=state0)
    u = _levels(1)
    # a measured output: the model's, and sensor noise for it to be judged against
    y = model.predict(u) + 0.01 * np.random.default_rng(7).standard_normal(u.size)
    parts, _ = accumulate(template, u, y, [(0, u.size, "fit")], state0)
    probes = probe_gram(template, state0, grid, S, fit_offset=True)
    n = len(pairs) + 1
    problem = SimpleNamespace(lower=np.r_[np.zeros(n - 1), -np.inf],
                              upper=np.full(n, np.inf), A_eq=None, b_eq=None)
    return template, state0, model, u, parts["fit"], probes, problem


def _reduced(template, state0, x):
    return template.replace(weights=x[:-1], offset=x[-1], initial_state=state0)


def _rms(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)))


def test_reversal_curves_turn_at_every_half_kernel_width_from_both_ends():
    grid = 5
    v = reversal_curves(grid, S)
    assert v.min() == 0.0 and v.max() == S
    step = np.diff(v)
    turns = v[1:-1][np.sign(step[1:]) != np.sign(step[:-1])]
    half = S / (2 * (grid - 1))
    # every level m S / (2 (grid - 1)) is a reversal from below and from above
    levels = np.round(np.arange(1, 2 * (grid - 1) + 1) * half, 9)
    assert set(levels[:-1]) <= set(np.round(turns, 9))
    # steps of a quarter kernel width, and one jump from the bottom to the top
    assert np.count_nonzero(np.abs(step) > S / (4 * (grid - 1)) + 1e-9) == 1


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2 ** 31 - 1), st.floats(0.02, 0.5))
def test_the_reduced_model_follows_its_reference_within_the_tolerance(seed, share):
    rng = np.random.default_rng(seed)
    grid = 5
    w = rng.uniform(0.0, 1.0, grid * (grid + 1) // 2) * (rng.uniform(size=15) < 0.8)
    template, state0, model, u, record, probes, problem = _setup(grid, w)
    x = np.r_[w, 0.5]
    reference = share * float(np.std(model.predict(u)))
    y, info = prune_kernels(x, w.size, record, record, probes, problem, reference)
    eps = _constants.PRUNE_TOLERANCE * reference
    reduced = _reduced(template, state0, y)
    v = reversal_curves(grid, S)
    # (P), measured on the models' outputs (not on the Gram matrices)
    assert _rms(reduced.predict(v), model.predict(v)) <= eps * (1 + 1e-6) + 1e-9
    assert _rms(reduced.predict(u), model.predict(u)) <= eps * (1 + 1e-6) + 1e-9
    # (J): the judged RMS (here the record's) rises by at most PRUNE_JUDGED
    every = np.arange(x.size)
    assert record.rms(every, y) <= record.rms(every, x) * (1 + _constants.PRUNE_JUDGED)
    assert np.all(y[:-1] >= 0) and info["kernels"] == np.count_nonzero(y[:-1])
    assert info["kernels"] <= info["kernels_before"] == np.count_nonzero(w)
    again, _ = prune_kernels(x, w.size, record, record, probes, problem, reference)
    assert np.array_equal(y, again)                        # the same on every run


def test_kernels_the_output_does_not_need_are_taken_away():
    grid = 6
    fam = KrasnoselskiiPokrovskii(grid)
    pairs = fam.pairs()
    w = np.full(len(pairs), 1e-7)
    big = [pairs.index(p) for p in ((0, 0), (1, 4), (2, 5), (3, 3))]
    w[big] = [1.0, 0.6, 0.8, 0.3]
    template, state0, model, u, record, probes, problem = _setup(grid, w)
    y, info = prune_kernels(np.r_[w, 0.5], w.size, record, record, probes, problem, 1e-3)
    assert sorted(np.flatnonzero(y[:-1])) == sorted(big)
    assert info["kernels"] == 4 and info["kernels_before"] == len(pairs)
    # with no tolerance nothing goes
    y0, info0 = prune_kernels(np.r_[w, 0.5], w.size, record, record, probes, problem, 0.0)
    assert info0["kernels"] == len(pairs) and np.array_equal(y0[:-1], w)


def test_the_reduction_keeps_the_fits_equality_constraints():
    grid = 5
    w = np.random.default_rng(3).uniform(0.2, 1.0, 15)
    template, state0, model, u, record, probes, problem = _setup(grid, w)
    top = int(np.argmax(u))
    _, rows = accumulate(template, u, model.predict(u), [(0, u.size, "fit")], state0,
                         rows_at=[top])
    problem.A_eq, problem.b_eq = rows[top][None, :], np.array([model.predict(u)[top]])
    y, info = prune_kernels(np.r_[w, 0.5], w.size, record, record, probes, problem, 0.05)
    assert info["kernels"] < 15
    reduced = _reduced(template, state0, y)
    assert reduced.predict(u)[top] == pytest.approx(model.predict(u)[top], abs=1e-9)


def test_the_default_fit_gives_a_kp_model_of_fewer_kernels_and_says_so():
    from pihyst.sim._preisach import Preisach
    from pihyst.sim.signals import triangle
    h = Preisach(S, [(72.7, 0.77, 3.07)], reversible=(12.7, 5.8))
    _, u = triangle(period_s=8.0, n_cycles=2, dt=2e-3)
    y = h.run(u)
    res = pihyst.fit(u, y, family="kp", input_range=(0.0, S), delay=0)
    reg = res.report.family("kp")["regularization"]
    pruning = reg["pruning"]
    assert pruning["kernels"] < pruning["kernels_before"] <= reg["kernels"]
    assert max(pruning["record_rms"], pruning["probe_rms"]) <= pruning["tolerance"]
    assert res.model.n_operators < reg["kernels"]
    assert res.model.n_operators == len(res.model.metadata["fit"]["kernels"])
