"""Mathematical properties of every model family (Hypothesis).

Between the envelopes, rate independence, chunked == whole, step == run, inputs not
modified, wiping-out of memory.
"""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from strategies import U, any_model, classical_models, multislope_models, signals

TOL = 1e-12
settings.register_profile("pihyst", max_examples=200, deadline=None)
settings.load_profile("pihyst")


@given(any_model(nonneg=True), signals())
def test_operators_between_envelopes(model, u):
    # R_k(u[t]) <= f_k[t] <= F_k(u[t]), hence sum w R <= y - offset <= sum w F for w >= 0
    phi = model.operators(u)
    y = model.predict(u)
    for t, v in enumerate(u):
        rise, fall = model.envelopes(v)
        scale = 1.0 + np.abs(phi[t])
        assert np.all(phi[t] >= rise - TOL * scale)
        assert np.all(phi[t] <= fall + TOL * scale)
        lo = model.offset + model.weights @ rise
        hi = model.offset + model.weights @ fall
        assert lo - 1e-9 <= y[t] <= hi + 1e-9


@given(any_model(nonneg=False), signals(min_size=2),
       st.lists(st.integers(1, 4), min_size=200, max_size=200))
def test_repeating_samples_changes_nothing(model, u, repeats):
    times = np.array(repeats[:u.size])
    slow = np.repeat(u, times)
    original = np.cumsum(times) - 1  # where each original sample lands
    np.testing.assert_allclose(model.predict(slow)[original], model.predict(u),
                               rtol=TOL, atol=TOL)


@given(any_model(nonneg=False), signals(min_size=2, max_size=60), st.integers(1, 5))
def test_intermediate_samples_on_monotone_stretches_change_nothing(model, u, n_between):
    # between u[i] and u[i+1] the input is monotone: insert points strictly inside
    pieces = [u[:1]]
    original = [0]
    for a, b in zip(u[:-1], u[1:]):
        inner = np.linspace(a, b, n_between + 2)[1:-1]
        pieces += [inner, [b]]
        original.append(original[-1] + inner.size + 1)
    dense = np.concatenate(pieces)
    np.testing.assert_allclose(model.predict(dense)[original], model.predict(u),
                               rtol=TOL, atol=1e-10)


@given(any_model(nonneg=False), signals(max_size=120), st.data())
def test_chunked_equals_whole(model, u, data):
    cuts = sorted(data.draw(st.lists(st.integers(0, u.size), max_size=4)))
    whole = model.simulate(u)
    state = None
    parts = []
    for lo, hi in zip([0, *cuts], [*cuts, u.size]):
        r = model.simulate(u[lo:hi], initial_state=state)
        parts.append(r.output)
        state = r.final_state
    np.testing.assert_array_equal(np.concatenate(parts), whole.output)
    np.testing.assert_array_equal(state, whole.final_state)


@given(any_model(nonneg=False), signals(max_size=80))
def test_step_equals_run(model, u):
    stepper = model.stepper()
    stepped = np.array([stepper.step(v) for v in u])
    np.testing.assert_array_equal(stepped, model.predict(u))
    np.testing.assert_array_equal(stepper.state, model.simulate(u).final_state)
    stepper.reset()
    np.testing.assert_array_equal(stepper.state, model.initial_state)


@given(any_model(nonneg=False), signals(max_size=50))
def test_inputs_and_states_not_modified(model, u):
    u_before = u.copy()
    state = np.linspace(-1.0, 1.0, model.n_operators)
    state_before = state.copy()
    initial_before = model.initial_state.copy()
    model.simulate(u, initial_state=state)
    model.operators(u, initial_state=state)
    stepper = model.stepper(state)
    for v in u:
        stepper.step(v)
    stepper.reset(state)
    np.testing.assert_array_equal(u, u_before)
    np.testing.assert_array_equal(state, state_before)
    np.testing.assert_array_equal(model.initial_state, initial_before)


@given(st.one_of(classical_models(nonneg=False), multislope_models(nonneg=False)),
       signals(max_size=60), signals(max_size=60), signals(max_size=60),
       st.floats(0.0, 1.0))
def test_wiping_out(model, history_a, history_b, suffix, top):
    # From rest, once the input rises above every earlier maximum, the output no
    # longer depends on the history before: f_k = max(R_k(M), 0) for both histories.
    m = max(history_a.max(initial=0.0), history_b.max(initial=0.0))
    peak = m + top * (U - m)
    tail = np.concatenate([[peak], suffix])
    y_a = model.predict(np.concatenate([history_a, tail]))[history_a.size:]
    y_b = model.predict(np.concatenate([history_b, tail]))[history_b.size:]
    np.testing.assert_allclose(y_a, y_b, rtol=TOL, atol=1e-10)
