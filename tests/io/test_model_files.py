"""Model JSON: load_model from path or dict, save, round trip, errors."""

import json
import re

import numpy as np
import pytest
from hypothesis import given, settings

import pihyst

from strategies import any_model, signals


@settings(max_examples=40, deadline=None)
@given(any_model(nonneg=False), signals(max_size=40))
def test_save_load_round_trip(tmp_path_factory, model, u):
    path = tmp_path_factory.mktemp("m") / "model.json"
    model.save(path)
    loaded = pihyst.load_model(path)
    assert type(loaded) is type(model)
    np.testing.assert_array_equal(loaded.predict(u), model.predict(u))
    assert loaded.to_dict() == model.to_dict()


def test_minimal_dict_uses_paper_defaults():
    m = pihyst.load_model({"family": "multislope", "thresholds": [0, 20, 30, 40],
                           "weights": [0.196, 0.026, 0.046, 0.028]})
    assert (m.U, m.a, m.b, m.h) == (150.0, 0.8, 1.2, 0.5)
    assert m.input_range == (0.0, 150.0)
    assert m.initial_state.tolist() == [0, 0, 0, 0]
    assert m.units == {"input": "V", "output": "um"}


def test_examples_load(tmp_path):
    for name in ("paper_table1_classical.json", "paper_table1_multislope.json"):
        m = pihyst.load_model(f"examples/{name}")
        assert m.metadata["source"].startswith("Xu, Zhang, Rong and Ni (2020)")


@pytest.mark.parametrize("d,match", [
    ({"family": "quantum", "thresholds": [0], "weights": [1]}, "'family' must be one of"),
    ({"family": "classical", "weights": [1]}, "missing required key 'thresholds'"),
    ({"family": "classical", "thresholds": [0]}, "missing required key 'weights'"),
    ({"family": "classical", "thresholds": [0], "weights": [1], "treshold": 2},
     "unknown key 'treshold'"),
    ({"family": "classical", "thresholds": [0], "weights": ["x"]},
     "weights\\[0\\] must be a number"),
    ({"family": "pwl", "rising": [{"x": [0]}], "falling": [], "weights": [1]},
     "rising\\[0\\] must be an object"),
])
def test_bad_dicts(d, match):
    with pytest.raises(pihyst.InvalidModelError, match=match):
        pihyst.load_model(d)


def test_bad_files_name_the_file_and_position(tmp_path):
    p = tmp_path / "broken.json"
    p.write_text('{"family": "classical",\n "weights": [1,]}')
    with pytest.raises(pihyst.InvalidModelError, match=r"broken.json:2:\d+: invalid JSON"):
        pihyst.load_model(p)
    p.write_text("[1, 2]")
    with pytest.raises(pihyst.InvalidModelError, match="broken.json: a model must be a JSON"):
        pihyst.load_model(p)
    with pytest.raises(pihyst.InvalidModelError, match="cannot read model"):
        pihyst.load_model(tmp_path / "missing.json")
    p.write_text(json.dumps({"family": "classical", "thresholds": [0, 5, 1], "weights": [1] * 3}))
    with pytest.raises(pihyst.InvalidModelError, match="broken.json: .*strictly increasing"):
        pihyst.load_model(p)


def test_saved_files_get_the_usual_permissions(tmp_path):
    import os
    path = tmp_path / "m.json"
    pihyst.ClassicalPI([0], [1]).save(path)
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


def test_model_file_with_byte_order_mark(tmp_path):
    p = tmp_path / "bom.json"
    p.write_bytes(b"\xef\xbb\xbf" + json.dumps({"family": "classical", "thresholds": [0],
                                                   "weights": [1]}).encode())
    assert pihyst.load_model(p).n_operators == 1


# ------------------------------------------------------------------ metadata in JSON
def _plain(value):
    """Whether ``value`` is made of JSON's own Python types only."""
    if isinstance(value, dict):
        return all(type(k) is str and _plain(v) for k, v in value.items())
    if isinstance(value, list):
        return all(_plain(v) for v in value)
    return value is None or type(value) in (str, int, float, bool)


@pytest.mark.filterwarnings("ignore::pihyst.PihystWarning")   # a record of 11 levels
@pytest.mark.parametrize("family", ["classical", "multislope", "multislope-identified",
                                    "modified-pi", "kp", "bouc-wen"])
def test_a_model_fitted_with_settle_saves_and_loads(tmp_path, family):
    # a staircase up and down that never turns up again: its first sweep ends at the
    # first sample of the top step
    u = np.repeat([0.0, 30, 60, 90, 120, 150, 120, 90, 60, 30, 0], 10)
    y = pihyst.load_model("examples/paper_table1_classical.json").predict(u)
    model = pihyst.fit(u, y, family=family, initial_state="settle").model
    assert _plain(dict(model.metadata)), model.metadata
    path = tmp_path / "m.json"
    pihyst.save_model(model, path)
    loaded = pihyst.load_model(path)
    assert loaded == model and loaded.metadata == model.to_dict()["metadata"]
    assert loaded.metadata["fit"]["settled"]["sample"] > 0


def test_numpy_values_in_metadata_are_saved_as_json_numbers_and_lists(tmp_path):
    metadata = {"n": np.int64(3), "x": np.float32(0.5), "ok": np.bool_(True),
                "v": np.arange(3), "t": (np.float64(1.0), 2), np.int16(7): "seven",
                "nested": {"m": np.eye(2), "nan": np.float64("nan"), "inf": float("inf")}}
    for model in (pihyst.load_model("examples/paper_table1_multislope.json"),
                  pihyst.BoucWenModel(beta=0.5, gamma=0.2, hysteretic=10.0, linear=30.0)):
        path = tmp_path / f"{model.family}.json"
        model.replace(metadata=metadata).save(path)
        assert pihyst.load_model(path).metadata == {
            "n": 3, "x": 0.5, "ok": True, "v": [0, 1, 2], "t": [1.0, 2], "7": "seven",
            "nested": {"m": [[1.0, 0.0], [0.0, 1.0]], "nan": None, "inf": None}}


@pytest.mark.parametrize("metadata, where", [
    ({"fit": {"s": {1, 2}}}, "metadata['fit']['s']: a set cannot be written as JSON"),
    ({"z": [1, 2j]}, "metadata['z'][1]: a complex cannot be written as JSON"),
    ({(1, 2): 0}, "metadata: key (1, 2) is not a JSON key")])
def test_metadata_json_cannot_hold_is_an_invalid_model_error(tmp_path, metadata, where):
    model = pihyst.load_model("examples/paper_table1_classical.json").replace(metadata=metadata)
    path = tmp_path / "m.json"
    with pytest.raises(pihyst.InvalidModelError, match=re.escape(where)):
        pihyst.save_model(model, path)
    assert not path.exists()
