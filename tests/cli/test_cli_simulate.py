"""pihyst simulate"""

import json

import numpy as np
import pytest

from pihyst.cli import main
from pihyst.io import read_columns
from pihyst.sim import make_plant
from pihyst.sim.signals import random_ramps, triangle


def simulate(tmp_path, *args):
    out = tmp_path / "data.csv"
    status = main(["simulate", *args, "-o", str(out)])
    return status, out


def test_default_records_the_papers_loop_on_the_paper_beam(tmp_path, capsys):
    status, out = simulate(tmp_path)
    assert status == 0
    cols, _ = read_columns(out, ["time_s", "voltage_V", "displacement_um"])
    t, u = triangle()
    np.testing.assert_allclose(cols["time_s"], t, atol=1e-12)
    np.testing.assert_allclose(cols["voltage_V"], u, atol=1e-12)
    expected = make_plant("paper-beam", seed=0).run(u, t)
    np.testing.assert_allclose(cols["displacement_um"], expected, rtol=0, atol=1e-12)
    text = out.read_text()      # plain CSV; what wrote it is in the sidecar
    assert text.startswith("time_s,voltage_V,displacement_um\n")
    side = json.loads((tmp_path / (out.name + ".json")).read_text())
    assert side["comments"][0].startswith("pihyst") and "paper-beam" in side["comments"][1]
    assert "wrote 3001 samples" in capsys.readouterr().out


def test_options_reach_the_plant_and_the_signal(tmp_path):
    status, out = simulate(tmp_path, "--plant", "remanent", "--signal", "random-ramps",
                           "--ramps", "7", "--seed", "3", "--max", "120", "--dt", "0.5",
                           "--no-noise", "--no-creep")
    assert status == 0
    cols, _ = read_columns(out, ["time_s", "voltage_V", "displacement_um"])
    t, u = random_ramps(u_max=120.0, n_ramps=7, dt=0.5, seed=3)
    np.testing.assert_allclose(cols["voltage_V"], u, atol=1e-12)
    y = make_plant("remanent", noise=False, creep=False).run(u, t)
    np.testing.assert_allclose(cols["displacement_um"], y, atol=1e-12)


@pytest.mark.parametrize("signal, extra", [
    ("sine", ["--period", "20", "--cycles", "2"]),
    ("decaying-triangles", ["--triangles", "3", "--ratio", "0.5", "--period", "40"]),
    ("staircase", ["--steps", "3", "--step-time", "2"]),
])
def test_every_signal(tmp_path, signal, extra):
    status, out = simulate(tmp_path, "--signal", signal, "--dt", "0.5", *extra)
    assert status == 0
    cols, _ = read_columns(out, ["voltage_V", "displacement_um"])
    assert cols["voltage_V"].max() == pytest.approx(150.0)
    assert cols["displacement_um"].max() > 30


def test_seed_changes_the_noise_only(tmp_path):
    _, a = simulate(tmp_path, "--seed", "1", "--dt", "1")
    ya = read_columns(a, ["displacement_um"])[0]["displacement_um"]
    _, b = simulate(tmp_path, "--seed", "2", "--dt", "1")
    yb = read_columns(b, ["displacement_um"])[0]["displacement_um"]
    assert 0 < np.abs(ya - yb).max() < 0.1


@pytest.mark.parametrize("args, message", [
    (["--max", "200"], "drive range [0, 150] V"),
    (["--min", "-1"], "drive range"),
    (["--dt", "0"], "argument --dt: must be a positive number"),
    (["--signal", "decaying-triangles", "--ratio", "2"], "--ratio: must be between 0 and 1"),
    (["--min", "100", "--max", "50"], "with --min below --max"),
    (["--signal", "staircase", "--step-time", "0.01", "--dt", "1"],
     "--signal staircase with --steps 10, --step-time 0.01, --dt 1: a step of 0.01 s is "
     "shorter than dt = 1 s"),
])
def test_bad_options_give_one_line_and_no_file(tmp_path, capsys, args, message):
    status, out = simulate(tmp_path, *args)
    err = capsys.readouterr().err
    assert status == 2 and message in err and err.count("\n") == 1
    assert err.startswith("pihyst: error: ")
    assert not out.exists()


def test_unknown_plant_is_an_argparse_error(tmp_path, capsys):
    status, _ = simulate(tmp_path, "--plant", "nope")
    assert status == 2
    assert "invalid choice" in capsys.readouterr().err
