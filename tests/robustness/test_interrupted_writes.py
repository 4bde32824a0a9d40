"""Nothing left behind on a signal (issue 24, item 6): the streamed CSV writer of
predict/compensate/simulate and the report folder, killed with SIGKILL, SIGTERM or
Ctrl-C at the worst moment (rows written, file not yet in place), leave neither a partial
target nor a temporary; SIGTERM is handled as Ctrl-C (exit status 143). Devices and
named pipes given as output are written as streams, never replaced."""

import os
import signal
import stat
import subprocess
import sys
import threading

import pytest
from harness import GOOD_MODEL, LOOP, VOLTS, run

from pihyst._atomic import AtomicFile, AtomicFolder

# `pihyst predict` through main(), stalled after its first block of rows: the test
# signals it there. argv[1]: 'named' forces the fallback without O_TMPFILE.
_STALLED_PREDICT = """
import signal, sys, time
# as in a foreground process, whatever started the suite (a shell's background job
# ignores SIGINT, and its children inherit that)
signal.signal(signal.SIGINT, signal.default_int_handler)
from pihyst import _atomic
from pihyst.io import _csv
if sys.argv[1] == "named":
    _atomic._open_unnamed = lambda folder: None
write = _csv.ColumnWriter.write
def stalled(self, columns):
    write(self, columns)
    self._file._file.flush()
    print("written", flush=True)
    time.sleep(60)
_csv.ColumnWriter.write = stalled
from pihyst.cli import main
sys.exit(main(sys.argv[2:]))
"""


def _signal_stalled_predict(tmp_path, how, sig):
    out = tmp_path / "out.csv"
    argv = [sys.executable, "-c", _STALLED_PREDICT, how, "predict", GOOD_MODEL, VOLTS,
            "-o", str(out)]
    with subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True) as child:
        assert child.stdout.readline().strip() == "written"
        child.send_signal(sig)
        _, err = child.communicate(timeout=30)
    return child.returncode, err


@pytest.mark.parametrize("how", ["unnamed", "named"])
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT, signal.SIGHUP])
def test_a_signal_during_a_streamed_write_leaves_nothing(tmp_path, how, sig):
    status, err = _signal_stalled_predict(tmp_path, how, sig)
    assert os.listdir(tmp_path) == []
    if sig == signal.SIGINT:
        assert status == 130 and err.strip() == "pihyst: interrupted"
    else:
        assert status == 143
        assert err.strip() == f"pihyst: terminated ({signal.Signals(sig).name})"


def test_sigkill_during_a_streamed_write_leaves_nothing(tmp_path):
    status, _ = _signal_stalled_predict(tmp_path, "unnamed", signal.SIGKILL)
    assert status == -signal.SIGKILL
    assert os.listdir(tmp_path) == []


def test_sigkill_during_a_streamed_write_keeps_the_old_file(tmp_path):
    (tmp_path / "out.csv").write_text("old\n")
    _signal_stalled_predict(tmp_path, "unnamed", signal.SIGKILL)
    assert os.listdir(tmp_path) == ["out.csv"]
    assert (tmp_path / "out.csv").read_text() == "old\n"


def test_atomic_file_streams_and_aborts(tmp_path):
    target = tmp_path / "a.csv"
    with AtomicFile(target) as f:
        f.write(b"one\n")
        assert os.listdir(tmp_path) == []        # nothing visible before the end
        f.write(b"two\n")
    assert target.read_text() == "one\ntwo\n"
    with pytest.raises(KeyboardInterrupt):
        with AtomicFile(target) as f:
            f.write(b"partial")
            raise KeyboardInterrupt
    assert os.listdir(tmp_path) == ["a.csv"] and target.read_text() == "one\ntwo\n"


def test_a_symbolic_link_is_written_through(tmp_path):
    real = tmp_path / "real.csv"
    real.write_text("old\n")
    link = tmp_path / "link.csv"
    link.symlink_to(real)
    with AtomicFile(link) as f:
        f.write(b"new\n")
    assert link.is_symlink() and real.read_text() == "new\n"


@pytest.mark.parametrize("command", [
    ["predict", GOOD_MODEL, VOLTS],
    ["simulate", "--cycles", "1"],
    ["compensate", GOOD_MODEL, os.path.join(os.path.dirname(VOLTS), "desired.csv"),
     "--saturate"],
])
def test_a_named_pipe_as_output_is_streamed_not_replaced(tmp_path, command):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()), daemon=True)
    reader.start()
    outcome = run([*command, "-o", str(fifo)])
    reader.join(timeout=20)
    assert outcome.status == 0, outcome.err
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert got and got[0].count(b"\n") > 10
    assert sorted(os.listdir(tmp_path)) == ["pipe"]


def test_a_report_folder_appears_complete_or_not_at_all(tmp_path, monkeypatch):
    pytest.importorskip("matplotlib")
    import pihyst.study as study_pkg
    real = study_pkg.write_report

    def interrupted(study, out_dir, **kwargs):
        with open(os.path.join(out_dir, "first.csv"), "w") as f:
            f.write("x\n")
        raise KeyboardInterrupt
    monkeypatch.setattr(study_pkg, "write_report", interrupted)
    out = tmp_path / "rep"
    outcome = run(["report", LOOP, "--out", str(out)])
    assert outcome.status == 130
    assert os.listdir(tmp_path) == []
    assert real is not interrupted


def test_atomic_folder_replaces_its_files_in_an_existing_folder(tmp_path):
    out = tmp_path / "rep"
    out.mkdir()
    (out / "mine.txt").write_text("keep\n")
    (out / "a.csv").write_text("old\n")
    with AtomicFolder(out) as build:
        with open(os.path.join(build, "a.csv"), "w") as f:
            f.write("new\n")
        assert (out / "a.csv").read_text() == "old\n"
    assert (out / "a.csv").read_text() == "new\n" and (out / "mine.txt").exists()
    assert sorted(os.listdir(tmp_path)) == ["rep"]
    with pytest.raises(RuntimeError):
        with AtomicFolder(tmp_path / "new") as build:
            open(os.path.join(build, "x"), "w").close()
            raise RuntimeError
    assert sorted(os.listdir(tmp_path)) == ["rep"]
