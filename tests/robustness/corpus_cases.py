"""The corpus cases as pytest parameters, split by what they need: quick ones in the
default suite, the ones that run a whole fit marked slow, the CSV reader's own in
test_csv_corpus.py."""

import os

import pytest
from harness import CORPUS, argv_for, corpus_cases, judge, run

# the record reader's own cases (a row longer than the header, a decimal comma, a repeated
# column name, a huge field, a non-UTF-8 byte, a bare carriage return), kept apart in
# test_csv_corpus.py with the fuzz of records
READER_FILES = {
    "csv/decimal-comma.csv", "csv/decimal-comma-cell-voltage.csv",
    "csv/decimal-comma-cell-displacement.csv", "csv/long-row.csv",
    "csv/duplicate-column.csv", "csv/huge-field.csv", "csv/non-utf8-value.csv",
    "csv/bare-cr.csv"}

# a whole fit that succeeds takes seconds; one of each kind stays in the default suite
QUICK_FITS = {"csv/pure-noise.csv"}


def params(kind, reader):
    out = []
    for name, k, command, expect, says, warns in corpus_cases():
        if k != kind or (name in READER_FILES) != reader:
            continue
        slow = command == "fit" and (expect == 0 or name in READER_FILES) \
            and name not in QUICK_FITS
        marks = [pytest.mark.slow] if slow else []
        out.append(pytest.param(name, command, expect, says, warns, marks=marks,
                                id=f"{command}-{name}"))
    return out


def check(tmp_path, name, command, expect, says, warns):
    out = str(tmp_path / ("model.json" if command == "fit" else "out.csv"))
    outcome = run(argv_for(command, name.split("/")[0], os.path.join(CORPUS, name), out))
    problems = judge(outcome, expect, out, says, warns)
    assert not problems, f"pihyst {' '.join(outcome.argv)}: {problems}"
    return outcome
