"""A model cannot be changed after it is made (issue 24, item 11): its arrays are views
of read-only memory (``setflags(write=True)`` fails too) and its metadata is read-only
all the way down; saving, loading and ``to_dict`` still give plain JSON."""

import json

import numpy as np
import pytest

import pihyst
from pihyst.model import Creep

META = {"fit": {"family": "classical", "thresholds": [0, 10], "deeper": {"a": [1, {"b": 2}]}},
        "array": np.arange(3.0)}


def _models():
    return [pihyst.ClassicalPI([0, 10], [0.5, 0.2], metadata=META),
            pihyst.MultislopePI([0, 20], [0.1, 0.2], metadata=META),
            pihyst.ClassicalPI([0, 10], [0.5, 0.2], creep=Creep([0.1], [0.01], 1e-3)),
            pihyst.BoucWenModel(beta=0.01, gamma=0.005, hysteretic=1.0, linear=0.5, n=1,
                                metadata=META)]


def _arrays(model):
    out = [getattr(model, n) for n in ("weights", "thresholds", "initial_state")
           if isinstance(getattr(model, n, None), np.ndarray)]
    if getattr(model, "creep", None) is not None:
        out += [model.creep.tau, model.creep.gain]
    return out


@pytest.mark.parametrize("model", _models()[:3], ids=lambda m: m.family)
def test_model_arrays_cannot_be_made_writable(model):
    arrays = _arrays(model)
    assert arrays
    for a in arrays:
        with pytest.raises(ValueError):
            a[0] = 1.0
        with pytest.raises(ValueError):
            a.setflags(write=True)


@pytest.mark.parametrize("change", [
    lambda m: m.metadata.__setitem__("x", 1),
    lambda m: m.metadata["fit"].__setitem__("family", "x"),
    lambda m: m.metadata["fit"]["deeper"]["a"][1].__setitem__("b", 3),
    lambda m: m.metadata["fit"]["thresholds"].append(20),
    lambda m: m.metadata["array"].__setitem__(0, 5.0),
    lambda m: m.metadata["array"].setflags(write=True),
])
def test_metadata_is_deeply_immutable(change):
    model = _models()[0]
    with pytest.raises((TypeError, ValueError, AttributeError)):
        change(model)
    assert model.metadata["fit"]["family"] == "classical"


@pytest.mark.parametrize("model", _models(), ids=lambda m: m.family)
def test_json_save_load_and_to_dict_still_work(tmp_path, model):
    d = model.to_dict()
    text = json.dumps(d)                      # plain JSON types all the way down
    assert pihyst.load_model(json.loads(text)) == model
    path = tmp_path / "m.json"
    model.save(path)
    again = pihyst.load_model(path)
    assert again == model
    if model.metadata:
        assert again.metadata["fit"]["deeper"]["a"][1]["b"] == 2
        d["metadata"]["fit"]["family"] = "changed"      # a copy: the model keeps its own
        assert model.metadata["fit"]["family"] == "classical"
    # a new model from an old one's metadata, as fit and fit-many do
    other = model.replace(metadata={**model.metadata, "source": {"data": "x.csv"}})
    assert other.metadata["source"]["data"] == "x.csv"
