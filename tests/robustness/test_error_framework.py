"""The exit statuses and one-line messages of docs/errors.md, for every kind of failure
a command can meet: user errors 2, internal errors 70 (traceback only with --debug),
Ctrl-C 130, a closed pipe 0."""

import errno
import subprocess
import sys

import pytest

from pihyst.cli import main, predict
from pihyst.cli.errors import UsageError, run_command
from pihyst.exceptions import FitError, InvalidArgumentError


def _fails_with(exc):
    def run(args):
        raise exc
    return run


@pytest.mark.parametrize("exc, status, says", [
    (UsageError("--foo: bad"), 2, "pihyst: error: --foo: bad"),
    (FitError("cannot fit\nat all"), 2, "pihyst: error: cannot fit at all"),
    (InvalidArgumentError("seed must be >= 0"), 2, "pihyst: error: seed must be >= 0"),
    (FileNotFoundError(errno.ENOENT, "No such file or directory", "in.csv"), 2,
     "pihyst: error: in.csv: No such file or directory"),
    (OSError(errno.ENOSPC, "No space left on device"), 2,
     "pihyst: error: No space left on device"),
    (MemoryError(), 2, "pihyst: error: not enough memory"),
    (KeyboardInterrupt(), 130, "pihyst: interrupted"),
    (ZeroDivisionError("float division by zero"), 70, "pihyst: internal error: "
     "ZeroDivisionError: float division by zero -- this is a bug in pihyst"),
    (RecursionError("maximum recursion depth exceeded"), 70, "internal error"),
])
def test_status_and_one_line(capsys, exc, status, says):
    assert run_command(_fails_with(exc), None) == status
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and says in err


def test_closed_pipe_is_quiet(capsys):
    assert run_command(_fails_with(BrokenPipeError(errno.EPIPE, "Broken pipe")), None) == 0
    assert capsys.readouterr().err == ""


def test_internal_error_traceback_only_with_debug(capsys, monkeypatch, tmp_path):
    monkeypatch.setattr(predict, "run", _fails_with(TypeError("unexpected")))
    argv = ["predict", "m.json", "in.csv", "-o", str(tmp_path / "o.csv")]
    assert main(argv) == 70
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err and "--debug" in err
    assert main([*argv, "--debug"]) == 70
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err
    assert err.splitlines()[-1].startswith("pihyst: internal error: TypeError: unexpected")
    monkeypatch.setenv("PIHYST_DEBUG", "1")
    assert main(argv) == 70
    assert "Traceback" in capsys.readouterr().err


def test_usage_errors_are_one_line(capsys):
    for argv in ([], ["frobnicate"], ["predict"], ["fit", "x.csv", "-o", "m.json", "--nope"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("pihyst: error: ")
        assert "--help" in err


def test_help_and_version_exit_0(capsys):
    assert main(["--version"]) == 0
    assert main(["fit", "--help"]) == 0
    assert main(["--help"]) == 0
    assert "--debug" in capsys.readouterr().out


def test_non_pihyst_warnings_are_one_line(capsys):
    import warnings

    def run(args):
        warnings.warn("overflow encountered", RuntimeWarning, stacklevel=2)
    with warnings.catch_warnings():
        warnings.simplefilter("default")    # as in a plain interpreter, not pytest's "error"
        assert run_command(run, None) == 0
    assert capsys.readouterr().err == "pihyst: warning: RuntimeWarning: overflow encountered\n"


def test_real_process_statuses(tmp_path):
    """The installed entry point, as a shell sees it (a few subprocesses only)."""
    bad = tmp_path / "bad.json"
    bad.write_text("[" * 100000)
    proc = subprocess.run([sys.executable, "-m", "pihyst", "predict", str(bad),
                           "in.csv", "-o", str(tmp_path / "o.csv")],
                          capture_output=True, text=True)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1
    assert "Traceback" not in proc.stderr


def test_unreadable_files(tmp_path, capsys):
    """chmod 000: one line naming the file (as root, which reads anything, it runs)."""
    import os
    import shutil

    from harness import GOOD_MODEL, VOLTS
    model, record = tmp_path / "m.json", tmp_path / "in.csv"
    shutil.copy(GOOD_MODEL, model)
    shutil.copy(VOLTS, record)
    for path in (model, record):
        path.chmod(0)
    out = tmp_path / "out.csv"
    status = main(["predict", str(model), str(record), "-o", str(out)])
    err = capsys.readouterr().err
    if os.geteuid() == 0:
        assert status == 0 and out.exists()
    else:
        assert status == 2 and err.count("\n") == 1 and "m.json" in err
        assert "Permission denied" in err and not out.exists()
