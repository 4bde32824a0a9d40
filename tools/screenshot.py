"""Regenerate the README's screenshot of the demo report with headless Chromium.

    python tools/screenshot.py out/demo/report.html docs/demo-report.png

Takes the top of the page (title, summary, Table 1 and the first figure) at a fixed
window size, so that a new screenshot differs from the last only where the report did.
Needs chromium (Debian: apt-get install chromium) or google-chrome on PATH.
"""

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
WINDOW = "1000,2150"


def browser():
    for name in BROWSERS:
        path = shutil.which(name)
        if path:
            return path
    return None


def screenshot(html, png, window=WINDOW, timeout=120):
    """Write ``png``, the screenshot of the page ``html``; raises RuntimeError saying why
    when there is no browser or it fails."""
    exe = browser()
    if exe is None:
        raise RuntimeError(f"no headless browser found (tried {', '.join(BROWSERS)})")
    html, png = Path(html).resolve(), Path(png)
    if not html.is_file():
        raise RuntimeError(f"{html}: no such report (make demo writes out/demo/report.html)")
    with tempfile.TemporaryDirectory() as tmp:
        shot = Path(tmp) / "shot.png"
        cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
               f"--user-data-dir={tmp}/profile", f"--window-size={window}",
               "--force-device-scale-factor=1", f"--screenshot={shot}", html.as_uri()]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        if proc.returncode != 0 or not shot.is_file() or shot.stat().st_size == 0:
            raise RuntimeError(f"{Path(exe).name} failed (exit {proc.returncode}): "
                               f"{proc.stderr.strip().splitlines()[-1:] or ''}")
        png.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(shot, png)
    return png


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("html", help="the report page (out/demo/report.html)")
    p.add_argument("png", help="the screenshot to write (docs/demo-report.png)")
    p.add_argument("--window", default=WINDOW, help=f"width,height (default {WINDOW})")
    args = p.parse_args(argv)
    try:
        out = screenshot(args.html, args.png, args.window)
    except (RuntimeError, subprocess.TimeoutExpired, OSError) as err:
        print(f"screenshot: error: {err}", file=sys.stderr)
        return 2
    print(f"screenshot: wrote {out} ({out.stat().st_size // 1024} kB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
