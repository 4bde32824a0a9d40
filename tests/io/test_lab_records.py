"""Records as lab software writes them, each read exactly (values and times checked
against what was written): LabVIEW .lvm by its published layout, TDMS by npTDMS's own
writer, .xlsx by openpyxl's, PI GCSArray data-recorder text as PIPython's savegcsarray
writes it, CSV with a units row, a time column named in ms; and what goes wrong said in
one line naming the file and where."""

import builtins
import warnings

import numpy as np
import pytest

from pihyst.cli import main
from pihyst.exceptions import PihystWarning
from pihyst.io import CSVError, RecordError, open_record, read_record

N = 40
T = np.arange(N) * 0.001
U = 75 + 75 * np.sin(2 * np.pi * 20 * T)
Y = 0.3 * U + 1.25


def lvm_header(separator="Tab", decimal=".", x_columns="One"):
    s = "\t" if separator == "Tab" else ","
    rows = [("LabVIEW Measurement", ""), ("Writer_Version", "2"), ("Reader_Version", "2"),
            ("Separator", separator), ("Decimal_Separator", decimal),
            ("Multi_Headings", "No"), ("X_Columns", x_columns), ("Time_Pref", "Relative"),
            ("Operator", "lab"), ("Date", "2024/05/01"), ("Time", "12:00:00.000")]
    return "".join(f"{k}{s}{v}\n" for k, v in rows) + f"***End_of_Header***{s}\n{s}\n"


def lvm_segment(rows, x0, dx=0.001, separator="\t", decimal=".", x_columns="One",
                names=("Voltage", "Displacement")):
    s = separator
    head = [("Channels", ["2", "2"][:1] * 1), ("Samples", [str(len(rows))] * 2),
            ("Date", ["2024/05/01"] * 2), ("Time", ["12:00:00"] * 2),
            ("X_Dimension", ["Time"] * 2), ("X0", [repr(x0)] * 2),
            ("Delta_X", [repr(dx)] * 2)]
    text = "".join(k + s + s.join(v) + s + "\n" for k, v in head)
    text += "***End_of_Header***" + s + "\n"
    cols = {"One": ["X_Value", *names], "No": list(names),
            "Multi": ["X_Value", names[0], "X_Value", names[1]]}[x_columns]
    text += s.join(cols + ["Comment"]) + "\n"
    for t, u, y in rows:
        values = {"One": [t, u, y], "No": [u, y], "Multi": [t, u, t, y]}[x_columns]
        line = s.join(repr(float(v)) for v in values)
        text += (line.replace(".", ",") if decimal == "," else line) + "\n"
    return text


def write_lvm(path, segments=2, **kw):
    sep = {"Tab": "\t", "Comma": ","}[kw.pop("separator", "Tab")]
    decimal = kw.pop("decimal", ".")
    x_columns = kw.pop("x_columns", "One")
    text = lvm_header("Tab" if sep == "\t" else "Comma", decimal, x_columns)
    bounds = np.linspace(0, N, segments + 1).astype(int)
    for a, b in zip(bounds[:-1], bounds[1:]):
        rows = list(zip(T[a:b], U[a:b], Y[a:b]))
        text += lvm_segment(rows, float(T[a]), separator=sep, decimal=decimal,
                            x_columns=x_columns)
    path.write_text(text)
    return path


def check(rec, time=T):
    np.testing.assert_array_equal(rec.voltage, U)
    np.testing.assert_array_equal(rec.displacement, Y)
    if time is not None:
        np.testing.assert_allclose(rec.time, time, rtol=0, atol=1e-15)


# ------------------------------------------------------------------ LabVIEW .lvm
@pytest.mark.parametrize("segments", [1, 3])
@pytest.mark.parametrize("x_columns", ["One", "No", "Multi"])
def test_lvm_segments_and_x_columns(tmp_path, segments, x_columns):
    path = write_lvm(tmp_path / "run.lvm", segments=segments, x_columns=x_columns)
    with open_record(path, need=("voltage", "displacement")) as reader:
        rec = reader.read()
        line = reader.describe()
    check(rec)
    assert f"LabVIEW Measurement File, {segments} segment(s)" in line
    assert "voltage column" in line and "'Voltage' (guessed from its name)" in line
    assert ("X0 and Delta_X" if x_columns == "No" else "the file's X column") in line


def test_lvm_decimal_comma_and_comma_separator(tmp_path):
    check(read_record(write_lvm(tmp_path / "a.lvm", decimal=","), need=("voltage",
                                                                            "displacement")))
    check(read_record(write_lvm(tmp_path / "b.lvm", separator="Comma"),
                      need=("voltage", "displacement")))


