"""pihyst compensate: docs/interfaces.md formats, limits and slew options, one-line errors
with exit status 2 and no partial output."""

import numpy as np
import pytest

from pihyst.cli import main
from pihyst.io import read_columns

CLASSICAL = "examples/paper_table1_classical.json"
MULTISLOPE = "examples/paper_table1_multislope.json"


def run(*argv):
    return main(list(argv))


def test_predict_then_compensate_gives_the_voltages_back(tmp_path, capsys):
    predicted = tmp_path / "pred.csv"
    assert run("predict", CLASSICAL, "examples/triangle_0_150V.csv", "-o", str(predicted)) == 0
    out = tmp_path / "comp.csv"
    assert run("compensate", CLASSICAL, str(predicted), "-o", str(out)) == 0
    cols, _ = read_columns(out, ["time_s", "voltage_V", "displacement_um", "saturated"])
    given, _ = read_columns(predicted, ["time_s", "voltage_V", "displacement_um"])
    np.testing.assert_allclose(cols["voltage_V"], given["voltage_V"], atol=1e-9)
    np.testing.assert_allclose(cols["displacement_um"], given["displacement_um"], atol=1e-9)
    np.testing.assert_array_equal(cols["time_s"], given["time_s"])
    assert not cols["saturated"].any()
    text = capsys.readouterr().out
    assert "wrote 301 samples" in text and "saturated: 0 of 301 samples" in text


def test_out_of_reach_is_counted(tmp_path, capsys):
    src = tmp_path / "d.csv"
    src.write_text("# desired\ntime_s,displacement_um,note\n0,0,a\n1,10,b\n2,50,c\n3,20,d\n"
                   "4,-1,e\n")
    out = tmp_path / "out.csv"
    assert run("compensate", MULTISLOPE, str(src), "-o", str(out), "--saturate") == 0
    cols, _ = read_columns(out, ["voltage_V", "displacement_um", "saturated"])
    np.testing.assert_array_equal(cols["saturated"], [0, 0, 1, 0, 1])
    assert cols["voltage_V"][2] == 150.0 and cols["voltage_V"][4] == 0.0
    np.testing.assert_allclose(cols["displacement_um"][[0, 1, 3]], [0, 10, 20], atol=1e-9)
    assert "saturated: 2 of 5 samples (1 at 0 V, 1 at 150 V)" in capsys.readouterr().out


def test_limits_and_slew_rate_in_volts_per_second(tmp_path, capsys):
    src = tmp_path / "d.csv"
    t = np.arange(40) * 0.5
    y = 20 + 15 * np.sin(t)
    src.write_text("time_s,displacement_um\n" + "".join(f"{a},{b}\n" for a, b in zip(t, y)))
    out = tmp_path / "out.csv"
    assert run("compensate", MULTISLOPE, str(src), "-o", str(out), "--saturate", "--u-min", "5",
               "--u-max", "120", "--slew-rate", "40") == 0
    cols, _ = read_columns(out, ["voltage_V", "saturated", "slew_limited"])
    u = cols["voltage_V"]
    assert np.all((u >= 5) & (u <= 120))
    assert np.all(np.abs(np.diff(np.r_[5.0, u])) <= 20.0)  # 40 V/s x 0.5 s
    assert cols["slew_limited"].any()
    text = capsys.readouterr().out
    assert "slew-limited:" in text and "at or toward 120 V" in text


def test_without_time_column_uses_sample_index(tmp_path):
    src = tmp_path / "d.csv"
    src.write_text("displacement_um\n1\n2\n")
    out = tmp_path / "out.csv"
    assert run("compensate", CLASSICAL, str(src), "-o", str(out)) == 0
    cols, _ = read_columns(out, ["time_s", "voltage_V"])
    np.testing.assert_array_equal(cols["time_s"], [0, 1])


