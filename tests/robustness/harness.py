"""Running pihyst's command line in-process on the malformed-input corpus and judging
the outcome by the rules of docs/errors.md:

- exit status 0 or 2 (never a traceback, never another status);
- on status 2, exactly one line on stderr, ``pihyst: error: ...``, and no output file;
- never a leftover temporary file beside the output.

Used by the tests of this folder and by ``python tests/robustness/count.py``, which runs
the whole corpus against every command and prints the counts.
"""

import contextlib
import io
import json
import os
import traceback
import warnings
from dataclasses import dataclass, field

from pihyst.cli import main

HERE = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(HERE, "corpus")
REPO = os.path.dirname(os.path.dirname(HERE))

with open(os.path.join(CORPUS, "manifest.json")) as _f:
    MANIFEST = json.load(_f)

GOOD_MODEL = os.path.join(CORPUS, "model", "ok-classical.json")
VOLTS = os.path.join(CORPUS, "input", "volts.csv")
DESIRED = os.path.join(CORPUS, "input", "desired.csv")
LOOP = os.path.join(CORPUS, "csv", "ok-loop.csv")


@dataclass
class Outcome:
    argv: list
    status: object            # int, or None when an exception escaped
    out: str
    err: str
    crash: str = ""           # the traceback of an escaped exception
    problems: list = field(default_factory=list)


def run(argv):
    """``pihyst ARGV`` in this process, as a user's shell would see it."""
    out, err = io.StringIO(), io.StringIO()
    crash = ""
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            warnings.catch_warnings():
        warnings.resetwarnings()        # as in a plain interpreter, not pytest's "error"
        warnings.simplefilter("default")
        try:
            status = main([str(a) for a in argv])
        except SystemExit as exc:       # argparse
            status = exc.code if isinstance(exc.code, int) else 2
        except BaseException:           # noqa: BLE001 - a traceback is what we count
            status, crash = None, traceback.format_exc()
    return Outcome(list(argv), status, out.getvalue(), err.getvalue(), crash)


def argv_for(command, kind, path, output):
    """The command line that feeds corpus file ``path`` (a model or a record) to
    ``command``, writing ``output``."""
    if kind == "model":
        other = VOLTS if command == "predict" else DESIRED
        return [command, path, other, "-o", output] + (
            ["--saturate"] if command in ("compensate", "track") else [])
    if command == "fit":
        return ["fit", path, "-o", output]
    if command == "report":
        return ["report", path, "--out", output]
    # (a corpus record as a desired trajectory is often out of the model's reach: the
    # corpus is about reading it, so saturating is intended)
    return [command, GOOD_MODEL, path, "-o", output] + (
        ["--saturate"] if command in ("compensate", "track") else [])


def judge(outcome, expect, output, says=None, warns=None):
    """Problems with an outcome (an empty list when it follows the rules)."""
    p = outcome.problems
    if outcome.status is None:
        p.append("traceback: " + outcome.crash.strip().splitlines()[-1])
        return p
    if outcome.status not in (0, 2):
        p.append(f"exit status {outcome.status}")
    if expect is not None and outcome.status != expect:
        p.append(f"exit status {outcome.status}, expected {expect}: {outcome.err.strip()!r}")
    lines = outcome.err.splitlines()
    if outcome.status == 2:
        if len(lines) != 1 or not lines[0].startswith("pihyst: error: "):
            p.append(f"stderr is not one error line: {outcome.err[:300]!r}")
        if says and says not in outcome.err:
            p.append(f"error does not say {says!r}: {outcome.err.strip()!r}")
        if os.path.exists(output):
            p.append("output written despite the error")
    if outcome.status == 0:
        stray = [x for x in lines if not x.startswith("pihyst: warning: ")]
        if stray:
            p.append(f"unexpected stderr on success: {stray[:3]}")
        if warns and warns not in outcome.err:
            p.append(f"no warning saying {warns!r}: {outcome.err.strip()!r}")
    folder = os.path.dirname(os.path.abspath(output))
    if os.path.isdir(folder):
        left = [f for f in os.listdir(folder) if f.startswith(".pihyst-")]
        if left:
            p.append(f"temporary files left: {left}")
    return p


def corpus_cases(commands=("predict", "fit", "compensate", "track")):
    """(name, kind, command, expected status, says, warns) for every corpus file and
    command that reads its kind."""
    for name, entry in sorted(MANIFEST.items()):
        kind = name.split("/")[0]
        if kind == "input":
            continue
        for command in commands:
            if command not in entry["expect"] and not (command == "report" and kind == "csv"):
                continue
            expect = entry["expect"].get(command)
            says = entry.get("says")
            if isinstance(says, dict):
                says = says.get(command)
            if command == "report":
                # report reads what fit reads, and time_s as predict and compensate do; its
                # own checks word some errors differently, so only the status is judged
                e = entry["expect"]
                expect = 2 if e["fit"] == 2 or e["predict"] == e["compensate"] == 2 else 0
                says = None
            yield (name, kind, command, expect, says if expect == 2 else None,
                   entry.get("warns", {}).get(command))
