"""The record options on the command line: the two measured records with one command
each, validate, compensate's reachable range and --strict, the input-range rule,
--initial-state, and streamed commands equal to the in-memory computation bit for bit."""

import json
import os
import warnings

import numpy as np
import pytest

import pihyst
from pihyst.cli import main
from pihyst.io import _records, _text_source, datasets, read_columns, read_record

CLASSICAL = "examples/paper_table1_classical.json"
MULTISLOPE = "examples/paper_table1_multislope.json"
DATA = datasets.data_root()
needs_data = pytest.mark.skipif(DATA is None, reason="the measured data sets (../shared/data "
                                "or $PIHYST_DATA) are not here")


def run(*argv):
    return main([str(a) for a in argv])


def triangle(path, peak=150.0, n=401, extra=""):
    u = np.r_[np.linspace(0, peak, n // 2 + 1), np.linspace(peak, 0, n // 2 + 1)[1:]]
    t = np.arange(u.size) * 0.01
    path.write_text("time_s,voltage_V" + extra + "\n"
                    + "".join(f"{a!r},{b!r}\n" for a, b in zip(t.tolist(), u.tolist())))
    return t, u


# ------------------------------------------------------------------ measured records
@needs_data
def test_p885_raw_file_fits_with_one_command(tmp_path, capsys):
    model = tmp_path / "p885.json"
    assert run("fit", DATA / datasets.P885_DIR / "Model_Vi_Do.dat", "--voltage", 1,
               "--displacement", 5, "--lag", 1, "--rate", 200, "--model", "classical",
               "-o", model) == 0
    out = capsys.readouterr().out
    assert "8026 samples, tab-separated, no header, 7 columns" in out
    u, y = datasets.p885(DATA)
    assert pihyst.load_model(model).input_range == (u.min(), u.max())
    assert run("validate", model, DATA / datasets.P885_DIR / "Test_Vi_Do_Di.dat", "--voltage",
               1, "--displacement", 5, "--lag", 1, "--rate", 200, "--json") == 0
    result = json.loads(capsys.readouterr().out)
    # judged from the state the record's first full sweep settles (stated), without it
    assert result["start_state"]["mode"] == "settle"
    assert result["errors"]["samples"] == 14154 - result["start_state"]["settling_samples"]
    assert result["offset_refitted"]["rms_um"] < 2.0


@needs_data
def test_smarthysteresis_raw_file_fits_with_one_command(tmp_path, capsys):
    model = tmp_path / "smart.json"
    assert run("fit", DATA / datasets.SMART_DIR / "hysteresis_v_150_1hz.csv", "--time", 2,
               "--displacement", 3, "--voltage", 4, "--skip-until", 4.26, "--model",
               "classical", "-o", model) == 0
    out = capsys.readouterr().out
    assert "28701 samples" in out and "21300 samples before 4.26 s skipped" in out
    assert pihyst.load_model(model).input_range == (-150.0, 150.0)


# ------------------------------------------------------------------ validate
def test_validate_a_model_on_its_own_prediction_and_a_shifted_record(tmp_path, capsys):
    src = tmp_path / "in.csv"
    triangle(src)
    pred = tmp_path / "pred.csv"
    assert run("predict", CLASSICAL, src, "-o", pred) == 0
    capsys.readouterr()
    assert run("validate", CLASSICAL, pred, "--json") == 0
    exact = json.loads(capsys.readouterr().out)
    assert exact["errors"]["max_abs_um"] == 0.0 and len(exact["cycles"]) == 1
    # judged from a start state it states: by default the one the record settles
    assert exact["start_state"]["mode"] == "settle" and not exact["start_state"]["given"]
    assert exact["start_state"]["settling_samples"] == 199
    assert exact["errors"]["samples"] == 401 - 199
    cols, _ = read_columns(pred, ["time_s", "voltage_V", "displacement_um"])
    shifted = tmp_path / "shifted.csv"
    pihyst.io.write_columns(shifted, {"t": cols["time_s"], "v": cols["voltage_V"],
                                      "d_nm": (cols["displacement_um"] + 2.0) * 1000})
    figure = tmp_path / "check.svg"
    assert run("validate", CLASSICAL, shifted, "--voltage", "v", "--displacement", "d_nm",
               "--time", "t", "--figure", figure, "--initial-state", "model") == 0
    out = capsys.readouterr().out
    assert "start state: the model file's (--initial-state model); all 401 samples judged" \
        in out
    assert "displacement in nm (column name 'd_nm') -> µm" in out
    assert "as the model is                    2         2         2     5.16 %" in out
    assert "mostly an offset of +2 µm" in out
    assert figure.read_text().lstrip().startswith("<?xml")


def _triangles():
    return np.r_[np.tile(np.r_[np.linspace(0, 150, 51), np.linspace(150, 0, 51)[1:-1]], 3), 0.0]


def _mid_range_start():
    return np.r_[np.linspace(70, 150, 30), np.linspace(150, 0, 60)[1:],
                 np.linspace(0, 150, 60)[1:], np.linspace(150, 0, 60)[1:],
                 np.linspace(0, 120, 40)[1:], np.linspace(120, 30, 40)[1:],
                 np.linspace(30, 150, 50)[1:]]


@pytest.mark.parametrize("voltage, settled", [(_triangles, 101), (_mid_range_start, 89)])
def test_settle_judges_the_span_fit_judges(tmp_path, capsys, voltage, settled):
    # --initial-state settle of validate and predict cuts the record where
    # pihyst.fit(initial_state="settle") does: at the first valley after both ends
    u = voltage()
    src = tmp_path / "rec.csv"
    model = pihyst.load_model(MULTISLOPE)
    y = model.predict(u) + 0.1
    pihyst.io.write_columns(src, {"voltage_V": u, "displacement_um": y})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pihyst.exceptions.PihystWarning)
        fitted = pihyst.fit(u, y, family="multislope", initial_state="settle")
    assert fitted.model.metadata["fit"]["settled"]["sample"] == settled
    assert run("validate", MULTISLOPE, src, "--initial-state", "settle", "--json") == 0
    result = json.loads(capsys.readouterr().out)
    assert result["first_judged_sample"] == settled
    assert result["errors"]["samples"] == u.size - settled
    assert result["errors"]["max_abs_um"] == pytest.approx(0.1)
    out = tmp_path / "predicted.csv"
    assert run("predict", MULTISLOPE, src, "--initial-state", "settle", "-o", out) == 0
    cols, _ = pihyst.io.read_columns(out, ["settling"])
    np.testing.assert_array_equal(cols["settling"], np.arange(u.size) < settled)


def test_validate_settle_needs_samples_after_the_sweep(tmp_path, capsys):
    ramp = tmp_path / "ramp.csv"
    pihyst.io.write_columns(ramp, {"voltage_V": np.linspace(0, 150, 11),
                                   "displacement_um": np.zeros(11)})
    assert run("validate", MULTISLOPE, ramp, "--initial-state", "settle") == 2
    err = capsys.readouterr().err
    assert "no samples left after the first sweep" in err and err.count("\n") == 1


# ------------------------------------------------------------------ compensate
def test_compensate_prints_reach_and_strict_refuses(tmp_path, capsys):
    src = tmp_path / "d.csv"
    src.write_text("time_s,displacement_um\n0,1\n1,10\n2,60\n3,5\n")
    out = tmp_path / "out.csv"
    assert run("compensate", MULTISLOPE, src, "-o", out, "--saturate") == 0
    text = capsys.readouterr().out
    assert "reachable displacement: [0, 41.38] µm with the voltage in [0, 150] V" in text
    assert "1 samples lie outside the reachable range" in text
    assert "sensor zero of the record the model was fitted on" in text
    out.unlink()
    assert run("compensate", MULTISLOPE, src, "-o", out, "--strict") == 2
    err = capsys.readouterr().err
    assert err.startswith(f"pihyst: error: {src}:4:2: displacement_um = 60 is out of reach")
    assert "[0, 41.38] µm" in err and err.count("\n") == 1 and not out.exists()
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".pihyst-")]


