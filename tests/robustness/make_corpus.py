"""Writes the malformed-input corpus (tests/robustness/corpus/) and its manifest.

Run from the repository root: ``python tests/robustness/make_corpus.py``. The files are
committed; this script is how they were made (deterministic: fixed seeds). Inputs too big
to commit (a million repeated values) or that depend on the machine (directories,
permissions) are made by the tests themselves (tests/robustness/conftest.py).

Manifest (corpus/manifest.json): for every file, ``expect`` maps a command to 0 (must
succeed) or 2 (must fail with one line), and ``says`` is a fragment the error line must
contain (the file, line and column where there is one). Files that must succeed and hold
a record give the values they must read as (``values``), so that a silent misread fails.
"""

import json
import os

import numpy as np

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")
MANIFEST = {}

MODEL_COMMANDS = ("predict", "compensate", "track")
CSV_COMMANDS = ("predict", "fit", "compensate", "track")


def put(kind, name, content, expect, says=None, values=None, note=""):
    path = os.path.join(ROOT, kind, name)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    data = content.encode("utf-8") if isinstance(content, str) else content
    with open(path, "wb") as f:
        f.write(data)
    entry = {"expect": expect, "note": note}
    if says:
        entry["says"] = says
    if values is not None:
        entry["values"] = values
    MANIFEST[f"{kind}/{name}"] = entry


# ------------------------------------------------------------------ model files
CLASSICAL = {"family": "classical", "thresholds": [0, 10, 30, 150],
             "weights": [0.008, 0.252, 0.019, 0.582]}
MULTISLOPE = {"family": "multislope", "thresholds": [0, 20, 30, 40],
              "weights": [0.196, 0.026, 0.046, 0.028]}
PWL = {"family": "pwl", "weights": [0.3],
       "rising": [{"x": [0, 150], "y": [-10, 140]}],
       "falling": [{"x": [0, 150], "y": [10, 160]}]}


def model(name, content, says=None, expect=None, note=""):
    if not isinstance(content, (str, bytes)):
        content = json.dumps(content)
    if expect is None:
        expect = {c: 2 for c in MODEL_COMMANDS}
    put("model", name, content, expect, says, note=note)


def bad_model(name, base, says, note="", **changes):
    d = dict(base)
    for k, v in changes.items():
        if v is _DROP:
            d.pop(k, None)
        else:
            d[k] = v
    model(name, d, says, note=note)


_DROP = object()


