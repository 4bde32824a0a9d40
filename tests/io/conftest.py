"""Fixtures of the record tests: both text engines, small blocks."""

import pytest

from pihyst.io import _records, _text_engines, _text_source


@pytest.fixture(params=["c", "pyarrow", "numpy"])
def engine(request, monkeypatch):
    """Run the test with each vectorised engine (pyarrow skipped when not installed)."""
    if request.param == "pyarrow":
        pytest.importorskip("pyarrow")
    if request.param == "c" and _text_engines._fast() is None:
        pytest.fail("the C parser (pihyst.io._fastcsv) is not built")
    monkeypatch.setattr(_text_engines, "engine_name", lambda: request.param)
    return request.param


@pytest.fixture
def small_blocks(monkeypatch):
    """Blocks of a few bytes and rows, so that every test crosses block boundaries."""
    monkeypatch.setattr(_text_source, "BLOCK_BYTES", 64)
    monkeypatch.setattr(_records, "BLOCK_ROWS", 3)
