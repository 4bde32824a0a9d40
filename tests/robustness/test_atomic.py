"""The atomic writer: nothing left by an interrupted write, not even after SIGKILL; errors
name the path asked for; special files written directly; a closed pipe is quiet."""

import os
import signal
import subprocess
import sys
import time

import pytest
from harness import GOOD_MODEL, VOLTS

from pihyst import _atomic
from pihyst._atomic import write_atomically

# a child that writes a large file and stops (as if slow) just before the file would be
# put in place; the test kills it there with SIGKILL
_KILLED_WRITER = """
import os, sys, time
from pihyst import _atomic
if sys.argv[2] == "named":
    _atomic._open_unnamed = lambda folder: None
real_fsync = os.fsync
def stall(fd):
    real_fsync(fd)
    print("written", flush=True)
    time.sleep(60)
os.fsync = stall
_atomic.write_atomically(sys.argv[1], b"x" * (16 << 20))
"""


def _kill_mid_write(target, how):
    with subprocess.Popen([sys.executable, "-c", _KILLED_WRITER, str(target), how],
                          stdout=subprocess.PIPE, text=True) as child:
        assert child.stdout.readline().strip() == "written"
        child.send_signal(signal.SIGKILL)
        child.wait()
    return child.returncode


def test_sigkill_mid_write_leaves_nothing(tmp_path):
    target = tmp_path / "big.csv"
    assert _kill_mid_write(target, "unnamed") == -signal.SIGKILL
    assert os.listdir(tmp_path) == []


def test_sigkill_mid_write_keeps_the_old_file_whole(tmp_path):
    target = tmp_path / "big.csv"
    target.write_text("old\n")
    _kill_mid_write(target, "unnamed")
    assert os.listdir(tmp_path) == ["big.csv"] and target.read_text() == "old\n"


def test_without_o_tmpfile_a_killed_writers_temporary_is_cleaned_once_stale(tmp_path):
    target = tmp_path / "big.csv"
    _kill_mid_write(target, "named")
    left = [f for f in os.listdir(tmp_path) if f.startswith(".pihyst-")]
    assert len(left) == 1                        # the fallback cannot avoid this one...
    write_atomically(tmp_path / "other.csv", "x\n")
    assert left[0] in os.listdir(tmp_path)       # ...which is too fresh to be judged stale
    old = time.time() - _atomic.STALE_AFTER_S - 60
    os.utime(tmp_path / left[0], (old, old))
    write_atomically(tmp_path / "other.csv", "y\n")
    assert sorted(os.listdir(tmp_path)) == ["other.csv"]


@pytest.mark.parametrize("unnamed", [True, False])
def test_write_replace_and_mode(tmp_path, monkeypatch, unnamed):
    if not unnamed:
        monkeypatch.setattr(_atomic, "_open_unnamed", lambda folder: None)
    target = tmp_path / "a.csv"
    write_atomically(target, "first\n")
    write_atomically(target, b"second\n")
    assert target.read_text() == "second\n" and os.listdir(tmp_path) == ["a.csv"]
    umask = os.umask(0)
    os.umask(umask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~umask


def test_an_error_while_writing_leaves_nothing(tmp_path, monkeypatch):
    def broken(fd):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(os, "fsync", broken)
    with pytest.raises(OSError) as err:
        write_atomically(tmp_path / "a.csv", "data")
    assert err.value.filename == str(tmp_path / "a.csv")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("where, says", [
    ("missing/deeper/out.csv", "folder {tmp}/missing does not exist"),
    ("", "is a folder"),
    ("file.txt/out.csv", "{tmp}/file.txt is not a folder"),
])
def test_errors_name_the_requested_path(scratch, where, says):
    path = os.path.join(str(scratch), where) if where else str(scratch)
    with pytest.raises(OSError) as err:
        write_atomically(path, "x")
    assert err.value.filename == path
    assert says.format(tmp=scratch) in err.value.strerror
    assert not [f for f in os.listdir(scratch) if f.startswith(".pihyst-")]


def test_special_files_are_written_directly():
    write_atomically(os.devnull, "nothing to see\n")


def test_closed_pipe_on_stdout_is_quiet(tmp_path):
    """pihyst ... | head: the reader went away; no 'Broken pipe', exit 0, file complete."""
    read, write = os.pipe()
    os.close(read)
    out = tmp_path / "out.csv"
    proc = subprocess.run([sys.executable, "-m", "pihyst", "predict", GOOD_MODEL, VOLTS,
                           "-o", str(out)], stdout=write, stderr=subprocess.PIPE, text=True)
    os.close(write)
    assert proc.returncode == 0 and proc.stderr == ""
    assert out.read_text().count("\n") > 40


def _read_only_folder(folder):
    raise PermissionError(13, "Permission denied", os.path.join(folder, ".pihyst-x.tmp"))


@pytest.mark.parametrize("command", [["predict", GOOD_MODEL, VOLTS], ["simulate"]])
def test_a_read_only_folder_is_named_never_a_temporary(tmp_path, monkeypatch, command):
    from harness import run
    monkeypatch.setattr(_atomic, "_open_unnamed", _read_only_folder)
    out = tmp_path / "out.csv"
    outcome = run([*command, "-o", str(out)])
    assert outcome.status == 2
    assert outcome.err.strip() == (f"pihyst: error: {out}: cannot write: folder {tmp_path} "
                                   "is not writable (Permission denied)")
    assert ".pihyst-" not in outcome.err and os.listdir(tmp_path) == []


_FDOPEN = os.fdopen


class _FullDisk:
    """A file whose writes fail as on a full disk (an OSError naming no file)."""

    def __init__(self, fd):
        self._real = _FDOPEN(fd, "wb")

    def write(self, data):
        raise OSError(28, "No space left on device")

    def __getattr__(self, name):
        return getattr(self._real, name)


@pytest.mark.parametrize("command", [["predict", GOOD_MODEL, VOLTS], ["simulate"]])
def test_a_full_disk_names_the_output(tmp_path, monkeypatch, command):
    from harness import run
    monkeypatch.setattr(_atomic.os, "fdopen", lambda fd, mode: _FullDisk(fd))
    out = tmp_path / "out.csv"
    outcome = run([*command, "-o", str(out)])
    assert outcome.status == 2
    assert outcome.err.strip() == f"pihyst: error: {out}: No space left on device"
    assert os.listdir(tmp_path) == []
