"""Delimited text records: the layouts read as they come, every misreading class refused
at its exact line and column, both vectorised engines agreeing with the careful reader."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pihyst.io import CSVError, read_columns, read_record
from pihyst.io._numbers import parse_number
from pihyst.io._text_check import check_block
from pihyst.io._text_engines import read_block
from pihyst.io._text_format import Dialect

pytestmark = pytest.mark.usefixtures("engine")


def write(tmp_path, content, name="r.csv"):
    path = tmp_path / name
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    return path


def read(path, **options):
    options.setdefault("need", ("voltage", "displacement"))
    return read_record(path, **options)


@pytest.mark.parametrize("content,options", [
    ("time_s,voltage_V,displacement_um\n0,1.5,2\n1,2.5,3\n", {}),
    ("time_s;voltage_V;displacement_um\n0;1,5;2\n1;2,5;3\n", {}),
    ("time_s\tvoltage_V\tdisplacement_um\n0\t1.5\t2\n1\t2.5\t3\n", {}),
    ("  time_s   voltage_V displacement_um\n 0  1.5   2\n1 2.5 3  \n", {}),
    ("0\t1,5\t2\n1\t2,5\t3\n", {"time": 1, "voltage": 2, "displacement": 3}),
    ("# made by hand\n\n0 1.5 2\n# between\n1 2.5 3\n", {"time": 1, "voltage": 2,
                                                       "displacement": 3}),
    ('"time_s","voltage_V","displacement_um"\n"0","1.5","2"\n1,2.5,3\n', {}),
    ("t,u,y\r0,1.5,2\r1,2.5,3\r", {"time": "t", "voltage": "u", "displacement": "y"}),
    ("t,u,y\r\n0,1.5,2\r\n1,2.5,3", {"time": "t", "voltage": "u", "displacement": "y"}),
    (b"\xef\xbb\xbftime_s,voltage_V,displacement_um\n0,1.5,2\n1,2.5,3\n", {}),
    ("time_s,voltage_V,displacement_um,note\n0,1.5,2,ok\n1,2.5,3,\n", {}),
    (",0,2,1.5\n,1,3,2.5\n", {"time": 2, "voltage": 4, "displacement": 3}),
])
def test_layouts_read_as_they_come(tmp_path, content, options, small_blocks):
    rec = read(write(tmp_path, content), **options)
    np.testing.assert_array_equal(rec.time, [0, 1])
    np.testing.assert_array_equal(rec.voltage, [1.5, 2.5])
    np.testing.assert_array_equal(rec.displacement, [2, 3])


def test_header_in_latin1_with_a_unit(tmp_path):
    path = write(tmp_path, "Zeit [s];Spannung [V];Weg [µm]\n0;1,5;2\n".encode("cp1252"))
    rec = read(path, voltage="Spannung [V]", displacement="Weg [µm]", time="Zeit [s]")
    assert rec.voltage.tolist() == [1.5] and rec.metadata["displacement_unit"] == "um"


@pytest.mark.parametrize("content,options,where,what", [
    # a decimal comma in a comma-separated file: more fields than the header
    ("time_s,voltage_V,displacement_um\n0,1,5,2\n", {}, ":2:4:", "4 fields where the header "
     "has 3; a decimal comma"),
    # Python's digit separators and other Python-only syntax
    ("voltage_V,displacement_um\n0,1\n1_5,2\n", {}, ":3:1:", "'1_5' is not a number"),
    ("voltage_V,displacement_um\n0,1\n0x10,2\n", {}, ":3:1:", "'0x10' is not a number"),
    ("voltage_V,displacement_um\n0,1\n1,Infinity\n", {}, ":3:2:", "not a finite number"),
    ("voltage_V,displacement_um\n0,1\n1,nan\n", {}, ":3:2:", "not a finite number"),
    ("voltage_V,displacement_um\n0,1\n1,\n", {}, ":3:2:", "missing value for column "
     "'displacement_um'"),
    ("voltage_V,displacement_um\n0,1\n1\n", {}, ":3:2:", "1 fields where the header has 2"),
    # a duplicated column name
    ("voltage_V,displacement_um,voltage_V\n0,1,2\n", {}, ":1:3:", "'voltage_V' appears 2 "
     "times"),
    # a quoted field going over two lines: the line where it starts
    ('voltage_V,displacement_um\n0,1\n1,"2\n3"\n', {}, ":3:2:", "unterminated quote"),
    ('note,voltage_V,displacement_um\n"a\nb",1,2\n', {}, ":2:1:", "unterminated quote"),
    # old Mac line ends: the line numbers still count
    ("voltage_V,displacement_um\r0,1\r1,x\r", {}, ":3:2:", "'x' is not a number"),
    ("voltage_V,displacement_um\r\n0,1\r\n\r\n1,x\r\n", {}, ":4:2:", "'x' is not a number"),
    # both decimal marks in one file: the comma is the odd one
    ("voltage_V;displacement_um\n0,5;1\n1.5;2\n", {}, ":2:1:", "decimal comma"),
    ("time_s,volts\n0,0\n", {}, ":1:", "missing column 'voltage_V' in header (time_s, volts)"),
    ("0,1\n", {}, ":1:", "no header line: name the columns by position"),
    ("voltage_V,displacement_um\n", {}, ":1:", "no data rows after the header"),
    ("", {}, ":1:", "empty file"),
    ("# only comments\n\n", {}, ":1:", "empty file"),
    ("a,b\n0,1\n", {"voltage": 3, "displacement": 1}, ":1:", "--voltage 3: the file has "
     "columns 1 to 2"),
    (b"voltage_V,displacement_um\n0,1\n\xff,2\n", {}, ":3:", "not UTF-8"),
])
def test_misreadings_refused_at_line_and_column(tmp_path, content, options, where, what):
    path = write(tmp_path, content)
    with pytest.raises(CSVError) as err:
        read(path, **options)
    message = str(err.value)
    assert message.startswith(f"{path}{where}") and what in message, message
    assert "\n" not in message


@pytest.mark.parametrize("header, quantity, hint", [
    ("Time (s),Voltage (V),Displacement (um)", "voltage",
     "(is it 'Voltage (V)'? --voltage 'Voltage (V)')"),
    ("time,voltage_V,Position [µm]", "displacement",
     "(is it 'Position [µm]'? --displacement 'Position [µm]')"),
    ("t,V,x", "voltage", "(is it 'V'? --voltage V)"),
])
def test_a_missing_column_names_the_one_that_looks_like_it(tmp_path, header, quantity,
                                                           hint):
    path = write(tmp_path, f"{header}\n0,0,0\n1,1,1\n")
    with pytest.raises(CSVError) as err:
        read(path)
    assert "missing column" in str(err.value) and str(err.value).endswith(hint), err.value


@pytest.mark.parametrize("header", ["a,b,c", "volts,voltage,x", "u,v,y"])
def test_no_hint_where_no_column_or_several_look_like_it(tmp_path, header):
    path = write(tmp_path, f"{header}\n0,0,0\n1,1,1\n")
    with pytest.raises(CSVError) as err:
        read(path)
    assert "missing column 'voltage_V'" in str(err.value) and "is it" not in str(err.value)


def test_a_field_longer_than_the_csv_modules_limit(tmp_path):
    long = "0." + "1" * 200_000
    path = write(tmp_path, f"voltage_V,displacement_um\n0,1\n{long},2\n2,3\n")
    rec = read(path)
    assert rec.voltage[1] == float(long)
    path = write(tmp_path, f"voltage_V,displacement_um,note\n0,1,{'x' * 200_000}\n1,x,a\n")
    with pytest.raises(CSVError, match=r":3:2: column 'displacement_um': 'x' is not"):
        read(path)


def test_errors_deep_in_a_file_name_the_right_line(tmp_path, small_blocks):
    rows = "".join(f"{i},{i}\n" if i % 7 else f"# note {i}\n" for i in range(500))
    path = write(tmp_path, "# head\nvoltage_V,displacement_um\n" + rows + "1,1e999\n")
    with pytest.raises(CSVError, match=r"r.csv:503:2: .*too large"):
        read(path)


def test_sample_locations_for_later_errors(tmp_path, small_blocks):
    rows = "".join(f"{i},{i}\n" if i % 5 else f"\n# c\n{i},{i}\n" for i in range(50))
    path = write(tmp_path, "voltage_V,displacement_um\n" + rows)
    rec = read(path)
    lines = (tmp_path / "r.csv").read_text().splitlines()
    for k in (0, 1, 5, 49):
        err = rec.error(k, "voltage", "here")
        assert lines[err.line - 1] == f"{k},{k}" and err.column == 1


def test_read_columns_keeps_its_interface(tmp_path):
    path = write(tmp_path, "# c\ntime_s,voltage_V\n0,1\n\n2,3\n")
    cols, lines = read_columns(path, ["voltage_V"], optional=["time_s", "other"])
    assert cols["voltage_V"].tolist() == [1, 3] and lines.tolist() == [3, 5]
    assert set(cols) == {"voltage_V", "time_s"}


# ------------------------------------------------------------------ properties
values = st.floats(allow_nan=False, allow_infinity=False, width=64)


@settings(max_examples=60, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.lists(st.tuples(values, values), min_size=1, max_size=30),
       sep=st.sampled_from([",", ";", "\t", " ", "  "]), header=st.booleans(),
       newline=st.sampled_from(["\n", "\r\n", "\r"]), comma=st.booleans(),
       comment=st.booleans())
def test_any_layout_reads_back_exactly(tmp_path_factory, data, sep, header, newline, comma,
                                       comment):
    comma = comma and sep != ","
    lines = (["# written by a test"] if comment else []) + \
        (["voltage_V" + sep + "displacement_um"] if header else [])
    for u, y in data:
        a, b = repr(u), repr(y)
        if comma:
            a, b = a.replace(".", ","), b.replace(".", ",")
        lines.append(a + sep + b)
    path = tmp_path_factory.mktemp("p") / "r.txt"
    path.write_bytes(newline.join(lines).encode())
    options = {} if header else {"voltage": 1, "displacement": 2}
    if comma and all("," not in line for line in lines):
        comma = False
    rec = read(path, decimal_comma=True if comma else None, **options)
    np.testing.assert_array_equal(rec.voltage, [u for u, _ in data])
    np.testing.assert_array_equal(rec.displacement, [y for _, y in data])


FIELD = st.text(alphabet="0123456789.,eE+-_xnaifINFAT \t\"", max_size=8)


@settings(max_examples=300)
@given(st.lists(st.tuples(FIELD, FIELD), min_size=1, max_size=4),
       st.sampled_from([(",", "."), (";", ","), (";", "."), ("\t", ","), (None, ".")]))
def test_engines_accept_nothing_the_careful_reader_refuses(rows, layout):
    sep, decimal = layout
    joiner = " " if sep is None else sep
    block = "".join(a + joiner + b + "\n" for a, b in rows).encode()
    dialect = Dialect(sep, decimal, ("u", "y"), 1, 2, 0, 2, 1)
    for engine in ("numpy", "pyarrow"):
        if engine == "pyarrow":
            pytest.importorskip("pyarrow")
        fast = read_block(block, dialect, [0, 1], engine=engine)
        if fast is None:
            continue
        careful = check_block("t", block, 2, dialect, [0, 1], ["u", "y"])
        np.testing.assert_array_equal(fast, careful)
        plain = all(joiner.strip() not in f and '"' not in f and (sep or not f.split(" ")[1:])
                    for row in rows for f in row) if sep else False
        if plain:   # fields that are not split or unquoted: each is a number as written
            for a, b in rows:
                assert np.isfinite(parse_number(a, decimal))
                assert np.isfinite(parse_number(b, decimal))
