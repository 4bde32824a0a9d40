"""The corpus cases of the record reader: a row longer than the header, a decimal comma,
a repeated column name, a field over 128 KiB, a non-UTF-8 byte named at its line, a bare
carriage return (an old Mac line end); and the fuzz of records, which looks for more."""

import pytest
from corpus_cases import check, params
from harness import GOOD_MODEL
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_fuzz import SETTINGS, VALID_RECORD, _check, mutated


@pytest.mark.parametrize("name, command, expect, says, warns", params("csv", reader=True))
def test_reader_case_on_the_command_line(tmp_path, name, command, expect, says, warns):
    check(tmp_path, name, command, expect, says, warns)


# Fuzz of the records: random bytes and mutated valid records (finds the reader's bugs)
@SETTINGS
@given(content=st.binary(max_size=3000) | mutated(VALID_RECORD))
def test_records(tmp_path, content):
    record = tmp_path / "record.csv"
    record.write_bytes(content)
    out = str(tmp_path / "out.csv")
    _check(tmp_path, ["predict", GOOD_MODEL, str(record), "-o", out], out)
    _check(tmp_path, ["compensate", GOOD_MODEL, str(record), "-o", out], out)
    _check(tmp_path, ["track", GOOD_MODEL, str(record), "-o", out, "--no-noise"], out)


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(content=mutated(VALID_RECORD))
def test_records_fitted(tmp_path, content):
    record = tmp_path / "record.csv"
    record.write_bytes(content)
    out = str(tmp_path / "model.json")
    _check(tmp_path, ["fit", str(record), "-o", out, "--model", "classical",
                      "--thresholds", "0,10,30"], out)
