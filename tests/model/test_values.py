"""Models are values: immutable, compared by parameters, copied with replace(), written
and read by their own to_dict()/from_dict(), run sample by sample through a Stepper."""

import json

import numpy as np
import pytest
from hypothesis import given, settings

import pihyst
from pihyst.model import ClassicalPI, MultislopePI, PiecewiseLinearPI, PIModel

from strategies import any_model, signals

PAPER_CLASSICAL = ClassicalPI([0, 10, 30, 150], [0.008, 0.252, 0.019, 0.582])
PWL = PiecewiseLinearPI([([0, 150], [-10, 140])], [([0, 150], [10, 160])], [1.0])


@pytest.mark.parametrize("name, value", [
    ("weights", [5, 5, 5, 5]), ("thresholds", [0, 1, 2, 3]), ("offset", 1.0),
    ("input_range", (0, 10)), ("initial_state", [0, 0, 0, 0]), ("metadata", {}),
    ("units", {}), ("new_attribute", 1),
])
def test_parameters_cannot_be_reassigned(name, value):
    m = PAPER_CLASSICAL
    before = m.predict(np.linspace(0, 150, 31))
    with pytest.raises(AttributeError, match="immutable"):
        setattr(m, name, value)
    np.testing.assert_array_equal(m.predict(np.linspace(0, 150, 31)), before)


def test_arrays_and_mappings_are_read_only():
    m = PAPER_CLASSICAL
    with pytest.raises(ValueError):
        m.weights[0] = 5.0
    with pytest.raises(ValueError):
        m.thresholds[0] = 5.0
    with pytest.raises(TypeError):
        m.units["output"] = "nm"
    with pytest.raises(TypeError):
        m.metadata["fit"] = {}


def test_equality_is_by_parameters_not_identity_or_metadata():
    same = ClassicalPI([0.0, 10.0, 30.0, 150.0], np.array([0.008, 0.252, 0.019, 0.582]),
                       metadata={"note": "another fit"})
    assert same == PAPER_CLASSICAL and hash(same) == hash(PAPER_CLASSICAL)
    assert PAPER_CLASSICAL != PAPER_CLASSICAL.replace(offset=0.1)
    assert PAPER_CLASSICAL != MultislopePI([0, 20, 30, 40], [0.008, 0.252, 0.019, 0.582])
    assert PAPER_CLASSICAL != "a model"
    assert len({PAPER_CLASSICAL, same, PAPER_CLASSICAL.replace(offset=1.0)}) == 2


def test_replace_changes_one_parameter_and_validates():
    m = PAPER_CLASSICAL.replace(weights=[1, 0, 0, 0])
    assert m.weights.tolist() == [1, 0, 0, 0]
    assert m.thresholds.tolist() == PAPER_CLASSICAL.thresholds.tolist()
    assert PAPER_CLASSICAL.weights[0] == 0.008  # the original is untouched
    with pytest.raises(pihyst.InvalidModelError, match="thresholds must be strictly"):
        PAPER_CLASSICAL.replace(thresholds=[0, 10, 10, 150])
    with pytest.raises(pihyst.InvalidModelError, match="no parameter 'a'"):
        PAPER_CLASSICAL.replace(a=0.5)
    ms = MultislopePI([0, 20], [1, 1]).replace(h=0.25)
    assert ms.h == 0.25 and ms.a == 0.8


def test_repr_shows_non_default_parameters_and_shortens_long_vectors():
    assert repr(PAPER_CLASSICAL) == ("ClassicalPI(thresholds=[0.0, 10.0, 30.0, 150.0], "
                                     "weights=[0.008, 0.252, 0.019, 0.582])")
    r = repr(MultislopePI([0, 20], [1, 1], b=1.3, offset=2.0))
    assert "b=1.3" in r and "offset=2" in r and "a=" not in r and "U=" not in r
    long = ClassicalPI(np.arange(40.0), np.full(40, 0.1))
    assert "(40 values)" in repr(long) and len(repr(long)) < 200
    assert "1 polylines" in repr(PWL)


def test_metadata_is_given_at_construction():
    m = ClassicalPI([0], [1], metadata={"fit": {"rms": 0.1}})
    assert m.metadata["fit"] == {"rms": 0.1}
    with pytest.raises(pihyst.InvalidModelError, match="metadata must be a dict"):
        ClassicalPI([0], [1], metadata=[1, 2])


@pytest.mark.parametrize("model", [
    PAPER_CLASSICAL,
    MultislopePI([0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028], b=1.3, offset=-1.0),
    PWL.replace(initial_state=[3.0], metadata={"source": "test"}),
])
def test_to_dict_and_from_dict_round_trip_through_json(model, tmp_path):
    d = json.loads(json.dumps(model.to_dict()))
    back = PIModel.from_dict(d)
    assert back == model and type(back) is type(model)
    assert dict(back.metadata) == dict(model.metadata)
    assert type(model).from_dict(d) == model
    model.save(tmp_path / "m.json")
    assert pihyst.load_model(tmp_path / "m.json") == model


def test_from_dict_on_a_family_class_refuses_another_family():
    with pytest.raises(pihyst.InvalidModelError, match="not 'multislope'"):
        MultislopePI.from_dict(PAPER_CLASSICAL.to_dict())


@pytest.mark.parametrize("change, message", [
    ({"thresholds": [0.0]}, "unknown key 'thresholds' for family 'pwl'"),
    ({"rising": "x"}, "rising must be a list"),
    ({"schema_version": 7}, "schema_version 7"),
    ({"family": ["pwl"]}, "key 'family' must be one of"),
])
def test_from_dict_refuses_what_it_would_otherwise_ignore_or_misread(change, message):
    with pytest.raises(pihyst.InvalidModelError, match=message):
        PIModel.from_dict({**PWL.to_dict(), **change})


@settings(max_examples=60)
@given(any_model(nonneg=False), signals(max_size=60))
def test_a_stepper_leaves_its_model_unchanged(model, u):
    before = model.to_dict()
    a, b = model.stepper(), model.stepper()
    ya = [a.step(v) for v in u]
    assert model.to_dict() == before
    assert [b.step(v) for v in u] == ya  # independent steppers, same results
    np.testing.assert_array_equal(ya, model.predict(u))


@settings(max_examples=40, deadline=None)
@given(any_model(), signals())
def test_models_pickle_and_copy_as_values(model, u):
    """multiprocessing and Dask send models by pickle: the copy is equal, has the same
    metadata and units, stays read-only, and predicts the same bits."""
    import copy
    import pickle

    for c in (pickle.loads(pickle.dumps(model)), copy.deepcopy(model)):
        assert type(c) is type(model) and c == model
        assert c.metadata == model.metadata and dict(c.units) == dict(model.units)
        np.testing.assert_array_equal(c.predict(u), model.predict(u))
        with pytest.raises(TypeError):
            c.units["output"] = "nm"


def test_a_fitted_model_with_creep_pickles():
    import pickle

    from pihyst.model import Creep

    m = PAPER_CLASSICAL.replace(creep=Creep([1.0, 10.0], [0.02, 0.03], 0.1),
                                metadata={"fit": {"family": "classical", "notes": ["a"]}})
    c = pickle.loads(pickle.dumps(m))
    t = np.arange(200) * 0.1
    u = np.clip(np.sin(t), 0, 1) * 150
    assert c == m and c.metadata["fit"]["notes"] == ["a"]
    np.testing.assert_array_equal(c.predict(u, t=t), m.predict(u, t=t))
