"""Every malformed model file of the corpus, fed to every command that reads a model:
one line and exit status 2 (no output), or exit 0 for the accepted variants; and through
the Python API, InvalidModelError and nothing else."""

import json
import os

import pytest
from corpus_cases import check, params
from harness import CORPUS, MANIFEST

import pihyst
from pihyst.io import load_model


@pytest.mark.parametrize("name, command, expect, says, warns", params("model", reader=False))
def test_model_file_on_the_command_line(tmp_path, name, command, expect, says, warns):
    check(tmp_path, name, command, expect, says, warns)


MODEL_FILES = sorted(n for n in MANIFEST if n.startswith("model/"))


@pytest.mark.parametrize("name", MODEL_FILES)
def test_load_model_raises_only_invalid_model_error(name):
    path = os.path.join(CORPUS, name)
    if MANIFEST[name]["expect"]["predict"] == 0:
        model = load_model(path)
        with open(path, "rb") as f:
            text = f.read().decode("utf-8-sig")
        assert model == pihyst.PIModel.from_dict(json.loads(text)), "read differently"
    else:
        with pytest.raises(pihyst.InvalidModelError) as err:
            load_model(path)
        assert "\n" not in str(err.value)
        assert name.split("/")[1] in str(err.value), "the error names the file"


def test_accepted_variants_read_exactly_as_the_plain_file():
    plain = load_model(os.path.join(CORPUS, "model", "ok-classical.json"))
    for variant in ("ok-bom.json", "ok-crlf.json"):
        assert load_model(os.path.join(CORPUS, "model", variant)) == plain


def test_negative_weights_predict_runs_compensate_refuses(tmp_path):
    """The rule of docs/errors.md: a model with a negative weight is not monotone, so it
    cannot be inverted; predict runs it, compensate and track refuse it, naming the
    weight."""
    model = load_model(os.path.join(CORPUS, "model", "neg-weight-classical.json"))
    model.predict([0.0, 50.0, 0.0])
    with pytest.raises(pihyst.InvalidModelError, match=r"weights\[1\] = -0.1"):
        pihyst.Compensator(model)
    with pytest.raises(pihyst.InvalidModelError, match="non-negative weights"):
        pihyst.compensate(model, [0.0, 1.0])