def models():
    ok = {c: 0 for c in MODEL_COMMANDS}
    # accepted variants: read exactly as the plain file
    model("ok-classical.json", CLASSICAL, expect=ok)
    model("ok-bom.json", b"\xef\xbb\xbf" + json.dumps(CLASSICAL).encode(), expect=ok,
          note="a byte-order mark, as some editors write")
    model("ok-crlf.json", json.dumps(CLASSICAL, indent=2).replace("\n", "\r\n"), expect=ok)
    model("ok-integers.json", {**CLASSICAL, "weights": [1, 2, 3, 4]}, expect=ok)
    model("ok-schema-float.json", {**CLASSICAL, "schema_version": 1.0}, expect=ok)
    model("ok-multislope.json", MULTISLOPE, expect=ok)
    model("ok-pwl.json", PWL, expect=ok)
    # negative weights: the model runs (predict), but cannot be inverted
    neg = {"predict": 0, "compensate": 2, "track": 2}
    model("neg-weight-classical.json", {**CLASSICAL, "weights": [0.5, -0.1, 0.2, 0.1]},
          "weights[1] = -0.1", expect=neg,
          note="a model that cannot be inverted: predict runs it, compensate refuses it")
    model("neg-weight-inverse.json", {"family": "classical", "thresholds": [0, 5, 20],
                                      "weights": [2.0, -0.5, -0.2],
                                      "input_range": [0, 60]},
          "weights[1]", expect=neg, note="an analytic inverse saved as a model")

    # broken files
    model("empty.json", "", "model/empty.json:1:1")
    model("whitespace.json", "  \n\t\n", "invalid JSON")
    model("binary.json", bytes(np.random.default_rng(1).integers(0, 256, 300, dtype=np.uint8)),
          "model/binary.json:1:")
    model("non-utf8.json", json.dumps(CLASSICAL).replace("classical", "classi\x00cal")
          .encode().replace(b"\x00", b"\xe9"), "not UTF-8")
    model("utf16.json", json.dumps(CLASSICAL).encode("utf-16"), "model/utf16.json:1:1")
    model("truncated.json", json.dumps(CLASSICAL)[:40], "invalid JSON")
    model("trailing-garbage.json", json.dumps(CLASSICAL) + "\n}x", "model/trailing-garbage.json:2:")
    model("two-objects.json", json.dumps(CLASSICAL) + json.dumps(CLASSICAL), "Extra data")
    model("deep-metadata.json", '{"family": "classical", "thresholds": [0], "weights": [1],'
          ' "metadata": ' + "[" * 100000 + "]" * 100000 + "}", "nested too deeply")
    model("deep-top.json", "[" * 100000 + "]" * 100000, "nested too deeply")
    model("huge-int-weight.json", '{"family": "classical", "thresholds": [0], "weights": [1'
          + "0" * 400 + "]}", "weights")
    model("inf-literal-weight.json", '{"family": "classical", "thresholds": [0], '
          '"weights": [1e400]}', "weights[0]")
    model("digits-5000.json", '{"family": "classical", "thresholds": [0], "weights": ['
          + "7" * 5000 + "]}", "model/digits-5000.json")
    model("nan-literal.json", '{"family": "classical", "thresholds": [0], "weights": [NaN]}',
          "NaN")
    model("infinity-literal.json", '{"family": "classical", "thresholds": [0], '
          '"weights": [Infinity]}', "Infinity")
    model("neg-infinity-offset.json", '{"family": "classical", "thresholds": [0], '
          '"weights": [1], "offset": -Infinity}', "Infinity")
    model("duplicate-key.json", '{"family": "classical", "thresholds": [0], "weights": [1], '
          '"weights": [2]}', "duplicate key 'weights'")
    for name, value in (("list", []), ("string", "classical"), ("number", 3), ("null", None),
                        ("true", True)):
        model(f"top-{name}.json", json.dumps(value), "must be a JSON object")

    bad_model("family-list.json", CLASSICAL, "family", family=["classical"])
    bad_model("family-number.json", CLASSICAL, "family", family=1)
    bad_model("family-null.json", CLASSICAL, "family", family=None)
    bad_model("family-case.json", CLASSICAL, "family", family="Classical")
    bad_model("family-missing.json", CLASSICAL, "family", family=_DROP)
    bad_model("weights-missing.json", CLASSICAL, "weights", weights=_DROP)
    bad_model("thresholds-missing.json", CLASSICAL, "thresholds", thresholds=_DROP)
    bad_model("unknown-key.json", CLASSICAL, "unknown key 'weight'", weight=[1])
    bad_model("pwl-thresholds.json", PWL, "unknown key 'thresholds'", thresholds=[0])
    bad_model("classical-shape-key.json", CLASSICAL, "unknown key 'a'", a=0.8)
    bad_model("weights-empty.json", CLASSICAL, "weights", weights=[], thresholds=[])
    bad_model("weights-short.json", CLASSICAL, "weights", weights=[0.1, 0.2])
    bad_model("weights-string.json", CLASSICAL, "weights", weights="0.1")
    bad_model("weights-strings.json", CLASSICAL, "weights", weights=["0.1", "0.2", "0.3", "0.4"],
              note="numbers written as strings are not numbers")
    bad_model("weights-bools.json", CLASSICAL, "weights", weights=[True, False, True, True],
              note="true is not the number 1")
    bad_model("weights-nested.json", CLASSICAL, "weights", weights=[[0.1, 0.2, 0.3, 0.4]])
    bad_model("weights-null.json", CLASSICAL, "weights", weights=None)
    bad_model("weights-null-item.json", CLASSICAL, "weights", weights=[0.1, None, 0.3, 0.4])
    bad_model("weights-object.json", CLASSICAL, "weights", weights={"0": 0.1})
    bad_model("thresholds-decreasing.json", CLASSICAL, "strictly increasing",
              thresholds=[0, 30, 10, 150])
    bad_model("thresholds-duplicate.json", CLASSICAL, "strictly increasing",
              thresholds=[0, 10, 10, 150])
    bad_model("thresholds-negative.json", CLASSICAL, ">= 0", thresholds=[-1, 10, 30, 150])
    bad_model("thresholds-strings.json", CLASSICAL, "thresholds", thresholds=["0", "10", "30",
                                                                               "150"])
    model("ok-threshold-huge.json", {**CLASSICAL, "thresholds": [0, 10, 30, 1.7e308]},
          expect={c: 0 for c in MODEL_COMMANDS},
          note="an operator that never moves: useless but valid")
    bad_model("offset-string.json", CLASSICAL, "offset", offset="1.5")
    bad_model("offset-bool.json", CLASSICAL, "offset", offset=True)
    bad_model("offset-list.json", CLASSICAL, "offset", offset=[1.5])
    bad_model("range-reversed.json", CLASSICAL, "input_range", input_range=[150, 0])
    bad_model("range-empty.json", CLASSICAL, "input_range", input_range=[5, 5])
    bad_model("range-one.json", CLASSICAL, "input_range", input_range=[0])
    bad_model("range-three.json", CLASSICAL, "input_range", input_range=[0, 1, 2])
    bad_model("range-string.json", CLASSICAL, "input_range", input_range="12",
              note="'12' must not become [1, 2]")
    bad_model("range-object.json", CLASSICAL, "input_range", input_range={"min": 0, "max": 150})
    bad_model("range-null-item.json", CLASSICAL, "input_range", input_range=[None, 150])
    bad_model("range-huge.json", CLASSICAL, "input_range", input_range=[-1.7e308, 1.7e308],
              note="an input range whose span overflows")
    bad_model("state-short.json", CLASSICAL, "initial_state", initial_state=[0, 0])
    bad_model("state-strings.json", CLASSICAL, "initial_state", initial_state=["0"] * 4)
    bad_model("units-list.json", CLASSICAL, "units", units=["V", "um"])
    bad_model("units-number.json", CLASSICAL, "units", units={"input": 1, "output": "um"})
    bad_model("units-string.json", CLASSICAL, "units", units="V")
    bad_model("metadata-list.json", CLASSICAL, "metadata", metadata=[1, 2])
    bad_model("metadata-string.json", CLASSICAL, "metadata", metadata="fitted")
    bad_model("schema-2.json", CLASSICAL, "schema_version", schema_version=2)
    bad_model("schema-string.json", CLASSICAL, "schema_version", schema_version="1")
    bad_model("schema-bool.json", CLASSICAL, "schema_version", schema_version=True,
              note="true is not version 1")
    bad_model("weights-overflow-output.json", CLASSICAL, "overflow",
              weights=[1e306, 1e306, 1e306, 1e306],
              note="every output would be infinite")
    # multislope shapes
    bad_model("ms-ah-one.json", MULTISLOPE, "a h < 1", a=1.0, b=1.2, h=1.0,
              note="a h = 1: the maximum threshold (1-a)U/(1-ah) divides by zero")
    bad_model("ms-a-zero.json", MULTISLOPE, "multislope shape", a=0.0)
    bad_model("ms-b-below-a.json", MULTISLOPE, "multislope shape", a=1.2, b=0.8)
    bad_model("ms-h-two.json", MULTISLOPE, "multislope shape", h=2.0)
    bad_model("ms-U-zero.json", MULTISLOPE, "multislope shape", U=0)
    bad_model("ms-U-negative.json", MULTISLOPE, "multislope shape", U=-150)
    bad_model("ms-U-string.json", MULTISLOPE, "U", U="150")
    bad_model("ms-U-list.json", MULTISLOPE, "U", U=[150])
    bad_model("ms-U-huge.json", MULTISLOPE, "overflow", U=1.6e308,
              note="b U overflows: the envelopes would be infinite")
    bad_model("ms-threshold-above-max.json", MULTISLOPE, "above (1 - a)U/(1 - a h)",
              thresholds=[0, 20, 30, 60])
    # pwl polylines
    bad_model("pwl-rising-object.json", PWL, "rising", rising={"x": [0, 150], "y": [0, 150]})
    bad_model("pwl-missing-y.json", PWL, "rising[0]", rising=[{"x": [0, 150]}])
    bad_model("pwl-x-decreasing.json", PWL, "strictly increasing",
              rising=[{"x": [150, 0], "y": [-10, 140]}])
    bad_model("pwl-y-decreasing.json", PWL, "non-decreasing",
              rising=[{"x": [0, 150], "y": [140, -10]}])
    bad_model("pwl-x-empty.json", PWL, "no breakpoints", rising=[{"x": [], "y": []}])
    bad_model("pwl-length-mismatch.json", PWL, "rising[0]", rising=[{"x": [0, 150], "y": [0]}])
    bad_model("pwl-rising-above-falling.json", PWL, "pwl", rising=PWL["falling"],
              falling=PWL["rising"])
    bad_model("pwl-count.json", PWL, "one rising and one falling", weights=[0.3, 0.2])
    bad_model("pwl-x-strings.json", PWL, "rising[0]", rising=[{"x": ["0", "150"],
                                                                "y": [-10, 140]}])


