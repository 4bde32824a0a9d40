"""The command line's error framework (docs/errors.md), shared by every command.

- An error the user can cause (a bad file, a bad option, data that cannot be fitted, an
  output that cannot be written) is one line ``pihyst: error: ...`` on stderr naming the
  file, line and column, or the option, with exit status 2 and no output file. A command
  reports one by raising one of :data:`USER_ERRORS` (:class:`UsageError` for its own
  checks) or an ``OSError`` that names the file.
- Anything else is a bug in pihyst: one line saying so and where to report it, exit
  status 70; the traceback only with ``--debug``.
- Ctrl-C: exit status 130. A closed standard output (``pihyst ... | head``): quiet,
  exit status 0 (the output files are complete before anything is printed).

Option values are checked where they are parsed, by the types below
(``type=positive_number``...): an out-of-range value is an error naming the option.
"""

import argparse
import math
import os
import re
import signal
import stat
import sys
import threading
import traceback
import warnings

from pihyst.exceptions import (
    FitError,
    InputRangeError,
    InvalidArgumentError,
    InvalidModelError,
    PihystWarning,
    RecordError,
)

EXIT_OK = 0
EXIT_USER_ERROR = 2
EXIT_BUG = 70            # EX_SOFTWARE of sysexits.h
EXIT_INTERRUPTED = 130   # 128 + SIGINT
EXIT_TERMINATED = 143    # 128 + SIGTERM

BUG_REPORTS = "the pihyst issue tracker (see 'Reporting bugs' in the README)"


class UsageError(ValueError):
    """Bad input detected by a command; the message is shown as is."""


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP arrived: handled as Ctrl-C is (every writer gives its file up,
    the rig zeroes the supply), then exit status 143."""


def _terminate(signum, frame):
    raise Terminated(signal.Signals(signum).name)


class _TerminationHandled:
    """SIGTERM and SIGHUP raise :class:`Terminated` while a command runs (main thread)."""

    SIGNALS = tuple(getattr(signal, n) for n in ("SIGTERM", "SIGHUP") if hasattr(signal, n))

    def __enter__(self):
        self._old = {}
        if threading.current_thread() is threading.main_thread():
            for sig in self.SIGNALS:
                try:
                    self._old[sig] = signal.signal(sig, _terminate)
                except (OSError, ValueError):
                    pass
        return self

    def __exit__(self, *exc):
        for sig, old in self._old.items():
            signal.signal(sig, old)
        return False


USER_ERRORS = (RecordError, InvalidModelError, InputRangeError, FitError, InvalidArgumentError,
               UsageError)


def one_line(text):
    """``text`` with line breaks turned into spaces: every message is one line."""
    return " ".join(str(text).splitlines()) or "(no message)"


#: What argparse takes for an option's value rather than an option name: its own rule for
#: negative numbers (``-5``, ``-.5``) widened to any float notation (``-1e-3``, ``-2.5E+8``,
#: ``-inf``), and to a list starting with one (``--input-range -10,150``). No option name
#: of pihyst starts with '-' and a digit; the option's type then says what is wrong.
NEGATIVE_NUMBER = re.compile(r"^-(\.?\d[\d.eE+\-,\s]*|inf|infinity|nan)$", re.IGNORECASE)


class ArgumentParser(argparse.ArgumentParser):
    """argparse with one-line errors: ``pihyst: error: argument --seed: ... (see 'pihyst
    simulate --help')``, exit status 2; a negative number in scientific notation
    (``--u-min -1e-3``) is an option's value, not an unknown option (every subcommand's
    parser is of this class: ``add_subparsers`` makes its parsers of the parent's class)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message):
        self.exit(EXIT_USER_ERROR,
                  f"pihyst: error: {one_line(message)} (see '{self.prog} --help')\n")


# ----------------------------------------------------------------------------- option types
def _float(text):
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None


def number(text):
    """A finite number."""
    x = _float(text)
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return x


def positive_number(text):
    """A finite number > 0."""
    x = number(text)
    if not x > 0:
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text!r}")
    return x


def open_fraction(text):
    """A number strictly between 0 and 1."""
    x = number(text)
    if not 0 < x < 1:
        raise argparse.ArgumentTypeError(f"must be between 0 and 1 (exclusive), got {text!r}")
    return x


def _whole(text):
    try:
        return int(text, 10)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number, got {text!r}") from None


def count(lowest=1, highest=None):
    """A whole number in [lowest, highest] (highest: a resource limit, said in the error)."""
    def parse(text):
        n = _whole(text)
        if n < lowest:
            raise argparse.ArgumentTypeError(f"must be at least {lowest}, got {text}")
        if highest is not None and n > highest:
            raise argparse.ArgumentTypeError(f"must be at most {highest:,}, got {text}")
        return n
    parse.__name__ = "count"
    return parse


def seed(text):
    """A random seed: a whole number >= 0 (any size)."""
    n = _whole(text)
    if n < 0:
        raise argparse.ArgumentTypeError(f"must be a whole number >= 0, got {text}")
    return n