# ------------------------------------------------------------------ input range rule
def test_a_hair_outside_the_range_is_predicted_far_outside_is_an_error(tmp_path, capsys):
    src = tmp_path / "in.csv"
    src.write_text("voltage_V\n0\n150.5\n0\n")
    out = tmp_path / "out.csv"
    assert run("predict", CLASSICAL, src, "-o", out) == 0
    assert "1 samples outside the model's input range [0, 150] V" in capsys.readouterr().out
    model = pihyst.load_model(CLASSICAL)
    wide = model.replace(input_range=(0, 151))
    cols, _ = read_columns(out, ["displacement_um"])
    np.testing.assert_array_equal(cols["displacement_um"], wide.predict([0, 150.5, 0]))
    assert run("predict", MULTISLOPE, src, "-o", out) == 0
    assert "taken at the nearest end" in capsys.readouterr().out
    src.write_text("voltage_V\n0\n152\n")
    assert run("predict", CLASSICAL, src, "-o", out) == 2
    assert f"{src}:3:1: voltage_V = 152 is outside" in capsys.readouterr().err


def test_fit_input_range(tmp_path, capsys):
    src = tmp_path / "rec.csv"
    t, u = triangle(src, peak=149.99)
    y = pihyst.load_model(CLASSICAL).replace(input_range=(0, 149.99)).predict(u)
    pihyst.io.write_columns(src, {"time_s": t, "voltage_V": u, "displacement_um": y})
    model = tmp_path / "m.json"
    assert run("fit", src, "--model", "classical", "--input-range", "0,150", "-o", model,
               "--voltage", "voltage_V") == 0
    fitted = pihyst.load_model(model)
    assert fitted.input_range == (0.0, 150.0)
    assert fitted.metadata["source"]["command"].endswith("fit --voltage voltage_V")
    assert fitted.metadata["source"]["record"]["samples"] == u.size
    assert run("fit", src, "--model", "classical", "--input-range", "0,100", "-o", model) == 2
    assert "is outside --input-range 0,100" in capsys.readouterr().err


