"""Fixtures of the robustness tests: a scratch folder per case with the files some option
cases name (a plain file where a folder is expected, a broken record)."""

import pytest


@pytest.fixture
def scratch(tmp_path):
    (tmp_path / "file.txt").write_text("not a folder\n")
    (tmp_path / "bad.csv").write_text("voltage_V,displacement_um\n1,x\n")
    return tmp_path
