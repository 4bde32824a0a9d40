"""A line of 2 MB with 10^6 fields (the earlier corpus's c06) is refused fast by every
command that reads a record: one line naming the file and the line, exit status 2. (The
sniffer scanned a line longer than its head once per byte: minutes.) Also when the long
line comes first, before any header or data."""

import time

import pytest
from harness import GOOD_MODEL, judge, run

FIELDS = 10 ** 6
ROWS = [f"{i},{i % 150},{i % 150 * 0.3}" for i in range(50)]


def _write(path, at):
    rows = ["time_s,voltage_V,displacement_um", *ROWS]
    rows.insert(at, ",".join(["1"] * FIELDS))
    path.write_text("\n".join(rows) + "\n")
    return at + 1


@pytest.mark.parametrize("at", [0, 1, 10])
@pytest.mark.parametrize("command", ["predict", "fit", "compensate", "track"])
def test_a_line_with_a_million_fields_is_refused_fast(tmp_path, command, at):
    record = tmp_path / "c06.csv"
    line = _write(record, at)
    out = str(tmp_path / "out.csv")
    argv = ["fit", record, "-o", out] if command == "fit" else \
        [command, GOOD_MODEL, record, "-o", out]
    start = time.perf_counter()
    outcome = run(argv)
    took = time.perf_counter() - start
    assert not judge(outcome, 2, out, f"c06.csv:{line}")
    assert took < 10, f"{took:.1f} s"
