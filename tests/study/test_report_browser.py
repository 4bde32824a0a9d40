"""The report as a person sees it: headless Chromium renders report.html from disk;
every figure must load and the page must not be blank.

Chromium is Debian's ``chromium`` package (``.ci/run`` installs it and sets
PIHYST_REQUIRE_BROWSER=1, so in CI this test runs or fails, never skips).
"""

import os
import re
import shutil
import subprocess

import numpy as np
import pytest
from matplotlib.image import imread

CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                  "--no-first-run", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--hide-scrollbars"]

# Appended to a copy of the report (the report itself has no script): once the page has
# loaded, count the images that decoded and write the result into the DOM.
CHECK_SCRIPT = """<script>
window.addEventListener("load", function () {
  var imgs = Array.prototype.slice.call(document.images);
  var ok = imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; });
  var bad = imgs.filter(function (i) { return !(i.complete && i.naturalWidth > 0); })
                .map(function (i) { return i.alt; });
  var d = document.createElement("div");
  d.id = "pihyst-check";
  d.textContent = "IMAGES " + ok.length + "/" + imgs.length + " BAD[" + bad.join("|") + "]"
                  + " WIDTHS[" + ok.map(function (i) { return i.naturalWidth; }).join(",") + "]";
  document.body.appendChild(d);
});
</script>"""


def _chromium():
    for name in ("chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return None


@pytest.fixture(scope="module")
def browser():
    path = _chromium()
    if path is None:
        if os.environ.get("PIHYST_REQUIRE_BROWSER") == "1" or os.environ.get("CI"):
            pytest.fail("chromium is required here (PIHYST_REQUIRE_BROWSER/CI) but was not "
                        "found: apt-get install chromium")
        pytest.skip("chromium not installed (apt-get install chromium); CI runs this test")
    return path


@pytest.fixture(scope="module")
def report(demo):
    return demo[1]


def _run(browser, profile, *args, timeout=120):
    cmd = [browser, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)


def test_every_figure_loads(browser, report, tmp_path):
    html = (report / "report.html").read_text(encoding="utf-8")
    n_img = html.count("<img ")
    assert n_img == 10
    checked = tmp_path / "checked.html"
    checked.write_text(html.replace("</body>", CHECK_SCRIPT + "</body>"), encoding="utf-8")
    res = _run(browser, tmp_path / "profile", "--virtual-time-budget=10000", "--dump-dom",
               checked.as_uri())
    found = re.search(r"IMAGES (\d+)/(\d+) BAD\[([^\]]*)\] WIDTHS\[([^\]]*)\]", res.stdout)
    assert found, f"no check result in the DOM; chromium said: {res.stderr[-2000:]}"
    ok, total, bad, widths = found.groups()
    assert (int(ok), int(total), bad) == (n_img, n_img, "")
    assert all(int(w) > 300 for w in widths.split(","))


def test_the_page_is_not_blank(browser, report, tmp_path):
    shot = tmp_path / "page.png"
    res = _run(browser, tmp_path / "profile", f"--screenshot={shot}",
               "--window-size=1200,2400", (report / "report.html").as_uri())
    assert shot.exists(), f"no screenshot; chromium said: {res.stderr[-2000:]}"
    img = imread(shot)[..., :3]
    assert img.shape[0] >= 2000 and img.shape[1] >= 1100
    ink = np.any(img < 0.85, axis=2)                   # anything not near-white
    assert ink.mean() > 0.03                           # text, tables and figures
    colour = (img.max(axis=2) - img.min(axis=2)) > 0.3  # the figures' coloured lines
    assert colour.sum() > 500
    rows_with_ink = np.flatnonzero(ink.any(axis=1))
    assert rows_with_ink.size > 0.5 * img.shape[0]     # content down the page
