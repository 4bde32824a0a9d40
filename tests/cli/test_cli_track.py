"""pihyst track: desired -> compensator -> simulated beam -> measured, errors printed;
one-line errors with exit status 2 and no partial output."""

import numpy as np
import pytest

from pihyst.cli import main
from pihyst.io import read_columns, write_columns
from pihyst.sim import signals

MODEL = "examples/paper_table1_multislope.json"


def run(*argv):
    return main(list(argv))


@pytest.fixture
def desired(tmp_path):
    t, y = signals.decaying_triangles(u_min=1.0, u_max=35.0, n_triangles=3, dt=0.5)
    path = tmp_path / "desired.csv"
    write_columns(path, {"time_s": t, "displacement_um": y})
    return path, t, y


def test_track_writes_measured_and_errors(tmp_path, capsys, desired):
    path, t, y = desired
    out = tmp_path / "tracked.csv"
    assert run("track", MODEL, str(path), "--plant", "lens", "--seed", "3", "-o", str(out)) == 0
    cols, _ = read_columns(out, ["time_s", "desired_um", "voltage_V", "displacement_um",
                                 "predicted_um", "error_um", "saturated"])
    np.testing.assert_array_equal(cols["time_s"], t)
    np.testing.assert_array_equal(cols["desired_um"], y)
    np.testing.assert_allclose(cols["error_um"], cols["displacement_um"] - y, atol=1e-12)
    np.testing.assert_allclose(cols["predicted_um"], y, atol=1e-9)  # the model is inverted
    assert np.all((cols["voltage_V"] >= 0) & (cols["voltage_V"] <= 150))
    text = capsys.readouterr().out
    mae = np.mean(np.abs(cols["error_um"]))
    assert f"mean absolute {mae:.4g} µm" in text and "% of the desired range" in text
    assert "saturated: 0 of" in text


def test_track_is_deterministic_for_a_seed(tmp_path, desired):
    path, _, _ = desired
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    for out in (a, b):
        assert run("track", MODEL, str(path), "--seed", "5", "-o", str(out),
                   "--slew-rate", "20") == 0
    assert a.read_text() == b.read_text()


@pytest.mark.parametrize("content,options,what", [
    ("displacement_um\n1\n2\n", (), "missing column 'time_s' in header (displacement_um); "
     "name the time column with --time NAME or --time NUMBER, or give the sample rate, "
     "--rate HZ"),
    ("time_s,displacement_um\n0,1\n1,2\n", ("--rate", "10"), "--rate is for records without"),
    ("time_s,displacement_um\n0,1\n2,2\n1,3\n", (), "d.csv:4:1: time_s = 1 goes back"),
    ("time_s,displacement_um\n0,1\n1,nan\n", (), "d.csv:3:2:"),
    ("time_s,displacement_um\n0,1\n", ("--u-max", "200"), "--u-max 200 is outside"),
    ("time_s,displacement_um\n0,1\n1,2\n", ("--slew-rate", "0"), "must be a positive"),
])
def test_bad_input(tmp_path, capsys, content, options, what):
    src = tmp_path / "d.csv"
    src.write_text(content)
    out = tmp_path / "out.csv"
    assert run("track", MODEL, str(src), "-o", str(out), *options) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("pihyst: error: ") and what in err
    assert not out.exists()


def test_track_takes_the_times_from_rate(tmp_path, capsys, desired):
    path, t, y = desired
    untimed = tmp_path / "untimed.csv"
    write_columns(untimed, {"displacement_um": y})
    out, timed_out = tmp_path / "rate.csv", tmp_path / "timed.csv"
    assert run("track", MODEL, str(untimed), "--rate", "2", "-o", str(out),
               "--slew-rate", "20") == 0
    assert run("track", MODEL, str(path), "-o", str(timed_out), "--slew-rate", "20") == 0
    cols, _ = read_columns(out, ["time_s", "voltage_V", "displacement_um"])
    timed, _ = read_columns(timed_out, ["time_s", "voltage_V", "displacement_um"])
    np.testing.assert_allclose(cols["time_s"], np.arange(y.size) / 2.0, rtol=0, atol=0)
    np.testing.assert_allclose(t, np.arange(y.size) * 0.5)   # the same times as the timed file
    for name in ("voltage_V", "displacement_um"):
        np.testing.assert_array_equal(cols[name], timed[name])