# ------------------------------------------------------------------ records (CSV)
def _triangle(n=61, top=150.0):
    half = n // 2
    u = np.r_[np.linspace(0, top, half + 1), np.linspace(top, 0, half + 1)[1:]]
    t = np.arange(u.size, dtype=float)
    # counter-clockwise, as a piezo's loop: the rising branch below the falling one
    y = 0.3 * u + 0.05 * np.sqrt(u * (top - u)) * np.r_[-np.ones(half + 1), np.ones(half)]
    return t, u, y


def _csv(t, u, y, header="time_s,voltage_V,displacement_um", sep=",", newline="\n"):
    rows = [header] + [sep.join(f"{v:.17g}" for v in row) for row in zip(t, u, y)]
    return newline.join(rows) + newline


def record(name, content, says=None, expect=None, values=None, note=""):
    if expect is None:
        expect = {c: 2 for c in CSV_COMMANDS}
    put("csv", name, content, expect, says, values, note)


def records():
    t, u, y = _triangle()
    good = _csv(t, u, y)
    values = {"time_s": t.tolist(), "voltage_V": u.tolist(), "displacement_um": y.tolist()}
    ok = {c: 0 for c in CSV_COMMANDS}
    ok_values = values
    record("ok-loop.csv", good, expect=ok, values=ok_values)
    record("ok-bom.csv", "\ufeff" + good, expect=ok, values=ok_values,
           note="Excel writes a byte-order mark")
    record("ok-crlf.csv", good.replace("\n", "\r\n"), expect=ok, values=ok_values)
    record("ok-comments.csv", "# recorded 2026-01-01\n" + good.replace("\n", "\n# note\n", 5),
           expect=ok, values=ok_values)
    record("ok-column-order.csv", _csv(y, t, u, header="displacement_um,time_s,voltage_V"),
           expect=ok, values=ok_values)
    record("ok-spaces.csv", good.replace(",", " , "), expect=ok, values=ok_values)
    record("ok-extra-column.csv", "\n".join(
        line + (",extra" if i == 0 else ",x") for i, line in enumerate(good.splitlines())) + "\n",
        expect=ok, values=ok_values)
    record("ok-quoted.csv", "\n".join(
        ",".join(f'"{f}"' for f in line.split(",")) for line in good.splitlines()) + "\n",
        expect=ok, values=ok_values)

    record("empty.csv", "", "csv/empty.csv:1: empty file")
    record("whitespace.csv", "  \n\n \t\n", "csv/whitespace.csv:1: empty file")
    record("comments-only.csv", "# nothing\n# here\n", "empty file")
    record("header-only.csv", "time_s,voltage_V,displacement_um\n", "no data rows")
    record("binary.csv", bytes(np.random.default_rng(2).integers(0, 256, 400, dtype=np.uint8)),
           "csv/binary.csv:")
    record("zeros.csv", bytes(1000), "csv/zeros.csv:")
    record("utf16.csv", good.encode("utf-16"), "csv/utf16.csv:")
    lines = good.splitlines()
    lines[5] = lines[5].replace(",", ",\xe9", 1)
    record("non-utf8-value.csv", "\n".join(lines).encode("latin-1") + b"\n",
           "csv/non-utf8-value.csv:6")
    record("semicolons.csv", good.replace(",", ";"), "separated by commas")
    record("tabs.csv", good.replace(",", "\t"), "missing column")
    record("no-header.csv", "\n".join(good.splitlines()[1:]) + "\n", "missing column")
    record("misspelt-header.csv", good.replace("voltage_V", "Voltage_V", 1)
           .replace("displacement_um", "displacement", 1), "missing column")

    def with_cell(line, col, text, name, says, note=""):
        rows = good.splitlines()
        fields = rows[line - 1].split(",")
        fields[col - 1] = text
        rows[line - 1] = ",".join(fields)
        record(name, "\n".join(rows) + "\n", says, note=note)

    # a bad value matters to the commands that read its column
    readers = {"voltage": {"predict": 2, "fit": 2, "compensate": 0, "track": 0},
               "displacement": {"predict": 0, "fit": 2, "compensate": 2, "track": 2}}
    for col, column in ((2, "voltage"), (3, "displacement")):
        for text, what in (("abc", "text"), ("", "missing"), ("nan", "nan"), ("inf", "inf"),
                           ("-Infinity", "neg-inf"), ("1e400", "overflow"), ("0x1A", "hex"),
                           ("1.5.2", "two-points"), ("1,5", "decimal-comma-cell")):
            name = f"{what}-{column}.csv"
            with_cell(7, col, text, name, f"csv/{name}:7:{col}")
            MANIFEST[f"csv/{name}"]["expect"] = dict(readers[column])
    with_cell(7, 1, "abc", "text-time.csv", None)
    MANIFEST["csv/text-time.csv"]["expect"] = {"predict": 2, "fit": 0, "compensate": 2,
                                               "track": 2}
    MANIFEST["csv/text-time.csv"]["says"] = "csv/text-time.csv:7:1"
    rows = good.splitlines()
    rows[9] = "5,7"
    record("short-row.csv", "\n".join(rows) + "\n", "csv/short-row.csv:10:3",
           expect={"predict": 0, "fit": 2, "compensate": 2, "track": 2},
           note="predict reads only time_s and voltage_V, which the row has")
    rows = good.splitlines()
    rows[9] = rows[9] + ",3,4"
    record("long-row.csv", "\n".join(rows) + "\n", "csv/long-row.csv:10",
           note="a row with more fields than the header: a decimal comma, a shifted row")
    rows = good.splitlines()
    rows[9] = '"3.5,1,2'
    record("open-quote.csv", "\n".join(rows) + "\n", "csv/open-quote.csv:10")
    record("decimal-comma.csv", _csv(t, u, y).replace(".", ","),
           "csv/decimal-comma.csv:2", note="a European decimal comma")
    record("huge-field.csv", "time_s,voltage_V,displacement_um\n0,0,0\n1," + "1" * 200000
           + ",0\n", "csv/huge-field.csv:3")
    record("bare-cr.csv", "\r" + good[1:], "csv/bare-cr.csv:1",
           note="a carriage return alone inside a line (found by the fuzz)")
    record("nul-byte.csv", good.replace("\n", "\n\x00", 1), "csv/nul-byte.csv:2",
           expect={"predict": 2, "fit": 0, "compensate": 2, "track": 2},
           note="a NUL byte in the time_s field of line 2 (fit does not read time_s)")
    record("duplicate-column.csv", "\n".join(
        line + "," + line.split(",")[1] for line in good.splitlines()) + "\n",
        "voltage_V", note="which voltage_V? an error, not the first one")
    # time problems (track needs time_s going forward; predict/fit/compensate do not)
    back = t.copy()
    back[10] = 3.0
    record("time-backwards.csv", _csv(back, u, y), "csv/time-backwards.csv:12:1",
           expect={"predict": 0, "fit": 0, "compensate": 0, "track": 2})
    record("no-time.csv", _csv(u, u, y, header="voltage_V,voltage_V2,displacement_um")
           .replace("voltage_V2", "x"), "missing column 'time_s'",
           expect={"predict": 0, "fit": 0, "compensate": 0, "track": 2})
    # values
    record("voltage-above-range.csv", _csv(t, u * 2, y), "csv/voltage-above-range.csv:",
           expect={"predict": 2, "fit": 0, "compensate": 0, "track": 0})
    record("voltage-negative.csv", _csv(t, u - 10, y), "csv/voltage-negative.csv:2:2",
           expect={"predict": 2, "fit": 0, "compensate": 0, "track": 0})
    record("huge-values.csv", _csv(t, u * 1e298, y * 1e298), "csv/huge-values.csv",
           expect={"predict": 2, "fit": 2, "compensate": 0, "track": 0},
           note="values near 1e300: squares overflow")
    record("tiny-values.csv", _csv(t, u * 1e-300, y * 1e-300), "csv/tiny-values.csv",
           expect={"predict": 0, "fit": 2, "compensate": 0, "track": 0},
           note="values near 1e-300: squares underflow")
    record("one-row.csv", _csv(t[:1], u[:1], y[:1]), "too few samples",
           expect={"predict": 0, "fit": 2, "compensate": 0, "track": 0})
    record("two-rows.csv", _csv(t[:2], u[:2], y[:2]), "too few samples",
           expect={"predict": 0, "fit": 2, "compensate": 0, "track": 0})
    n = 200
    record("constant-voltage.csv", _csv(np.arange(n), np.full(n, 75.0), np.linspace(0, 1, n)),
           "constant", expect={"predict": 0, "fit": 2, "compensate": 0, "track": 0})
    record("constant-displacement.csv", _csv(t, u, np.full(u.size, 3.0)), "constant",
           expect={"predict": 0, "fit": 2, "compensate": 0, "track": 0})
    rng = np.random.default_rng(7)
    uu = np.tile(np.r_[np.linspace(0, 150, 151), np.linspace(149, 1, 149)], 10)
    record("pure-noise.csv", _csv(np.arange(uu.size), uu, rng.normal(0, 1, uu.size)),
           "noise", expect={"predict": 0, "fit": 2, "compensate": 0, "track": 0},
           note="displacement unrelated to the voltage")
    up = np.linspace(0, 150, 301)
    record("monotone-input.csv", _csv(np.arange(up.size), up, 0.3 * up + 0.001 * up ** 1.5),
           "never reverses", expect={"predict": 0, "fit": 2, "compensate": 0, "track": 0},
           note="no falling branch: no hysteresis to identify")
    tt, uu2, _ = _triangle(301)
    exact = 0.3 * uu2
    record("no-hysteresis.csv", _csv(tt, uu2, exact), None,
           expect={"predict": 0, "fit": 0, "compensate": 0, "track": 0},
           note="a straight line: fitted with a warning that there is no hysteresis")
    MANIFEST["csv/no-hysteresis.csv"]["warns"] = {"fit": "no hysteresis"}
    top_first = np.r_[np.linspace(150, 0, 151), np.linspace(0, 150, 151)[1:],
                      np.linspace(150, 0, 151)[1:]]
    true = {"family": "classical", "thresholds": [0, 20, 50], "weights": [0.2, 0.1, 0.05]}
    import pihyst
    y_top = pihyst.load_model(true).predict(top_first, initial_state=[150, 130, 100])
    record("exact-from-top.csv", _csv(np.arange(top_first.size), top_first, y_top), None,
           expect={"predict": 0, "fit": 0, "compensate": 0, "track": 0},
           note="noise-free record starting at the top of its range")
    square = np.tile([0.0, 150.0], 50)
    record("two-levels.csv", _csv(np.arange(square.size), square, 0.3 * square), "distinct",
           expect={"predict": 0, "fit": 2, "compensate": 0, "track": 0},
           note="a square wave: two input levels say nothing about the loop")
    offset = np.r_[np.linspace(0, 1e-7, 31), np.linspace(1e-7, 0, 31)[1:]] + 1e3
    record("no-resolution.csv", _csv(np.arange(offset.size), offset, offset - 1e3),
           {"fit": "too little for floating point", "predict": "outside the model's input"},
           expect={"predict": 2, "fit": 2, "compensate": 0, "track": 0},
           note="the input changes in its 11th digit: nothing left to fit")


