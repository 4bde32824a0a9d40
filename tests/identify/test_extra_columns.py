"""The creep columns beside the offset (identify/_family_fit.ExtraColumns): the augmented
normal equations are those of the explicit matrix [operators, 1, Q] on each role's
samples, bit for bit up to rounding, for any record and any columns."""

import numpy as np
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
