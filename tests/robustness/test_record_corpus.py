"""Every malformed record (CSV) of the corpus whose outcome does not hang on the CSV
reader's internals (those are in test_csv_corpus.py), fed to predict, fit, compensate
and track: one line and exit status 2 with file, line and column, or exit 0 with the
values read exactly; fit's data-sufficiency errors and warnings."""

import os

import numpy as np
import pytest
from corpus_cases import check, params
from harness import CORPUS, MANIFEST

from pihyst.io import read_columns


@pytest.mark.parametrize("name, command, expect, says, warns", params("csv", reader=False))
def test_record_on_the_command_line(tmp_path, name, command, expect, says, warns):
    outcome = check(tmp_path, name, command, expect, says, warns)
    values = MANIFEST[name].get("values")
    if values and outcome.status == 0 and command == "predict":
        cols, _ = read_columns(tmp_path / "out.csv", ["time_s", "voltage_V"])
        np.testing.assert_array_equal(cols["voltage_V"], values["voltage_V"])
        np.testing.assert_array_equal(cols["time_s"], values["time_s"])


@pytest.mark.parametrize("name", sorted(n for n, e in MANIFEST.items()
                                        if n.startswith("csv/") and e.get("values")))
def test_accepted_variants_read_the_same_values(name):
    cols, _ = read_columns(os.path.join(CORPUS, name),
                           ["time_s", "voltage_V", "displacement_um"])
    for column, expected in MANIFEST[name]["values"].items():
        np.testing.assert_array_equal(cols[column], expected, err_msg=f"{name} {column}")