# ------------------------------------------------------------------ initial state
def test_initial_state_modes(tmp_path):
    src = tmp_path / "in.csv"
    src.write_text("voltage_V\n75\n75\n")
    results = {}
    for mode in ("bottom", "top", "zero", "model"):
        out = tmp_path / f"{mode}.csv"
        assert run("predict", CLASSICAL, src, "-o", out, "--initial-state", mode) == 0
        results[mode] = read_columns(out, ["displacement_um"])[0]["displacement_um"][0]
    model = pihyst.load_model(CLASSICAL)
    top = model.simulate([0, 150, 0, 150, 75], initial_state=np.zeros(4)).output[-1]
    assert results["top"] == top and results["bottom"] < results["top"]
    assert results["zero"] == results["model"]


# ------------------------------------------------------------------ streaming
def test_streamed_predict_and_compensate_equal_in_memory_bit_for_bit(tmp_path, monkeypatch):
    rng = np.random.default_rng(3)
    u = np.clip(75 + np.cumsum(rng.normal(0, 5, 3000)), 0, 150)
    src = tmp_path / "in.csv"
    pihyst.io.write_columns(src, {"time_s": np.arange(u.size) * 1e-3, "voltage_V": u})
    monkeypatch.setattr(_text_source, "BLOCK_BYTES", 997)   # about 25 rows a block
    monkeypatch.setattr(_records, "BLOCK_ROWS", 37)
    out = tmp_path / "pred.csv"
    for name in (CLASSICAL, MULTISLOPE):
        model = pihyst.load_model(name)
        assert run("predict", name, src, "-o", out) == 0
        predicted = read_record(out, need=("voltage", "displacement"))
        np.testing.assert_array_equal(predicted.displacement, model.predict(u))
        comp = tmp_path / "comp.csv"
        assert run("compensate", name, out, "-o", comp, "--slew-rate", 20000) == 0
        cols, _ = read_columns(comp, ["voltage_V", "displacement_um", "saturated"])
        step = 20000 * np.diff(predicted.time).min()   # V/s x the smallest time step
        whole = pihyst.compensate(model, model.predict(u), slew_rate=step, sample_period=1.0)
        np.testing.assert_array_equal(cols["voltage_V"], whole.voltage)
        np.testing.assert_array_equal(cols["displacement_um"], whole.displacement)


def test_records_of_other_formats_on_the_command_line(tmp_path, capsys):
    np.savez(tmp_path / "r.npz", v=np.array([0.0, 150.0, 0.0]))
    out = tmp_path / "out.csv"
    assert run("predict", CLASSICAL, tmp_path / "r.npz", "--voltage", "v", "--rate", 10,
               "-o", out) == 0
    cols, _ = read_columns(out, ["time_s", "displacement_um"])
    np.testing.assert_allclose(cols["displacement_um"], [0, 38.76, 3.09], atol=1e-12)
    np.testing.assert_array_equal(cols["time_s"], [0, 0.1, 0.2])
    assert run("predict", CLASSICAL, tmp_path / "r.npz", "-o", out) == 2
    err = capsys.readouterr().err
    assert "r.npz: no 'voltage_V' for the voltage" in err and err.count("\n") == 1