def readers():
    """Issue 24's readers: a headerless first row that is not a valid sample, a last
    number cut short, a tail of NULs, and binary records truncated, bit-flipped or
    empty (each library's exception, one line naming the file)."""
    import io as _io

    import scipy.io
    t, u, y = _triangle()
    every = {c: 2 for c in CSV_COMMANDS}
    body = _csv(t, u, y).split("\n", 1)[1]
    for name, first in (("nan", "nan"), ("inf", "inf"), ("hex", "0x10")):
        record(f"first-row-{name}.csv", f"0,{first},0\n" + body,
               f"first-row-{name}.csv:1:2: '{first}' is not a", expect=every,
               note="a headerless first row with a value that is not a sample: an error, "
                    "not a header")
    text = _csv(t, u, y) + "99,5,0."
    lines = text.count("\n") + 1
    record("cut-last-number.csv", text,
           f"cut-last-number.csv:{lines}:3: the last line ends without a line end",
           expect=every, note="the file cut off in its last number")
    record("nul-tail.csv", (_csv(t, u, y) + "\0" * 70000).encode(),
           f"nul-tail.csv:{lines}: not a text file (it holds NUL bytes) from this line on",
           expect=every,
           note="a tail of NULs (a file cut off, a sparse file): the data end there")
    buffers = {}
    b = _io.BytesIO()
    np.savez(b, time_s=t, voltage_V=u, displacement_um=y)
    buffers["npz"] = b.getvalue()
    b = _io.BytesIO()
    np.save(b, np.c_[t, u, y])
    buffers["npy"] = b.getvalue()
    for name, compress in (("mat", False), ("zmat", True)):
        b = _io.BytesIO()
        scipy.io.savemat(b, {"time_s": t, "voltage_V": u, "displacement_um": y},
                         do_compression=compress)
        buffers[name] = b.getvalue()
    for kind, data in buffers.items():
        ext = "mat" if kind == "zmat" else kind
        record(f"cut-{kind}.{ext}", data[:len(data) // 2], "cannot read", expect=every,
               note=f"a .{ext} file cut in half")
        record(f"empty-{kind}.{ext}", b"", "cannot read", expect=every,
               note=f"an empty .{ext} file")
    flipped = bytearray(buffers["zmat"])
    for k in range(len(flipped) // 2, len(flipped) // 2 + 16):
        flipped[k] ^= 0xFF
    record("flipped-zmat.mat", bytes(flipped), "cannot read MATLAB file", expect=every,
           note="bit flips in a compressed MATLAB file (a zlib error)")
    flipped = bytearray(buffers["npz"])
    for k in range(len(flipped) // 3, len(flipped) // 3 + 16):
        flipped[k] ^= 0xFF
    record("flipped.npz", bytes(flipped), "cannot read", expect=every,
           note="bit flips in an .npz (a bad CRC, BadZipFile)")
    found = os.path.join(ROOT, "csv", "scipy-segv.mat")     # kept as the fuzz found it
    if os.path.exists(found):
        with open(found, "rb") as f:
            record("scipy-segv.mat", f.read(), "cannot read MATLAB file",
                   expect=every, note="bit flips in a MATLAB v5 file on which SciPy's "
                   "loadmat crashes with SIGSEGV, or in some processes raises "
                   "ZeroDivisionError (found by the fuzz test): read in a forked child, a "
                   "one-line error either way")


def inputs():
    """The other input of each command: voltages inside every corpus model's range, a
    desired displacement (with times) within their reach."""
    t = np.arange(41.0)
    u = np.r_[np.linspace(0, 50, 21), np.linspace(50, 0, 21)[1:]]
    put("input", "volts.csv", _csv(t, u, 0.3 * u), {})
    put("input", "desired.csv", _csv(t, u, 0.1 * u), {})


def main():
    inputs()
    models()
    records()
    readers()
    with open(os.path.join(ROOT, "manifest.json"), "w") as f:
        json.dump(MANIFEST, f, indent=1, sort_keys=True)
        f.write("\n")
    print(f"{len(MANIFEST)} corpus files in {ROOT}")


if __name__ == "__main__":
    main()
