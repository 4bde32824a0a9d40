"""The creep columns beside the offset (identify/_family_fit.ExtraColumns): the augmented
normal equations are those of the explicit matrix [operators, 1, Q] on each role's
samples, bit for bit up to rounding, for any record and any columns."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pihyst.identify._cycles import layout
from pihyst.identify._family_fit import ExtraColumns
from pihyst.identify._gram import accumulate
from pihyst.model import ClassicalPI


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_extra=st.integers(1, 3),
       holdout=st.sampled_from([None, 0.5]))
def test_augmented_normal_equations_are_those_of_the_explicit_matrix(seed, n_extra,
                                                                     holdout):
    rng = np.random.default_rng(seed)
    S = 10.0
    cycle = np.r_[np.linspace(0, S, 40), np.linspace(S, 0, 40)[1:]]
    v = np.concatenate([cycle * rng.uniform(0.3, 1.0) for _ in range(4)])
    d = rng.normal(size=v.size)
    model = ClassicalPI(np.sort(rng.uniform(0, S, 5)), np.ones(5), input_range=(0, S))
    lay = layout(v, S, settle=False, holdout=holdout)
    state0 = np.zeros(5)
    parts, _ = accumulate(model, v, d, lay.segments, state0, offset=True)
    q = rng.normal(size=(v.size, n_extra))
    extra = ExtraColumns(values=q, lower=np.zeros(n_extra), upper=np.ones(n_extra),
                         names=tuple(f"q{j}" for j in range(n_extra)))
    F = model.operators(v, initial_state=state0)
    roles = ("fit", "held_back")
    out = extra.augmented(parts, F, d, lay, roles)
    for role in roles:
        i = lay.indices(role)
        A = np.c_[F[i], np.ones(i.size), q[i]]
        np.testing.assert_allclose(out[role].G, A.T @ A, rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(out[role].b, A.T @ d[i], rtol=1e-10, atol=1e-9)
        assert out[role].n == i.size


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_a_known_column_gives_the_normal_equations_of_the_record_without_it(seed):
    """known=True (the creep estimate, weight 1): G, b and d^T d of the target d - q."""
    rng = np.random.default_rng(seed)
    S = 10.0
    cycle = np.r_[np.linspace(0, S, 40), np.linspace(S, 0, 40)[1:]]
    v = np.concatenate([cycle * rng.uniform(0.3, 1.0) for _ in range(4)])
    d = rng.normal(size=v.size)
    q = rng.normal(size=v.size)
    model = ClassicalPI(np.sort(rng.uniform(0, S, 4)), np.ones(4), input_range=(0, S))
    lay = layout(v, S, settle=False, holdout=0.5)
    parts, _ = accumulate(model, v, d, lay.segments, np.zeros(4), offset=True)
    removed, _ = accumulate(model, v, d - q, lay.segments, np.zeros(4), offset=True)
    extra = ExtraColumns(values=q[:, None], lower=np.ones(1), upper=np.ones(1),
                         names=("known",), known=True)
    out = extra.augmented(parts, model.operators(v, initial_state=np.zeros(4)), d, lay,
                          ("fit", "held_back"))
    for role in ("fit", "held_back"):
        np.testing.assert_allclose(out[role].G, removed[role].G, rtol=1e-12)
        np.testing.assert_allclose(out[role].b, removed[role].b, rtol=1e-9, atol=1e-9)
        assert out[role].dd == pytest.approx(removed[role].dd, rel=1e-9)


def test_a_family_fitted_with_free_bounded_columns_finds_their_weight():
    """The free form: a column the record holds with weight 0.3, bounded to [0, 1], is
    fitted with the operators' weights; its part is in the fitter's predictions."""
    from pihyst.identify._families import as_family
    from pihyst.identify._options import FitOptions

    S = 10.0
    cycle = np.r_[np.linspace(0, S, 60), np.linspace(S, 0, 60)[1:]]
    u = np.concatenate([cycle * a for a in (1.0, 0.7, 1.0, 0.5, 1.0, 0.8)])
    truth = ClassicalPI([0.0, 2.0, 5.0], [1.0, 0.5, 0.25], input_range=(0, S))
    q = np.sin(np.arange(u.size) / 17.0)
    y = truth.predict(u) + 0.3 * q
    options = FitOptions.from_arguments(family="classical", thresholds=[0.0, 2.0, 5.0],
                                        input_range=(0, S), initial_state="zero")
    fitter = options.fitter(options.frame(u, y)).with_columns(
        ExtraColumns(values=q[:, None], lower=np.zeros(1), upper=np.ones(1),
                     names=("q",)))
    res = fitter.fit(as_family("classical"))
    coefficient = fitter.extra_coefficients[id(res.model)][1]
    np.testing.assert_allclose(coefficient, [0.3], atol=1e-8)
    np.testing.assert_allclose(res.model.weights, truth.weights, atol=1e-8)
    assert res.errors["fit"]["rms"] < 1e-8