def test_no_progress_bar_in_a_pipe(tmp_path, capsys):
    src = tmp_path / "in.csv"
    triangle(src)
    assert run("predict", CLASSICAL, src, "-o", tmp_path / "o.csv") == 0
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("argv,message", [
    (["validate", CLASSICAL, "{src}", "--figure", "{tmp}/f.txt"], "use a .png, .svg or .pdf"),
    (["fit", "{src}", "-o", "{tmp}/m.json", "--input-range", "0-150"], "expected LO,HI"),
    (["predict", CLASSICAL, "{src}", "-o", "{tmp}/o.csv", "--lag", "-2"],
     "argument --lag: must be at least 0, got -2"),
    (["predict", CLASSICAL, "{src}", "-o", "{tmp}/o.csv", "--rate", "10"],
     "--rate is for records without a time column"),
    (["predict", CLASSICAL, "{src}", "-o", "{tmp}/o.csv", "--reader", "nothing"],
     "expected MODULE:FUNCTION"),
])
def test_bad_options_are_one_line_errors(tmp_path, capsys, argv, message):
    src = tmp_path / "in.csv"
    triangle(src, extra="")
    argv = [a.format(src=src, tmp=tmp_path) for a in argv]
    assert run(*argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("pihyst: error: ") and message in err and err.count("\n") == 1
    assert not [p for p in os.listdir(tmp_path) if p not in ("in.csv",)]


def test_reader_function_on_the_command_line(tmp_path, capsys):
    (tmp_path / "rig.py").write_text(
        "import numpy as np\n"
        "def load(path):\n"
        "    v = np.loadtxt(path)\n"
        "    return {'voltage': v, 'metadata': {'rate': 2.0}}\n")
    data = tmp_path / "volts.raw"
    data.write_text("0\n150\n0\n")
    out = tmp_path / "o.csv"
    assert run("predict", CLASSICAL, data, "--reader", f"{tmp_path / 'rig.py'}:load",
               "-o", out) == 0
    cols, _ = read_columns(out, ["time_s", "displacement_um"])
    np.testing.assert_array_equal(cols["time_s"], [0, 0.5, 1.0])
    assert "python function" in capsys.readouterr().out


READERS = (
    "import sys\n"
    "import numpy as np\n"
    "def raises(path): raise RuntimeError('boom')\n"
    "def exits(path): sys.exit(3)\n"
    "def none(path): return None\n"
    "def matrix(path): return {'voltage': np.zeros((3, 3))}\n"
    "def ragged(path): return {'voltage': [[1, 2], [3]]}\n"
    "def words(path): return {'voltage': ['a', 'b']}\n"
    "def keys(path): return {'voltage': np.zeros(3), 1: 2, 'x': 3}\n"
    "def meta(path): return {'voltage': np.zeros(3), 'metadata': 5}\n"
    "def rate(path): return {'voltage': np.zeros(3), 'metadata': {'rate': -5}}\n"
    "not_a_function = 3\n")


@pytest.mark.parametrize("function,message", [
    ("raises", "the reader {readers}:raises failed: RuntimeError: boom"),
    ("exits", "the reader {readers}:exits failed: it called sys.exit(3)"),
    ("none", "the reader returned NoneType"),
    ("matrix", "the reader's 'voltage' has shape (3, 3)"),
    ("ragged", "the reader's 'voltage' is not an array of numbers"),
    ("words", "'voltage' holds <U1 values, not numbers"),
    ("keys", "the reader returned unknown keys 'x', 1"),
    ("meta", "the reader's 'metadata' is int, expected a dict"),
    ("rate", "the reader's metadata 'rate' must be positive, got -5"),
    ("not_a_function", "'not_a_function' in {readers} is not a function but int"),
    ("missing", "{readers} has no function 'missing'"),
])
def test_a_failing_or_bad_reader_function_is_a_one_line_user_error(tmp_path, capsys,
                                                                    function, message):
    readers = tmp_path / "readers.py"
    readers.write_text(READERS)
    data = tmp_path / "volts.raw"
    data.write_text("0\n")
    assert run("predict", CLASSICAL, data, "--reader", f"{readers}:{function}",
               "-o", tmp_path / "o.csv") == 2
    err = capsys.readouterr().err
    assert err.startswith(f"pihyst: error: {data}: ") and err.count("\n") == 1
    assert message.format(readers=readers) in err
    assert not (tmp_path / "o.csv").exists()


def test_a_reader_module_that_fails_to_load_is_a_one_line_user_error(tmp_path, capsys):
    (tmp_path / "broken.py").write_text("raise RuntimeError('at import')\n")
    data = tmp_path / "volts.raw"
    data.write_text("0\n")
    assert run("predict", CLASSICAL, data, "--reader", f"{tmp_path / 'broken.py'}:load",
               "-o", tmp_path / "o.csv") == 2
    err = capsys.readouterr().err
    assert "cannot load it (RuntimeError: at import)" in err and err.count("\n") == 1


VOLTS_160 = ("time_s,voltage_V,displacement_um\n"
             + "".join(f"{k},{v},0\n" for k, v in enumerate([0, 10, 20, 30, 40, 160, 60])))
OUT_OF_REACH = ("time_s,displacement_um\n"
                + "".join(f"{k / 10},{d}\n" for k, d in enumerate([0, 1, 2, 3, 4, 5, 99, 6])))
TIME_BACK = ("time_s,displacement_um\n"
             + "".join(f"{t},{k}\n" for k, t in enumerate([0, 1, 2, 3, 4, 3.5, 6])))


@pytest.mark.parametrize("text, argv, where", [
    (VOLTS_160, ["predict", "-o", "{tmp}/o.csv", "--skip-until", "3"],
     "7:2: voltage_V = 160 is outside"),
    (VOLTS_160, ["validate", "--skip-until", "3", "--lag", "1"],
     "7:2: voltage_V = 160 is outside"),
    (VOLTS_160, ["validate", "--skip-until", "3"], "7:2: voltage_V = 160 is outside"),
    (OUT_OF_REACH, ["compensate", "-o", "{tmp}/o.csv", "--strict", "--skip-until", "0.5"],
     "8:2: displacement_um = 99 is out of reach"),
    (TIME_BACK, ["compensate", "-o", "{tmp}/o.csv", "--slew-rate", "100", "--skip-until", "2"],
     "7:1: time_s = 3.5 "),
    (TIME_BACK, ["track", "-o", "{tmp}/o.csv", "--skip-until", "2"], "7:1: time_s = 3.5 "),
])
def test_errors_after_skip_until_name_the_files_line(tmp_path, capsys, text, argv, where):
    """The reader counts the skipped lines as it goes: an error found while streaming the
    samples kept after --skip-until names the file's own line."""
    src = tmp_path / "in.csv"
    src.write_text(text)
    command, *options = argv
    assert run(command, MULTISLOPE, src, *[a.format(tmp=tmp_path) for a in options]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"pihyst: error: {src}:{where}"), err


@pytest.mark.parametrize("command,options,message", [
    (command, ["--voltage-gain", "1e308"],
     "{src}:4:2: column 'voltage_V': 10 times the voltage gain 1e+308 is too large")
    for command in ("predict", "validate")] + [
    ("validate", ["--displacement-unit", "m"],
     "{src}:3:3: column 'displacement_um': 1e+303 times 1e+06 (m to µm) is too large"),
] + [
    (command, ["--rate", "1e-310", "--time", "none"],
     "{src}: sample 1: its time 1 / --rate 1e-310 Hz is too large for a double")
    for command in ("predict", "validate")])
def test_a_scale_option_that_overflows_is_one_line(tmp_path, capsys, command, options,
                                                   message):
    src = tmp_path / "in.csv"
    src.write_text("time_s,voltage_V,displacement_um\n0,0,0\n1,0,1e303\n2,10,0\n3,0,0\n")
    out = ["-o", tmp_path / "o.csv"] if command == "predict" else []
    assert run(command, CLASSICAL, src, *out, *options) == 2
    err = capsys.readouterr().err
    assert err.startswith("pihyst: error: " + message.format(src=src)), err
    assert err.count("\n") == 1 and "warning" not in err


@pytest.mark.parametrize("command,option", [
    *[(c, o) for c in ("compensate", "track")
      for o in (["--voltage-gain", "20"], ["--lag", "1"], ["--voltage", "2"])],
    *[("predict", o) for o in (["--lag", "1"], ["--displacement", "2"],
                               ["--displacement-unit", "nm"], ["--displacement-gain", "-1"])],
])
def test_a_record_option_a_command_does_not_use_is_refused(tmp_path, capsys, command, option):
    src = tmp_path / "in.csv"
    src.write_text("time_s,voltage_V,displacement_um\n0,0,0\n1,10,1\n2,0,0\n")
    assert run(command, MULTISLOPE, src, "-o", tmp_path / "o.csv", *option) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"pihyst: error: argument {option[0]}: not used by pihyst "
                          f"{command}: "), err
    assert err.count("\n") == 1 and not (tmp_path / "o.csv").exists()


