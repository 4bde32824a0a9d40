"""Every shell command of the README runs as written, in the README's order, from the
root of a copy of the repository (its tracked files: a fresh clone), with the installed
`pihyst` on PATH and the measured sets found by the documented rule (`make data`).

The set-up commands themselves (`make demo`, `make test`, `pip install`) are what this
suite runs in, and are left out, as is a command that opens a window (`--gui`). The
files the text leaves to the reader — their own records in each format, a fleet of
records — are made first from the simulated beams (GIVEN below, as
tests/docs/test_readme.py does for the Python examples)."""

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
README = REPO / "README.md"
SET_UP = ("make demo", "make test", "pip install")
# a command that opens a window for a person to use cannot run here
INTERACTIVE = ("--gui",)
GIVEN = ("run.lvm", "run.tdms", "loop.xlsx", "drec.dat", "loop.csv", "records/", "raw/",
         "options.json")

pytestmark = pytest.mark.skipif(not README.exists(), reason="runs from a source checkout")


def readme_commands(text):
    """The README's shell commands in order: continuation lines joined, comments and
    blank lines left out."""
    out = []
    for block in re.findall(r"```sh\n(.*?)```", text, flags=re.S):
        for line in block.replace("\\\n", " ").splitlines():
            words = shlex.split(line, comments=True)
            if words:
                out.append(words)
    return out


def _record(seed=0, signal="decaying"):
    from pihyst.sim import make_plant
    from pihyst.sim.signals import decaying_triangles, random_ramps
    if signal == "decaying":
        t, u = decaying_triangles(dt=1.0)
    else:
        t, u = random_ramps(n_ramps=10, dt=1.0, seed=seed)
    return t, u, make_plant("paper-beam", seed=seed).run(u, t)


def make_given(root):
    """The reader's own files the README's commands name."""
    t, u, y = _record()
    text = "\n".join(f"{a:.6g}\t{b:.6g}\t{c:.6g}" for a, b, c in zip(t, u, y))
    # LabVIEW Measurement File: one segment, one X column
    head = ("LabVIEW Measurement\t\nWriter_Version\t2\nReader_Version\t2\nSeparator\tTab\n"
            "Decimal_Separator\t.\nMulti_Headings\tNo\nX_Columns\tOne\nTime_Pref\tRelative\n"
            "***End_of_Header***\t\n\t\n"
            f"Channels\t2\t\nSamples\t{t.size}\t{t.size}\t\nX0\t0\t0\t\nDelta_X\t1\t1\t\n"
            "***End_of_Header***\t\nX_Value\tVoltage\tDisplacement\tComment\n")
    (root / "run.lvm").write_text(head + text + "\n")
    import nptdms
    with nptdms.TdmsWriter(str(root / "run.tdms")) as w:
        w.write_segment([nptdms.RootObject(), nptdms.GroupObject("Loop"),
                         nptdms.ChannelObject("Loop", "Voltage", u,
                                              properties={"wf_increment": 1.0,
                                                          "unit_string": "V"}),
                         nptdms.ChannelObject("Loop", "Position", y,
                                              properties={"unit_string": "um"})])
    import openpyxl
    book = openpyxl.Workbook()
    sheet = book.active
    sheet.title = "Loop"
    sheet.append(["Time", "Voltage", "Displacement"])
    sheet.append(["s", "V", "µm"])
    for row in zip(t.tolist(), u.tolist(), y.tolist()):
        sheet.append(row)
    book.save(root / "loop.xlsx")
    # PI data recorder (GCSArray) as PIPython's savegcsarray writes it
    header = {"VERSION": 1, "TYPE": 1, "SEPARATOR": 32, "DIM": 2, "SAMPLE_TIME": 1.0,
              "NDATA": t.size, "NAME0": "Voltage of axis 1", "NAME1": "Position of axis 1"}
    drec = "".join(f"# {k} = {v} \n" for k, v in header.items()) + "# \n# END_HEADER \n"
    drec += "".join(f"{a:.6f} {b:.6f} \n" for a, b in zip(u, y))
    (root / "drec.dat").write_text(drec[:-2] + "\n")
    # a units row and the time in ms
    rows = "\n".join(f"{1000 * a:g},{b:.6g},{c:.6g}" for a, b, c in zip(t, u, y))
    (root / "loop.csv").write_text(f"time_ms,voltage,displacement\nms,V,um\n{rows}\n")
    # a fleet: two records as CSV, two in the P-885 stack's .dat layout
    for folder in ("records", "raw"):
        (root / folder).mkdir()
    for k in (1, 2):
        t, u, y = _record(seed=k, signal="ramps")
        rows = "\n".join(f"{a:g},{b:.6g},{c:.6g}" for a, b, c in zip(t, u, y))
        (root / "records" / f"act{k:02d}.csv").write_text(
            f"time_s,voltage_V,displacement_um\n{rows}\n")
        dat = "\n".join(f"{b:.6g}\t0\t0\t0\t{c:.6g}\t-317.2\t-317.2" for b, c in zip(u, y))
        (root / "raw" / f"act{k:02d}.dat").write_text(dat + "\n")
    (root / "options.json").write_text('{"act01.dat": {"voltage": 1, "displacement": 5, '
                                       '"lag": 1, "rate": 200}, "act02.dat": {"voltage": 1, '
                                       '"displacement": 5, "rate": 200}}')


def fresh_clone(dest):
    files = subprocess.run(["git", "-C", str(REPO), "ls-files", "-z"], check=True,
                           capture_output=True).stdout.decode().split("\0")
    for name in filter(None, files):
        src = REPO / name
        if src.is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / name)
    return dest


@pytest.mark.slow
@pytest.mark.skipif(not (REPO / ".git").exists() or shutil.which("git") is None,
                    reason="copies the tracked files of a git checkout")
def test_every_readme_command_runs_as_written(tmp_path):
    from pihyst.io import datasets
    data = datasets.data_root()
    if data is None:
        pytest.skip("the measured data sets are not here ($PIHYST_DATA or ../shared/data)")
    bin_dir = Path(sys.executable).parent
    if not (bin_dir / "pihyst").exists():
        pytest.skip("the pihyst command is not installed beside this Python")
    root = fresh_clone(tmp_path / "pihyst")
    make_given(root)
    env = dict(os.environ, PATH=f"{bin_dir}{os.pathsep}{os.environ['PATH']}",
               PIHYST_DATA=str(data), MPLBACKEND="Agg")
    ran = []
    for words in readme_commands(README.read_text(encoding="utf-8")):
        line = " ".join(words)
        if line.startswith(SET_UP) or any(w in INTERACTIVE for w in words):
            continue
        proc = subprocess.run(words, cwd=root, env=env, capture_output=True, text=True,
                              timeout=900, stdin=subprocess.DEVNULL)
        assert proc.returncode == 0, (f"README command failed (exit {proc.returncode}): "
                                      f"{line}\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}")
        ran.append(line)
    assert any(c.startswith("make data") for c in ran)
    assert len(ran) >= 30
    # what they wrote is there
    for name in ("p885.json", "smart.json", "check.svg", "model.json", "rep/report.html",
                 "models/summary.csv", "run.csv", "stage_x.h", "csrc/libpihyst.so"):
        assert (root / name).exists(), name


def test_no_readme_command_reaches_outside_the_clone():
    for words in readme_commands(README.read_text(encoding="utf-8")):
        assert not any(w.startswith("../") or "/../" in w for w in words), " ".join(words)
