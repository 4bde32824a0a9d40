"""tools/screenshot.py, which regenerates the README's screenshot (make screenshot):
headless Chromium's PNG of a page, at the fixed window size; one line and exit status 2
when there is no page or no browser."""

import importlib
import struct
import sys
from pathlib import Path

import pytest

TOOLS = Path(__file__).resolve().parents[2] / "tools"
pytestmark = pytest.mark.skipif(not (TOOLS / "screenshot.py").exists(),
                                reason="runs from a source checkout")


@pytest.fixture(scope="module")
def screenshot():
    sys.path.insert(0, str(TOOLS))
    try:
        yield importlib.import_module("screenshot")
    finally:
        sys.path.remove(str(TOOLS))


@pytest.mark.slow
def test_a_page_becomes_a_png_of_the_window_size(screenshot, tmp_path):
    if screenshot.browser() is None:
        pytest.skip("no headless browser (apt-get install chromium)")
    page = tmp_path / "report.html"
    page.write_text("<!DOCTYPE html><html><body><h1>pihyst</h1></body></html>")
    png = screenshot.screenshot(page, tmp_path / "shot.png", window="400,300")
    data = png.read_bytes()
    assert data.startswith(b"\x89PNG\r\n\x1a\n")
    assert struct.unpack(">II", data[16:24]) == (400, 300)


def test_no_report_is_one_line_and_status_2(screenshot, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(screenshot, "browser", lambda: "/usr/bin/true")
    assert screenshot.main([str(tmp_path / "none.html"), str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no such report" in err
    assert not (tmp_path / "x.png").exists()


def test_no_browser_is_one_line_and_status_2(screenshot, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(screenshot, "browser", lambda: None)
    page = tmp_path / "report.html"
    page.write_text("<html></html>")
    assert screenshot.main([str(page), str(tmp_path / "x.png")]) == 2
    assert "no headless browser found" in capsys.readouterr().err
