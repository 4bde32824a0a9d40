"""Model JSON: load_model from path or dict, save, round trip, errors."""

import json

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
