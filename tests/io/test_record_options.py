"""The reading options (units, gain, rate, lag, skip) and reading block by block."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pihyst.exceptions import InvalidArgumentError
from pihyst.io import CSVError, RecordError, open_record, read_record

pytestmark = pytest.mark.usefixtures("engine")


def write(tmp_path, rows, header="t,u,y"):
    path = tmp_path / "r.csv"
    path.write_text(header + "\n" + "".join(",".join(repr(v) for v in r) + "\n" for r in rows))
    return path


def test_lag_pairs_later_displacement_and_locates_it(tmp_path, small_blocks):
    rows = [(0.1 * k, float(k), 100.0 + k) for k in range(20)]
    path = write(tmp_path, rows)
    rec = read_record(path, time="t", voltage="u", displacement="y", lag=2)
    assert len(rec) == 18
    np.testing.assert_array_equal(rec.voltage, np.arange(18))
    np.testing.assert_array_equal(rec.displacement, 102 + np.arange(18))
    np.testing.assert_array_equal(rec.time, [r[0] for r in rows[:18]])
    assert rec.error(0, "displacement", "x").line == 4   # header, then raw rows 0, 1, 2
    assert rec.error(0, "voltage", "x").line == 2


def test_skip_until_with_time_or_rate(tmp_path, small_blocks):
    rows = [(0.5 * k, float(k), float(-k)) for k in range(10)]
    path = write(tmp_path, rows)
    rec = read_record(path, time="t", voltage="u", displacement="y", skip_until=2.0)
    np.testing.assert_array_equal(rec.voltage, np.arange(4, 10))
    assert rec.metadata["skipped_samples"] == 4
    assert rec.error(0, "voltage", "here").line == 6
    rec = read_record(path, time="none", voltage="u", displacement="y", rate=4, lag=1,
                      skip_until=1.0)
    np.testing.assert_array_equal(rec.voltage, np.arange(4, 9))
    np.testing.assert_array_equal(rec.displacement, -np.arange(5, 10))
    np.testing.assert_array_equal(rec.time, np.arange(4, 9) / 4)


def test_units_gain_from_options_and_names(tmp_path):
    path = write(tmp_path, [(0.0, 1.0, 2e-6)], header="time_s,amp_in,pos_m")
    rec = read_record(path, voltage="amp_in", displacement="pos_m", voltage_gain=15)
    assert rec.voltage.tolist() == [15.0] and rec.displacement == pytest.approx([2.0])
    assert rec.metadata["displacement_unit"] == "m"
    rec = read_record(path, voltage=2, displacement=3, displacement_unit="mm")
    assert rec.displacement == pytest.approx([2e-3])


def test_a_sensor_counting_the_other_way_is_negated(tmp_path):
    # a laser sensor measuring the distance to the target reads less as the actuator
    # extends towards it: displacement_gain=-1 (after the unit's factor, in any order)
    path = write(tmp_path, [(0.0, 1.0, 2e-3), (0.1, 2.0, 1e-3)], header="time_s,u,dist_mm")
    reader = open_record(path, voltage="u", displacement="dist_mm", displacement_gain=-1)
    rec = reader.read()
    assert rec.displacement == pytest.approx([-2.0, -1.0])
    assert rec.metadata["displacement_gain"] == -1
    assert "displacement x -1" in reader.describe()
    assert "displacement_gain" not in read_record(path, voltage="u",
                                                  displacement="dist_mm").metadata


@pytest.mark.parametrize("header, factors, note", [
    ("t_ms,u_mV,y", (1e-3, 1e-3), "voltage in mV (column name 'u_mV') -> V, time in ms"),
    ("time [us],U [kV],y", (1e-6, 1e3), "voltage in kV (column name 'U [kV]') -> V"),
    ("Zeit (ns),Spannung (V),y", (1e-9, 1.0), "time in ns (column name 'Zeit (ns)') -> s"),
    ("time_s,voltage_V,y", (1.0, 1.0), None),
    ("times,volts,y", (1.0, 1.0), None),             # no unit in the name
])
def test_time_and_voltage_in_the_unit_their_column_names(tmp_path, small_blocks, header,
                                                         factors, note):
    # a column named time_ms holds milliseconds: read as seconds it made a record 1000
    # times longer (creep time constants, the delay's sample period, --skip-until)
    rows = [(10.0 * k, 2.0 * k, 0.5 * k) for k in range(12)]
    path = write(tmp_path, rows, header=header)
    names = header.split(",")
    reader = open_record(path, time=names[0], voltage=names[1], displacement="y",
                         skip_until=factors[0] * 35.0, voltage_gain=3)
    rec = reader.read()
    np.testing.assert_allclose(rec.time, factors[0] * 10.0 * np.arange(4, 12))
    np.testing.assert_allclose(rec.voltage, 3 * factors[1] * 2.0 * np.arange(4, 12))
    if note is None:
        assert "->" not in reader.describe()
        assert "time_unit" not in rec.metadata and "voltage_unit" not in rec.metadata
    else:
        assert note in reader.describe()


@pytest.mark.parametrize("options,message", [
    ({"lag": -1}, "--lag must be"),
    ({"rate": 0}, "--rate must be positive"),
    ({"rate": 10}, "--rate is for records without a time column"),
    ({"time": "none", "skip_until": 1}, "--skip-until needs a time column"),
    ({"displacement_unit": "inch"}, "--displacement-unit must be"),
    ({"voltage_gain": 0}, "--voltage-gain must not be 0"),
    ({"displacement_gain": 0}, "--displacement-gain must not be 0"),
    ({"displacement": "u"}, "both read from column 2"),
    ({"separator": "|"}, "unknown separator"),
])
def test_bad_options_are_value_errors(tmp_path, options, message):
    path = write(tmp_path, [(0.0, 1.0, 2.0)])
    kwargs = {"time": "t", "voltage": "u", "displacement": "y", **options}
    with pytest.raises(ValueError, match=message):
        read_record(path, **kwargs)


def test_nothing_left_after_skip_or_lag(tmp_path):
    path = write(tmp_path, [(0.0, 1.0, 2.0)])
    with pytest.raises(ValueError, match="no samples left after --lag 1"):
        read_record(path, time="t", voltage="u", displacement="y", lag=1)
    with pytest.raises(CSVError, match=r"r.csv:1:4: column 'y' appears 2 times"):
        path.write_text("t,u,y,y\n0,1,2,3\n")
        read_record(path, voltage="u", displacement="y")


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(n=st.integers(1, 60), lag=st.integers(0, 4), skip=st.none() | st.floats(0, 3),
       block=st.integers(16, 200))
def test_blocks_join_to_the_whole_record(tmp_path_factory, monkeypatch, n, lag, skip, block):
    from pihyst.io import _records, _text_source
    path = tmp_path_factory.mktemp("b") / "r.csv"
    rng = np.random.default_rng(n)
    rows = np.column_stack([np.arange(n) * 0.1, rng.normal(size=n), rng.normal(size=n)])
    path.write_text("t,u,y\n" + "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in rows.tolist()))
    options = dict(time="t", voltage="u", displacement="y", lag=lag, skip_until=skip)
    try:
        whole = read_record(path, **options)
    except RecordError as err:
        assert "no samples left" in str(err)
        return
    monkeypatch.setattr(_text_source, "BLOCK_BYTES", block)
    monkeypatch.setattr(_records, "BLOCK_ROWS", 3)
    with open_record(path, **options) as reader:
        parts = list(reader.chunks())
    assert [p.start for p in parts] == list(np.cumsum([0] + [len(p) for p in parts])[:-1])
    for q in ("voltage", "displacement", "time"):
        np.testing.assert_array_equal(np.concatenate([getattr(p, q) for p in parts]),
                                      getattr(whole, q))


@pytest.mark.parametrize("kind", ["csv", "npy"])
@pytest.mark.parametrize("need,rate,options,message", [
    # nothing to read: a clear error, not a StopIteration inside a generator
    ((), None, {"time": "none"}, r"no column to read: need=\(\)"),
    ((), 10.0, {}, r"no column to read: need=\(\).*; the rate gives the time, but it needs"),
    (("time",), 10.0, {}, r"no column to read: need=\('time',\).*; the rate gives the time"),
    ((), None, {"optional": ()}, r"no column to read: need=\(\): name the quantities"),
])
def test_a_reader_with_no_column_to_read_says_so(tmp_path, kind, need, rate, options,
                                                 message):
    if kind == "csv":
        path = write(tmp_path, [(1.0, 2.0), (3.0, 4.0)], header="u,y")
    else:
        path = tmp_path / "r.npy"
        np.save(path, np.array([[1.0, 2.0], [3.0, 4.0]]))
    with pytest.raises(InvalidArgumentError, match=message):
        open_record(path, need=need, rate=rate, **options)


@pytest.mark.parametrize("need", [("time", "displacement"), ("time", "voltage"),
                                  ("time", "voltage", "displacement")])
def test_a_needed_time_comes_from_the_rate(tmp_path, small_blocks, need):
    path = write(tmp_path, [(float(k), 2.0 * k) for k in range(9)],
                 header="voltage_V,displacement_um")
    with open_record(path, need=need, rate=4.0) as reader:
        rec = reader.read()
        blocks = list(reader.chunks())
    np.testing.assert_array_equal(rec.time, np.arange(9) / 4.0)
    np.testing.assert_array_equal(np.concatenate([b.time for b in blocks]), rec.time)
    assert rec.metadata["rate_hz"] == 4.0
    # a time column and a rate: which is meant? (the column is looked for to refuse both)
    timed = write(tmp_path, [(0.0, 1.0, 2.0)], header="time_s,voltage_V,displacement_um")
    with pytest.raises(ValueError, match="--rate is for records without a time column"):
        open_record(timed, need=need, rate=4.0)
    with open_record(timed, need=need, rate=4.0, time="none") as reader:
        assert reader.read().time.tolist() == [0.0]
    with pytest.raises(ValueError, match=r"needs the time \(or --rate HZ\)"):
        open_record(timed, need=need, time="none")


def test_need_may_name_one_quantity_alone(tmp_path):
    path = write(tmp_path, [(0.0, 1.0), (0.5, 2.0)], header="time_s,voltage_V")
    with open_record(path, need="voltage", optional="time") as reader:
        rec = reader.read()
    assert rec.voltage.tolist() == [1.0, 2.0] and rec.time.tolist() == [0.0, 0.5]
    with pytest.raises(InvalidArgumentError, match=r"unknown quantities \['force'\]"):
        open_record(path, need="force")