@pytest.mark.parametrize("content,options,where,what", [
    ("time_s,displacement_um\n0,0\n1,abc\n", (), "d.csv:3:2:", "'abc' is not a number"),
    ("time_s,displacement_um\n0,0\n1,nan\n", (), "d.csv:3:2:", "not a finite number"),
    ("time_s,displacement_um\n0,0\n1,\n", (), "d.csv:3:2:", "missing value"),
    ("time_s,voltage_V\n0,0\n", (), "d.csv:1:", "missing column 'displacement_um'"),
    ("", (), "d.csv:1:", "empty file"),
    ("time_s,displacement_um\n", (), "d.csv:1:", "no data rows"),
    ("time_s,displacement_um\n0,0\n1,1\n1,2\n", ("--slew-rate", "5"), "d.csv:4:1:",
     "does not increase"),
    ("displacement_um\n0\n1\n", ("--slew-rate", "5"), "d.csv", "needs a time_s column"),
    ("time_s,displacement_um\n0,0\n", ("--slew-rate", "-5"), "", "must be a positive"),
    ("time_s,displacement_um\n0,0\n", ("--u-min", "-10"), "json:", "input range"),
    ("time_s,displacement_um\n0,0\n", ("--u-min", "100", "--u-max", "50"), "json:",
     "must be below --u-max"),
])
def test_bad_input_one_line_error_exit_2_no_output(tmp_path, capsys, content, options, where,
                                                    what):
    src = tmp_path / "d.csv"
    src.write_text(content)
    out = tmp_path / "out.csv"
    assert run("compensate", MULTISLOPE, str(src), "-o", str(out), *options) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("pihyst: error: ")
    assert where in err and what in err
    assert not out.exists()
    assert not list(tmp_path.glob(".pihyst-*"))


def test_model_with_negative_weights_is_a_one_line_error(tmp_path, capsys):
    model = tmp_path / "m.json"
    model.write_text('{"family": "classical", "thresholds": [0, 10], "weights": [1, -0.5]}')
    src = tmp_path / "d.csv"
    src.write_text("time_s,displacement_um\n0,1\n")
    out = tmp_path / "out.csv"
    assert run("compensate", str(model), str(src), "-o", str(out)) == 2
    err = capsys.readouterr().err
    assert "non-negative weights" in err and err.count("\n") == 1
    assert not out.exists()


@pytest.mark.parametrize("far", ["100", "1e308", "-5"])
def test_strict_refuses_out_of_reach_whatever_the_slew_rate(tmp_path, capsys, far):
    src = tmp_path / "d.csv"
    src.write_text(f"time_s,displacement_um\n0,0\n1,{far}\n2,{far}\n3,{far}\n")
    out = tmp_path / "out.csv"
    assert run("compensate", MULTISLOPE, str(src), "-o", str(out), "--slew-rate", "2",
               "--strict") == 2
    err = capsys.readouterr().err
    assert err.startswith(f"pihyst: error: {src}:3:2: displacement_um = {float(far):g} is out "
                          f"of reach: the model reaches [0, 41.38] µm")
    assert err.count("\n") == 1 and not out.exists()
    assert run("compensate", MULTISLOPE, str(src), "-o", str(out), "--saturate",
               "--slew-rate", "2") == 0
    cols, _ = read_columns(out, ["saturated", "slew_limited"])
    np.testing.assert_array_equal(cols["saturated"], [0, 1, 1, 1])
    text = capsys.readouterr().out
    assert "saturated: 3 of 4 samples" in text and "3 samples lie outside" in text


def test_strict_with_a_slew_rate_accepts_what_is_in_reach(tmp_path, capsys):
    src = tmp_path / "d.csv"
    src.write_text("time_s,displacement_um\n0,0\n1,30\n2,30\n3,30\n")
    out = tmp_path / "out.csv"
    assert run("compensate", MULTISLOPE, str(src), "-o", str(out), "--slew-rate", "2",
               "--strict") == 0
    cols, _ = read_columns(out, ["saturated", "slew_limited"])
    np.testing.assert_array_equal(cols["saturated"], [0, 0, 0, 0])
    np.testing.assert_array_equal(cols["slew_limited"], [0, 1, 1, 1])