def test_lvm_channels_by_name_or_number(tmp_path):
    path = write_lvm(tmp_path / "run.lvm")
    rec = read_record(path, voltage="Voltage", displacement=3, time="X_Value")
    check(rec)


def test_lvm_segment_times_that_restart_continue(tmp_path):
    text = lvm_header()
    text += lvm_segment(list(zip(T[:20], U[:20], Y[:20])), 0.0, x_columns="No")
    text += lvm_segment(list(zip(T[:20], U[20:], Y[20:])), 0.0, x_columns="No")
    path = tmp_path / "r.lvm"
    path.write_text(text)
    with open_record(path) as reader:
        rec = reader.read()
        assert "segment 2's time starts again" in reader.describe()
    check(rec)


def test_lvm_faults_name_line_and_column(tmp_path):
    path = write_lvm(tmp_path / "run.lvm", segments=1)
    lines = path.read_text().splitlines()
    k = next(i for i, s in enumerate(lines) if s.startswith("X_Value")) + 3
    lines[k] = lines[k].replace("\t", "\tabc", 1).split("\tabc")[0] + "\tabc\t1.0"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(CSVError, match=rf"run.lvm:{k + 1}:2: column 'Voltage': 'abc' is not"):
        read_record(path)
    path.write_text("Channels\t2\n")
    with pytest.raises(CSVError, match="not a LabVIEW Measurement File"):
        read_record(path)