# ----------------------------------------------------------------------------- running
def run_command(run, args, *, debug=False):
    """Run a command's ``run(args)`` and turn what it raises into the exit status and
    one stderr line of docs/errors.md."""
    try:
        with warnings.catch_warnings(), _TerminationHandled():
            warnings.showwarning = _show_warning
            refuse_outputs_over_inputs(args)
            run(args)
            sys.stdout.flush()  # a closed pipe shows here, not at interpreter exit
    except BrokenPipeError:
        _detach_stdout()
        return EXIT_OK
    except Terminated as err:
        _say(f"pihyst: terminated ({err})")
        return EXIT_TERMINATED
    except KeyboardInterrupt:
        _say("pihyst: interrupted")
        return EXIT_INTERRUPTED
    except USER_ERRORS as err:
        _say(f"pihyst: error: {one_line(err)}")
        return EXIT_USER_ERROR
    except MemoryError:
        _say("pihyst: error: not enough memory for this input; use a shorter record or "
             "coarser options")
        return EXIT_USER_ERROR
    except OSError as err:
        _say(f"pihyst: error: {one_line(os_error_message(err))}")
        return EXIT_USER_ERROR
    except Exception as err:  # noqa: BLE001 - an unexpected error is a bug, said as one
        if debug:
            traceback.print_exc()
        from pihyst._version import __version__
        how = "the traceback above" if debug else "the output of the same command with --debug"
        _say(f"pihyst: internal error: {type(err).__name__}: {one_line(err)} -- this is a bug "
             f"in pihyst {__version__}, not in your input; please report it with the command "
             f"line and {how} to {BUG_REPORTS}")
        return EXIT_BUG
    return EXIT_OK


def check_output(path):
    """Fail now, before any work, if the output ``path`` cannot be written (its folder
    does not exist, it is a folder): the error names the path."""
    from pihyst._atomic import check_target
    check_target(path)


#: the attributes of a command's arguments that name what it writes, and their option
OUTPUTS = {"output": "-o", "out": "--out", "figure": "--figure"}


def refuse_outputs_over_inputs(args):
    """UsageError, before anything is read, if an output path of ``args`` (``-o``,
    ``--out``, ``--figure``) is empty, or is one of the command's input files: the same
    file by device and inode, so also through a symbolic or hard link (every other
    argument that names an existing file is an input). A report's ``--out`` folder may
    not hold its input either: the report's files would replace it. Terminals and other
    character devices (``/dev/null``, ``/dev/stdout``) may be both."""
    values = getattr(args, "__dict__", None) or {}
    inputs = []
    for key, value in values.items():
        if key in OUTPUTS or key == "run":
            continue
        for item in value if isinstance(value, (list, tuple)) else [value]:
            if isinstance(item, str) and item:
                st = _stat(item)
                if st is not None and not stat.S_ISDIR(st.st_mode):
                    inputs.append((item, st))
    for key, option in OUTPUTS.items():
        path = values.get(key)
        if not isinstance(path, str):
            continue
        if path == "":
            raise UsageError(f"argument {option}: an empty file name ('')")
        st = _stat(path)
        if st is None or stat.S_ISCHR(st.st_mode) or (key == "out" and
                                                       not stat.S_ISDIR(st.st_mode)):
            continue          # (a folder option on a file: the command says so itself)
        for item, ist in inputs:
            if stat.S_ISDIR(st.st_mode):
                if key == "out" and _inside(item, path):
                    raise UsageError(f"{option} {path}: holds the input {item}, which the "
                                     "report's files could replace; choose another folder")
            elif (ist.st_dev, ist.st_ino) == (st.st_dev, st.st_ino):
                same = "is" if os.path.abspath(item) == os.path.abspath(path) else \
                    "is the same file as"
                raise UsageError(f"{option} {path}: {same} the input {item}; refusing to "
                                 "overwrite an input (choose another output file)")


def _stat(path):
    try:
        return os.stat(path)
    except (OSError, ValueError):
        return None


def _inside(item, folder):
    return os.path.dirname(os.path.realpath(item)) == os.path.realpath(folder)


def os_error_message(err):
    """``FILE: reason`` for an OSError (the file the user named)."""
    reason = err.strerror or str(err)
    if err.filename is not None:
        return f"{os.fsdecode(err.filename)}: {reason}"
    return reason


def _say(line):
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):   # stderr closed too: nothing more can be said
        pass


def _show_warning(message, category, filename, lineno, file=None, line=None):
    prefix = "" if issubclass(category, PihystWarning) else f"{category.__name__}: "
    _say(f"pihyst: warning: {prefix}{one_line(message)}")


def _detach_stdout():
    """Point stdout at /dev/null so that the interpreter's final flush of a closed pipe
    does not print 'Broken pipe' on the way out."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # not a real file (e.g. in tests)
        pass


def step_printer(prefix):
    """A progress callable that prints each step to stderr as ``PREFIX: step (time)``,
    on a terminal or with PIHYST_PROGRESS=1 (PIHYST_PROGRESS=0: never); else None."""
    wanted = os.environ.get("PIHYST_PROGRESS")
    if wanted == "0" or (wanted != "1" and not sys.stderr.isatty()):
        return None

    def say(line):
        print(f"{prefix}: {line}", file=sys.stderr, flush=True)
    return say