def test_lag_zero_is_accepted_where_no_lag_applies(tmp_path):
    src = tmp_path / "in.csv"
    src.write_text("time_s,voltage_V,displacement_um\n0,0,0\n1,10,1\n2,0,0\n")
    assert run("compensate", MULTISLOPE, src, "-o", tmp_path / "o.csv", "--lag", "0") == 0


def test_progress_bar_on_a_terminal(monkeypatch):
    pytest.importorskip("tqdm")
    import io

    from pihyst.cli.record_options import progress_bar

    class Terminal(io.StringIO):
        def isatty(self):
            return True
    term = Terminal()
    monkeypatch.setattr("sys.stderr", term)
    with progress_bar("reading big.csv") as bar:
        bar(50, 100)
        bar(100, 100)
    assert "reading big.csv" in term.getvalue() and "100" in term.getvalue()


# ------------------------------------------------------------------ units rows
def loop_rows(n=200):
    u = 75 + 75 * np.sin(np.linspace(0, 6 * np.pi, n))
    y = pihyst.load_model(CLASSICAL).predict(u)
    return "".join(f"{k * 0.01!r},{a!r},{b!r}\n" for k, (a, b) in enumerate(zip(u.tolist(),
                                                                           y.tolist())))


@pytest.mark.parametrize("units,option,ok", [
    ("s,V,um", None, True), ("s,V,um", "--units-row", True),
    ("s,V,um", "--no-units-row", False),
    ("sec,Volt,micron", None, False), ("sec,Volt,micron", "--units-row", True)])