# ------------------------------------------------------------------ TDMS (npTDMS)
def write_tdms(path, groups=("Loop",), increment=0.001, offset=0.0):
    nptdms = pytest.importorskip("nptdms")
    with nptdms.TdmsWriter(str(path)) as w:
        for half in (slice(0, N // 2), slice(N // 2, N)):
            objects = [nptdms.RootObject()] if half.start == 0 else []
            for g in groups:
                props = ({"wf_increment": increment, "wf_start_offset": offset,
                          "unit_string": "V"} if half.start == 0 else {})
                objects += [nptdms.GroupObject(g),
                            nptdms.ChannelObject(g, "Voltage", U[half], properties=props),
                            nptdms.ChannelObject(g, "Position", Y[half],
                                                 properties={"unit_string": "um"}
                                                 if half.start == 0 else {})]
            w.write_segment(objects)
    return path


def test_tdms_written_by_nptdms(tmp_path):
    path = write_tdms(tmp_path / "run.tdms", offset=0.5)
    with open_record(path) as reader:
        rec = reader.read()
        line = reader.describe()
    check(rec, time=0.5 + T)
    assert "wf_start_offset and wf_increment" in line and "'Position'" in line


def test_tdms_group_and_channel_names(tmp_path):
    path = write_tdms(tmp_path / "run.tdms", groups=("A", "B"))
    rec = read_record(path, voltage="B/Voltage", displacement="A/Position")
    check(rec)
    with pytest.raises(RecordError, match="several columns may hold the voltage"):
        read_record(path)


def test_tdms_broken_file_is_one_line(tmp_path):
    path = write_tdms(tmp_path / "run.tdms")
    data = path.read_bytes()
    (tmp_path / "cut.tdms").write_bytes(data[:len(data) // 3])
    with pytest.raises(RecordError, match=r"cut.tdms: "):
        read_record(tmp_path / "cut.tdms")


# ------------------------------------------------------------------ Excel (openpyxl)
def write_xlsx(path, units=True, sheets=("Notes", "Loop")):
    openpyxl = pytest.importorskip("openpyxl")
    book = openpyxl.Workbook()
    book.active.title = sheets[0]
    book.active.append(["nothing here"])
    ws = book.create_sheet(sheets[1])
    ws.append(["Time", "Voltage", "Displacement"])
    if units:
        ws.append(["s", "V", "µm"])
    for row in zip(T.tolist(), U.tolist(), Y.tolist()):
        ws.append(list(row))
    book.save(path)
    return path


def test_xlsx_written_by_openpyxl_by_sheet_name_or_number(tmp_path):
    openpyxl = pytest.importorskip("openpyxl")
    path = write_xlsx(tmp_path / "run.xlsx")
    # the workbook holds what openpyxl wrote (16 significant digits, Excel's precision)
    stored = np.array(list(openpyxl.load_workbook(path)["Loop"].iter_rows(
        min_row=3, values_only=True)), dtype=float)
    np.testing.assert_allclose(stored, np.c_[T, U, Y], rtol=1e-15, atol=0)
    for sheet in ("Loop", 2, "2"):
        with open_record(path, sheet=sheet) as reader:
            rec = reader.read()
            np.testing.assert_array_equal(np.c_[rec.time, rec.voltage, rec.displacement],
                                          stored)
            assert "sheet 'Loop'" in reader.describe()
            assert "its unit 'V' in the file" in reader.describe()
    with pytest.raises(RecordError, match=r"--sheet 3: no such sheet \(sheets: 1 'Notes', "
                                          r"2 'Loop'\)"):
        read_record(path, sheet=3)


def test_xlsx_bad_cell_names_row_and_column(tmp_path):
    openpyxl = pytest.importorskip("openpyxl")
    path = write_xlsx(tmp_path / "run.xlsx", units=False)
    book = openpyxl.load_workbook(path)
    book["Loop"]["B7"] = "oops"
    book.save(path)
    with pytest.raises(CSVError, match=r"run.xlsx:7:2: sheet 'Loop' cell B7: column "
                                       r"'Voltage': 'oops' is not a number"):
        read_record(path, sheet="Loop", voltage="Voltage", displacement="Displacement")


@pytest.mark.parametrize("suffix,module,extra", [(".xlsx", "openpyxl", "xlsx"),
                                                 (".tdms", "nptdms", "tdms")])
def test_missing_extra_is_one_line_naming_it(tmp_path, monkeypatch, suffix, module, extra):
    path = tmp_path / f"r{suffix}"
    path.write_bytes(b"\0" * 10)
    real = builtins.__import__

    def no(name, *args, **kwargs):
        if name.split(".")[0] == module:
            raise ImportError(name)
        return real(name, *args, **kwargs)
    monkeypatch.setattr(builtins, "__import__", no)
    with pytest.raises(RecordError) as err:
        read_record(path)
    assert str(err.value) == (f"{path}: reading this file needs {module}: "
                              f"pip install 'pihyst[{extra}]'")


# ------------------------------------------------------------------ PI GCSArray
def savegcsarray(path, header, data, sep=32):
    """The file PIPython's pitools.savegcsarray writes (its layout, byte for byte)."""
    out = "".join(f"# {k} = {v} \n" for k, v in header.items())
    out += "# \n# END_HEADER \n"
    for values in zip(*data):
        out += chr(sep).join(f"{v:.6f}" for v in values) + " \n"
    out = out[:-2] + "\n"
    path.write_text(out, encoding="utf-8")
    return path


@pytest.mark.parametrize("sep", [32, 9])
def test_gcsarray_names_and_sample_time(tmp_path, sep):
    header = {"VERSION": 1, "TYPE": 1, "SEPARATOR": sep, "DIM": 2, "SAMPLE_TIME": 5e-05,
              "NDATA": N, "NAME0": "Voltage of Piezo 1", "NAME1": "Actual Position of Axis 1"}
    path = savegcsarray(tmp_path / "drec.dat", header, [U, Y], sep)
    with open_record(path) as reader:
        rec = reader.read()
        line = reader.describe()
    np.testing.assert_array_equal(rec.voltage, [float(f"{v:.6f}") for v in U])
    np.testing.assert_array_equal(rec.displacement, [float(f"{v:.6f}") for v in Y])
    np.testing.assert_array_equal(rec.time, np.arange(N) / 20000.0)
    assert "PI GCSArray" in line and "SAMPLE_TIME = 5e-05 s in the header" in line
    assert "'Voltage of Piezo 1' (guessed from its NAME in the header)" in line
    rec = read_record(path, voltage="Voltage of Piezo 1", displacement=2, rate=1000)
    np.testing.assert_array_equal(rec.time, np.arange(N) / 1000.0)


def test_gcsarray_two_positions_is_asked_which(tmp_path):
    header = {"SEPARATOR": 32, "DIM": 3, "SAMPLE_TIME": 1e-4, "NAME0": "Commanded Position",
              "NAME1": "Target Position", "NAME2": "Voltage"}
    path = savegcsarray(tmp_path / "d.txt", header, [Y, Y, U])
    with pytest.raises(RecordError, match="several columns may hold the displacement"):
        read_record(path)


# ------------------------------------------------------------------ CSV as labs write it
def test_units_row_taken_and_converted(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("t,drive,pos\nms,V,nm\n" + "".join(
        f"{a!r},{b!r},{c!r}\n" for a, b, c in zip((T * 1e3).tolist(), U.tolist(),
                                                (Y * 1e3).tolist())))
    with open_record(path) as reader:
        rec = reader.read()
        line = reader.describe()
    np.testing.assert_array_equal(rec.voltage, U)
    np.testing.assert_allclose(rec.displacement, Y, rtol=1e-15)
    np.testing.assert_allclose(rec.time, T, rtol=1e-15, atol=0)
    assert "units on line 2" in line and "its unit 'ms' in the file" in line
    assert "time in ms (the file's unit 'ms') -> s" in line


@pytest.mark.parametrize("name,factor", [("time_ms", 1e-3), ("t [us]", 1e-6),
                                         ("time_min", 60.0), ("Zeit (s)", 1.0)])
def test_time_column_in_other_units_found_by_its_name(tmp_path, name, factor):
    path = tmp_path / "r.csv"
    path.write_text(f"{name},voltage_V,displacement_um\n" + "".join(
        f"{a!r},{b!r},{c!r}\n" for a, b, c in zip((T / factor).tolist(), U.tolist(),
                                                Y.tolist())))
    with open_record(path) as reader:
        rec = reader.read()
        assert f"{name!r} (its name)" in reader.describe()
    np.testing.assert_allclose(rec.time, T, rtol=1e-12, atol=1e-18)


def test_time_like_column_not_used_is_a_warning(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("time_s,voltage_V,displacement_um,timestamp\n0,1,2,5\n1,2,3,6\n")
    with pytest.warns(PihystWarning, match=r"column 'timestamp' looks like a time but is "
                                           r"not used \(the time is column 1 'time_s'\)"):
        read_record(path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_record(path, need=("voltage", "displacement"), optional=())


def test_units_row_with_a_unit_that_is_not_the_quantitys(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("time_s,voltage_V,pos\ns,V,mA\n0,1,2\n")
    with pytest.raises(RecordError, match=r"unit 'mA' \(from the file\) is not a length "):
        read_record(path, displacement="pos")


# ------------------------------------------------------------------ one command each
def test_each_format_fits_with_one_command(tmp_path, capsys):
    files = [write_lvm(tmp_path / "run.lvm"), write_xlsx(tmp_path / "run.xlsx"),
             write_tdms(tmp_path / "run.tdms")]
    for path in files:
        model = tmp_path / f"{path.suffix[1:]}.json"
        options = ["--sheet", "Loop"] if path.suffix == ".xlsx" else []
        assert main(["fit", str(path), *options, "--model", "classical", "--holdout",
                     "none", "--no-creep", "-o", str(model)]) == 0
        out = capsys.readouterr().out
        assert f"read {path}: {N} samples" in out and model.exists()


# ------------------------------------------------------------------ plain files out
def test_what_pihyst_writes_opens_in_numpy_and_pandas_defaults(tmp_path, capsys):
    model, out = "examples/paper_table1_classical.json", tmp_path / "out.csv"
    volts = tmp_path / "v.csv"
    volts.write_text("time_s,voltage_V\n" + "".join(
        f"{a!r},{b!r}\n" for a, b in zip(T.tolist(), U.tolist())))
    assert main(["predict", model, str(volts), "-o", str(out)]) == 0
    text = out.read_text()
    assert "#" not in text
    named = np.genfromtxt(out, names=True, delimiter=",")
    assert named.dtype.names == ("time_s", "voltage_V", "displacement_um")
    np.testing.assert_array_equal(named["voltage_V"], U)
    plain = np.loadtxt(out, skiprows=1, delimiter=",")
    np.testing.assert_array_equal(plain[:, 1], U)
    pandas = pytest.importorskip("pandas")
    frame = pandas.read_csv(out)
    assert list(frame.columns) == ["time_s", "voltage_V", "displacement_um"]
    np.testing.assert_array_equal(frame["displacement_um"].to_numpy(), plain[:, 2])
    # the metadata: beside it, and read back with the record
    import json
    side = json.loads((tmp_path / "out.csv.json").read_text())
    assert side["file"] == "out.csv" and side["rows"] == N and side["comments"]
    with open_record(out, need=("voltage", "displacement")) as reader:
        rec = reader.read()
        assert "metadata from out.csv.json" in reader.describe()
    assert rec.metadata["sidecar"]["comments"] == side["comments"]


def test_an_lvm_with_bytes_undefined_in_cp1252_is_one_line_not_a_crash(tmp_path):
    """Found by the reader fuzz: 0x8d is neither UTF-8 nor defined in cp1252."""
    path = tmp_path / "bad.lvm"
    path.write_bytes(b"\x8dLabVIEW Measurement\t\n")
    with pytest.raises((RecordError, CSVError)) as info:
        read_record(path)
    assert "\n" not in str(info.value)
