"""pihyst predict: docs/interfaces.md formats and one-line errors with exit status 2."""

import subprocess
import sys

import numpy as np
import pytest

import pihyst
from pihyst.cli import main
from pihyst.io import read_columns

MODEL = "examples/paper_table1_classical.json"


def run(*argv):
    return main(list(argv))


def test_predict_triangle_reproduces_table1(tmp_path, capsys):
    out = tmp_path / "out.csv"
    assert run("predict", MODEL, "examples/triangle_0_150V.csv", "-o", str(out)) == 0
    cols, _ = read_columns(out, ["time_s", "voltage_V", "displacement_um"])
    assert cols["displacement_um"][150] == pytest.approx(38.76, abs=1e-12)
    assert cols["displacement_um"][-1] == pytest.approx(3.09, abs=1e-12)
    assert cols["time_s"][-1] == 300.0
    assert "wrote 301 samples" in capsys.readouterr().out


def test_columns_by_name_comments_and_extra_columns(tmp_path):
    src = tmp_path / "in.csv"
    src.write_text("# a comment\nnote,voltage_V,time_s\nx,0,0\n# mid comment\ny,150,1\nz,0,2\n")
    out = tmp_path / "out.csv"
    assert run("predict", MODEL, str(src), "-o", str(out)) == 0
    cols, _ = read_columns(out, ["time_s", "displacement_um"])
    np.testing.assert_allclose(cols["displacement_um"], [0, 38.76, 3.09], atol=1e-12)
    np.testing.assert_array_equal(cols["time_s"], [0, 1, 2])


def test_without_time_column_uses_sample_index(tmp_path):
    src = tmp_path / "in.csv"
    src.write_text("voltage_V\n0\n75\n")
    out = tmp_path / "out.csv"
    assert run("predict", MODEL, str(src), "-o", str(out)) == 0
    cols, _ = read_columns(out, ["time_s"])
    np.testing.assert_array_equal(cols["time_s"], [0, 1])


@pytest.mark.parametrize("content,where,what", [
    ("time_s,voltage_V\n0,0\n1,abc\n", ":3:2:", "'abc' is not a number"),
    ("time_s,voltage_V\n0,0\n1,nan\n", ":3:2:", "not a finite number"),
    ("time_s,voltage_V\n0,0\n1,\n", ":3:2:", "missing value"),
    ("time_s,volts\n0,0\n", ":1:", "missing column 'voltage_V'"),
    ("", ":1:", "empty file"),
    ("# only a comment\n", ":1:", "empty file"),
    ("time_s,voltage_V\n", ":1:", "no data rows"),
    ("time_s,voltage_V\n0,0\n1,200\n", ":3:2:", "outside the model's input range"),
])
def test_bad_input_one_line_error_exit_2_no_output(tmp_path, capsys, content, where, what):
    src = tmp_path / "bad.csv"
    src.write_text(content)
    out = tmp_path / "out.csv"
    assert run("predict", MODEL, str(src), "-o", str(out)) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("pihyst: error: ")
    assert f"bad.csv{where}" in err and what in err
    assert not out.exists()
    assert not list(tmp_path.glob(".pihyst-*"))


def test_bad_model_file(tmp_path, capsys):
    model = tmp_path / "m.json"
    model.write_text('{"family": "classical", "thresholds": [0, -1], "weights": [1, 1]}')
    out = tmp_path / "out.csv"
    assert run("predict", str(model), "examples/triangle_0_150V.csv", "-o", str(out)) == 2
    assert "m.json: " in capsys.readouterr().err
    assert not out.exists()


def test_console_script_help_and_exit_status(tmp_path):
    exe = [sys.executable, "-m", "pihyst"]
    help_text = subprocess.run([*exe, "predict", "--help"], capture_output=True, text=True,
                               check=True).stdout
    assert "voltage_V" in help_text and "example:" in help_text
    bad = subprocess.run([*exe, "predict", MODEL, str(tmp_path / "nope.csv"), "-o",
                          str(tmp_path / "o.csv")], capture_output=True, text=True)
    assert bad.returncode == 2 and "cannot read file" in bad.stderr


def test_version():
    assert pihyst.__version__ == "0.1.0"


def test_missing_output_folder_is_a_one_line_error(tmp_path, capsys):
    out = tmp_path / "no" / "such" / "out.csv"
    assert run("predict", MODEL, "examples/triangle_0_150V.csv", "-o", str(out)) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "No such file or directory" in err


def test_excel_style_files(tmp_path, capsys):
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbftime_s,voltage_V\r\n0,0\r\n7,150\r\n")
    out = tmp_path / "out.csv"
    assert run("predict", MODEL, str(bom), "-o", str(out)) == 0
    cols, _ = read_columns(out, ["time_s", "displacement_um"])
    np.testing.assert_array_equal(cols["time_s"], [0, 7])  # BOM not part of "time_s"
    semi = tmp_path / "semi.csv"  # Excel in a decimal-comma locale
    semi.write_text("time_s;voltage_V\n0;0\n0,5;150\n")
    assert run("predict", MODEL, str(semi), "-o", str(out)) == 0
    cols, _ = read_columns(out, ["time_s", "displacement_um"])
    np.testing.assert_array_equal(cols["time_s"], [0, 0.5])