def test_initial_state_top_starts_at_rest_at_the_top(tmp_path):
    src = tmp_path / "mid.csv"
    src.write_text("time_s,displacement_um\n0,20\n1,21\n")
    first = {}
    for mode in ("bottom", "top"):
        out = tmp_path / f"{mode}.csv"
        assert run("compensate", MULTISLOPE, str(src), "-o", str(out), "--initial-state",
                   mode) == 0
        first[mode] = read_columns(out, ["voltage_V"])[0]["voltage_V"][0]
    assert first["top"] < first["bottom"] - 20      # 20 um on the falling branch
    out = tmp_path / "slew.csv"
    assert run("compensate", MULTISLOPE, str(src), "-o", str(out), "--initial-state", "top",
               "--slew-rate", "5") == 0
    np.testing.assert_array_equal(read_columns(out, ["voltage_V"])[0]["voltage_V"], [145, 140])
    assert run("compensate", MULTISLOPE, str(src), "-o", str(out), "--initial-state", "top",
               "--slew-rate", "5", "--u-max", "120") == 0
    np.testing.assert_array_equal(read_columns(out, ["voltage_V"])[0]["voltage_V"], [115, 110])


def _absolute_model(tmp_path):
    """A model whose output lives in a sensor's absolute frame (about -119 .. -80 um), as
    the P-885 model's does."""
    import json
    with open(CLASSICAL_PATH) as f:
        d = json.load(f)
    d["offset"] = -119.0
    path = tmp_path / "abs.json"
    path.write_text(json.dumps(d))
    return path


CLASSICAL_PATH = "examples/paper_table1_classical.json"


def _triangle_desired(path, top=30.0, n=200):
    y = np.r_[np.linspace(0, top, n // 2), np.linspace(top, 0, n // 2)]
    path.write_text("time_s,displacement_um\n" + "".join(
        f"{k * 0.01!r},{v!r}\n" for k, v in enumerate(y.tolist())))
    return y


def test_targets_in_the_users_frame_with_relative(tmp_path, capsys):
    model = _absolute_model(tmp_path)
    src, out = tmp_path / "d.csv", tmp_path / "out.csv"
    y = _triangle_desired(src)
    # in the model's frame (the default) a 0-30 um triangle is out of reach: exit 2
    assert run("compensate", str(model), str(src), "-o", str(out)) == 2
    err = capsys.readouterr().err
    assert "out of the model's reach, more than 10 %" in err and "--relative" in err
    assert err.count("\n") == 1 and not out.exists()
    # --saturate says that is intended
    assert run("compensate", str(model), str(src), "-o", str(out), "--saturate") == 0
    assert "frame: absolute" in capsys.readouterr().out
    # --relative: from the model's rest point at its lowest voltage; it tracks
    assert run("compensate", str(model), str(src), "-o", str(out), "--relative") == 0
    text = capsys.readouterr().out
    assert "frame: relative, desired displacement from the model's rest point at 0 V" in text
    assert "saturated: 0 of 200 samples" in text
    cols, _ = read_columns(out, ["displacement_um", "saturated"])
    np.testing.assert_allclose(cols["displacement_um"], y, atol=1e-9)   # in the user's frame


def test_track_takes_the_frame_too(tmp_path, capsys):
    model = _absolute_model(tmp_path)
    src, out = tmp_path / "d.csv", tmp_path / "out.csv"
    _triangle_desired(src)
    assert run("track", str(model), str(src), "-o", str(out)) == 2
    assert "out of the model's reach" in capsys.readouterr().err
    assert run("track", str(model), str(src), "-o", str(out), "--relative") == 0
    assert "frame: relative" in capsys.readouterr().out