def test_units_row_detected_forced_or_refused(tmp_path, capsys, units, option, ok):
    path = tmp_path / "loop.csv"
    path.write_text("time_s,voltage_V,displacement_um\n" + units + "\n" + loop_rows())
    code = run("predict", CLASSICAL, path, "-o", tmp_path / "out.csv",
               *([option] if option else []))
    out, err = capsys.readouterr()
    if ok:
        assert code == 0 and "units on line 2" in out
        assert read_columns(tmp_path / "out.csv", ["voltage_V"])[0]["voltage_V"].size == 200
    else:
        assert code == 2 and f"{path}:2:" in err and "is not a number" in err
        assert ("pass --units-row" in err) == (option is None)
        assert not (tmp_path / "out.csv").exists()


def test_units_row_forced_where_there_is_none_to_take(tmp_path, capsys):
    path = tmp_path / "bare.csv"
    path.write_text(loop_rows(30))
    assert run("predict", CLASSICAL, path, "-o", tmp_path / "o.csv", "--voltage", 2,
               "--units-row") == 2
    assert "no header line for a units row" in capsys.readouterr().err
    npy = tmp_path / "u.npy"
    np.save(npy, np.linspace(0, 150, 30))
    assert run("predict", CLASSICAL, npy, "-o", tmp_path / "o.csv", "--no-units-row") == 2
    assert "for delimited text files" in capsys.readouterr().err


def test_fit_says_its_time_column_in_the_read_line(tmp_path, capsys):
    path = tmp_path / "loop.csv"
    path.write_text("time_s,voltage_V,displacement_um\n" + loop_rows(400))
    assert run("fit", path, "--model", "classical", "-o", tmp_path / "m.json") == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first.startswith(f"read {path}") and "time column 1 'time_s'" in first
    assert first.endswith("time used for creep")


def test_a_displacement_that_falls_as_the_voltage_rises_is_named(tmp_path, capsys):
    """A sensor counting the other way (a distance to the target): the fit says so and
    how to read it, in one line with no model written; --displacement-gain -1 fits it."""
    u = np.tile(np.r_[np.linspace(0, 150, 60), np.linspace(150, 0, 60)], 3)
    y = 0.1 * u + 2.0 * np.sin(np.deg2rad(u)) * np.tile(np.r_[np.ones(60), -np.ones(60)], 3)
    src = tmp_path / "dist.csv"
    np.savetxt(src, np.c_[u, 100.0 - y], delimiter=",", header="voltage_V,distance_um",
               comments="")
    out = tmp_path / "m.json"
    assert run("fit", src, "--displacement", "distance_um", "-o", out) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "falls as the voltage rises" in err
    assert "--displacement-gain -1" in err and not out.exists()
    assert run("fit", src, "--displacement", "distance_um", "--displacement-gain", "-1",
               "-o", out) == 0
    assert out.exists()
