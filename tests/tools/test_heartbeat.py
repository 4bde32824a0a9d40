"""tools/heartbeat.py, which make runs its long steps under: the command's output passes
through as it comes, a line saying what runs follows every silence longer than --every,
and the exit status is the command's."""

import subprocess
import sys
from pathlib import Path

import pytest

HEARTBEAT = Path(__file__).resolve().parents[2] / "tools" / "heartbeat.py"
pytestmark = pytest.mark.skipif(not HEARTBEAT.exists(), reason="runs from a source checkout")


def run(code, every="0.3"):
    return subprocess.run([sys.executable, str(HEARTBEAT), "--every", every, "--",
                           sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)


def test_output_passes_through_and_silences_are_filled():
    proc = run("import time; print('first'); time.sleep(1.2); print('last')")
    lines = proc.stdout.splitlines()
    assert proc.returncode == 0
    assert lines[0] == "first" and lines[-1] == "last"
    beats = lines[1:-1]
    assert beats and all(b.startswith("make: ... ") and " s into python" in b for b in beats)


def test_a_quiet_command_that_ends_soon_gets_no_heartbeat():
    proc = run("print('done')", every="30")
    assert proc.stdout == "done\n"


def test_the_exit_status_is_the_commands():
    assert run("import sys; sys.exit(3)", every="30").returncode == 3


def test_a_heartbeat_starts_its_own_line_after_a_partial_one():
    proc = run("import sys, time; sys.stdout.write('...'); sys.stdout.flush(); "
               "time.sleep(1)")
    assert proc.stdout.startswith("...\nmake: ... ")


def test_it_names_the_program_the_command_started():
    code = "import subprocess; subprocess.run(['sleep', '1.2'])"
    proc = run(code)
    assert "running sleep 1.2" in proc.stdout


def test_ctrl_c_ends_both_quietly_with_the_commands_status():
    import os
    import signal
    import time
    # as a terminal starts it: Ctrl-C not ignored (a job started in the background by a
    # shell without job control, as some CI runners start theirs, inherits SIGINT ignored)
    proc = subprocess.Popen([sys.executable, str(HEARTBEAT), "--", sys.executable, "-c",
                             "import time; print('up', flush=True); time.sleep(30)"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert proc.stdout.readline() == "up\n"
    time.sleep(0.3)
    os.killpg(proc.pid, signal.SIGINT)          # as the terminal sends it, to the group
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 130               # the command's: ended by SIGINT
    assert err == ""                            # no traceback of the heartbeat's own
    assert "KeyboardInterrupt" in out           # the command's last words pass through
