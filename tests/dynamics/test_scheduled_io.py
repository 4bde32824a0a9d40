"""Scheduled state-space model files (pihyst.dynamics._scheduled_io)."""

import dataclasses
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pihyst.dynamics import (
    ScheduledStateSpace,
    load_scheduled_state_space,
    save_scheduled_state_space,
)
from pihyst.dynamics._scheduled_io import scheduled_to_dict
from pihyst.exceptions import InvalidModelError


def random_model(rng, K, P, R, p, m):
    """Random stable modes, with values JSON text must keep exactly: negative zeros,
    subnormals, 17-digit mantissas."""
    radius = rng.uniform(0.0, 0.999, (K, P))
    angle = rng.uniform(1e-3, np.pi - 1e-3, (K, P))

    def odd(*shape):
        x = rng.normal(size=shape) * 10.0 ** rng.integers(-300, 300, size=shape)
        x.flat[::3] = -0.0
        x.flat[1::5] = 5e-324
        return x
    cplx = lambda *s: odd(*s) + 1j * odd(*s)   # noqa: E731
    return ScheduledStateSpace(np.cumsum(rng.uniform(1e-3, 2.0, K)),
                               radius * np.exp(1j * angle), cplx(K, P, p), cplx(K, P, m),
                               rng.uniform(-0.999, 0.999, (K, R)), odd(K, R, p), odd(K, R, m),
                               odd(K, p, m), window=float(rng.uniform(1, 1e4)),
                               exponent=float(rng.choice([1.0, 0.0, 0.5, 2.0, rng.normal()])))


def same_bits(a, b):
    for field in dataclasses.fields(ScheduledStateSpace):
        x, y = np.asarray(getattr(a, field.name)), np.asarray(getattr(b, field.name))
        assert x.dtype == y.dtype and x.shape == y.shape, field.name
        assert x.tobytes() == y.tobytes(), field.name


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), K=st.integers(1, 4), P=st.integers(0, 3),
       R=st.integers(0, 2), p=st.integers(1, 3), m=st.integers(1, 3))
def test_a_saved_model_reads_back_bit_for_bit(tmp_path_factory, seed, K, P, R, p, m):
    model = random_model(np.random.default_rng(seed), K, P, R, p, m)
    path = tmp_path_factory.mktemp("m") / "scheduled.json"
    save_scheduled_state_space(model, path)
    back = load_scheduled_state_space(path)
    same_bits(model, back)
    u = np.random.default_rng(seed).normal(size=(30, m))
    if np.all(np.abs(model.D) < 1e100) and np.all(np.abs(model.c) < 1e100):
        np.testing.assert_array_equal(back.predict(u * 1e-200), model.predict(u * 1e-200))


def test_the_file_is_plain_json_with_every_field():
    model = random_model(np.random.default_rng(0), 2, 1, 0, 3, 3)
    d = json.loads(json.dumps(scheduled_to_dict(model)))
    assert d["family"] == "scheduled_state_space"
    assert set(d) == {"family"} | {f.name for f in dataclasses.fields(ScheduledStateSpace)}
    assert d["real_c"]["shape"] == [2, 0, 3]        # an empty axis keeps its neighbours
    same_bits(model, load_scheduled_state_space(d))


def good():
    return scheduled_to_dict(ScheduledStateSpace(
        [1.0, 3.0], [[0.5j], [0.7j]], [[[1.0]], [[1.0]]], [[[1.0]], [[1.0]]],
        np.zeros((2, 0)), np.zeros((2, 0, 1)), np.zeros((2, 0, 1)), [[[0.0]], [[0.0]]],
        window=100.0))


def edited(**changes):
    d = good()
    for key, value in changes.items():
        if value is None:
            del d[key]
        else:
            d[key] = value
    return d


@pytest.mark.parametrize("d, message", [
    (edited(family="hammerstein"), "key 'family' must be 'scheduled_state_space'"),
    (edited(poles=None), "key 'poles' is missing"),
    (edited(extra=1), "unknown key 'extra'"),
    (edited(window="wide"), "key 'window' must be a finite number"),
    (edited(window=True), "key 'window' must be a finite number"),
    (edited(window=0.5), "window must be at least 1 sample"),
    (edited(D=[[[0.0]], [[0.0]]]), "key 'D' must be an object with the keys 'shape', 'values'"),
    (edited(D={"shape": [2, 1, 1], "values": [[[0.0]], [["x"]]]}),
     "key 'D' must be an object whose 'values' is nested lists of numbers"),
    (edited(D={"shape": [2, 1, 2], "values": [[[0.0]], [[0.0]]]}),
     "key 'D' must be an object whose 'values' has the shape [2, 1, 2] it gives, not [2, 1, 1]"),
    (edited(D={"shape": [2, -1], "values": []}), "key 'D' must be an object whose 'shape'"),
    (edited(poles={"shape": [2, 1], "values": [[0.5], [0.7]]}),
     "key 'poles' must be an object with the keys 'shape', 'real', 'imag'"),
    (edited(poles={"shape": [2, 1], "real": [[0.0], [0.0]], "imag": [[0.5], [1.5]]}),
     "every pole must lie inside the unit circle"),
    (edited(amplitudes={"shape": [2], "values": [3.0, 1.0]}),
     "amplitudes must be non-negative and strictly increasing"),
    (edited(b={"shape": [2, 1, 1], "real": [[[1.0]], [[12345.0]]],   # 1e400 in the file
               "imag": [[[0.0]], [[0.0]]]}), "b holds NaN or infinite entries"),
    ([1, 2], "key 'family' must be"),
])
def test_a_malformed_model_is_refused_in_one_line(tmp_path, d, message):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(d).replace("12345.0", "1e400"))    # JSON reads it as inf
    with pytest.raises(InvalidModelError) as err:
        load_scheduled_state_space(path)
    text = str(err.value)
    assert text.startswith(f"{path}: ") and message in text and "\n" not in text


def test_broken_json_names_the_line_and_column(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"family": "scheduled_state_space",\n "window": 1e,\n}')
    with pytest.raises(InvalidModelError, match=r"bad\.json:2:"):
        load_scheduled_state_space(path)
    with pytest.raises(InvalidModelError, match="cannot read model"):
        load_scheduled_state_space(tmp_path / "absent.json")
