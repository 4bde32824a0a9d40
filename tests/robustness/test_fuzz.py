"""Property-based fuzz of the command line's readers, in-process: random bytes and
mutated valid files as model files, and random option values. Every outcome is exit 0,
or exit 2 with one line and no output file; never a traceback (or exit 70), never a
leftover file. (The fuzz of records, which finds the CSV reader's bugs, is in
test_csv_corpus.py.)"""

import json
import os

from harness import CORPUS, DESIRED, judge, run
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])



def _read(*parts):
    with open(os.path.join(CORPUS, *parts), "rb") as f:
        return f.read()


VALID_MODELS = [_read("model", n) for n in ("ok-classical.json", "ok-multislope.json",
                                            "ok-pwl.json")]
VALID_RECORD = _read("csv", "ok-loop.csv")

_json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=5),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=5), inner,
                                                                  max_size=4),
    max_leaves=8)


@st.composite
def mutated(draw, valid):
    """``valid`` with a few byte-level edits: replace, delete, insert, duplicate."""
    data = bytearray(draw(st.sampled_from(valid)) if isinstance(valid, list) else valid)
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.integers(0, max(len(data) - 1, 0)))
        j = min(len(data), i + draw(st.integers(0, 40)))
        how = draw(st.sampled_from(["replace", "delete", "insert", "duplicate"]))
        if how == "replace":
            data[i:i + 1] = draw(st.binary(min_size=1, max_size=1))
        elif how == "delete":
            del data[i:j]
        elif how == "insert":
            data[i:i] = draw(st.binary(max_size=8) | st.sampled_from(
                [b"NaN", b"-", b"1e999", b",", b"\n", b'"', b"\xff", b"[", b"}", b"0" * 400]))
        else:
            data[i:i] = data[i:j]
    return bytes(data)


@st.composite
def json_edited(draw):
    """A valid model with one key set to an arbitrary JSON value (or removed)."""
    d = json.loads(draw(st.sampled_from(VALID_MODELS)))
    key = draw(st.sampled_from(sorted(d) + ["input_range", "initial_state", "offset", "U"]))
    if draw(st.booleans()):
        d.pop(key, None)
    else:
        d[key] = draw(_json_values)
    return json.dumps(d).encode()


def _check(tmp_path, argv, out):
    for leftover in (out,):
        if os.path.exists(leftover):
            os.unlink(leftover)
    outcome = run(argv)
    problems = judge(outcome, None, out)
    assert not problems, f"pihyst {' '.join(argv)}: {problems}"


@SETTINGS
@given(content=st.binary(max_size=3000) | mutated(VALID_MODELS) | json_edited())
def test_model_files(tmp_path, content):
    model = tmp_path / "model.json"
    model.write_bytes(content)
    out = str(tmp_path / "out.csv")
    _check(tmp_path, ["predict", str(model), os.path.join(CORPUS, "input", "volts.csv"),
                      "-o", out], out)
    _check(tmp_path, ["compensate", str(model), DESIRED, "-o", out], out)


_option_values = st.sampled_from(["nan", "inf", "-inf", "-1", "0", "1e308", "-1e308",
                                  "1e-308", "x", "", "99999999999999999999", "0.5", "3"])


@SETTINGS
@given(option=st.sampled_from(["--period", "--dt", "--cycles", "--min", "--max", "--ratio",
                               "--ramps", "--rate", "--steps", "--step-time", "--seed",
                               "--triangles"]),
       value=_option_values,
       signal=st.sampled_from(["triangle", "sine", "decaying-triangles", "random-ramps",
                               "staircase"]))
def test_simulate_options(tmp_path, option, value, signal):
    out = str(tmp_path / "out.csv")
    _check(tmp_path, ["simulate", "-o", out, "--period", "20", "--dt", "1", "--steps", "3",
                      "--step-time", "2", "--ramps", "3", "--triangles", "2", "--signal",
                      signal, option, value], out)
