"""Negative numbers in scientific notation (-1e-3, -2.5E+8, -1e308) are option values on
every subcommand, not unknown options: in range they are used, out of range they get the
option's one-line range error (exit status 2), never argparse's 'expected one argument'."""

import argparse
import contextlib
import io
import os
import shutil
from pathlib import Path

import pytest
from harness import DESIRED, GOOD_MODEL, LOOP, VOLTS, judge, run

import pihyst
from pihyst.cli import build_parser
from pihyst.cli.errors import NEGATIVE_NUMBER

NEGATIVES = ("-1e-3", "-2.5E+8", "-1e308", "-1e400", "-.5e1", "-3.", "-inf", "-10,150")


def _options(parser, path=()):
    """(subcommand path, option string) of every option that takes one value."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _options(sub, path + (name,))
        elif action.option_strings and action.nargs is None and \
                isinstance(action, (argparse._StoreAction, argparse._AppendAction)):
            yield path, action.option_strings[-1]


OPTIONS = sorted(set(_options(build_parser())))


def test_every_subcommand_is_walked():
    commands = {path[0] for path, _ in OPTIONS}
    assert {"predict", "fit", "fit-many", "validate", "simulate", "compensate", "track",
            "demo", "report", "export", "rig"} <= commands
    assert ("rig", "record") in {path for path, _ in OPTIONS}


@pytest.mark.parametrize("value", ["-1", "-1.5", "-.5", "-1e-3", "-1E3", "-2.5e+8", "-3.e2",
                                   "-10,150", "-1e-3, 2", "-inf", "-NaN", "-1e"])
def test_the_matcher_takes_negative_numbers_and_lists(value):
    assert NEGATIVE_NUMBER.match(value)


@pytest.mark.parametrize("value", ["-o", "-h", "--u-min", "-e3", "-x1", "-1.csv", "-", "--"])
def test_the_matcher_leaves_options(value):
    assert not NEGATIVE_NUMBER.match(value)


@pytest.mark.parametrize("path, option", OPTIONS, ids=[" ".join(p) + " " + o
                                                         for p, o in OPTIONS])
def test_a_negative_number_is_the_options_value(path, option):
    parser = build_parser()   # parsed only: nothing runs
    for value in NEGATIVES:
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            try:
                parser.parse_args([*path, option, value])
            except SystemExit:
                pass
        text = err.getvalue()
        assert "expected one argument" not in text, text
        assert "unrecognized arguments" not in text, text
        assert len(text.splitlines()) <= 1, text


# every numeric option of the commands that compute, with a tiny and a huge negative
# value: a value the option allows runs (0), one it does not is one line (2)
BASES = {
    "predict": ["predict", GOOD_MODEL, VOLTS, "-o", "{out}"],
    "compensate": ["compensate", GOOD_MODEL, DESIRED, "-o", "{out}"],
    "track": ["track", GOOD_MODEL, DESIRED, "-o", "{out}"],
    "validate": ["validate", GOOD_MODEL, LOOP],
    "simulate": ["simulate", "-o", "{out}", "--period", "20", "--dt", "1"],
    "fit": ["fit", LOOP, "-o", "{out}", "--model", "classical", "--thresholds", "0,20,40"],
    "rig record": ["rig", "record", "--config", "{config}", "--period", "2", "--cycles",
                   "1", "-o", "{out}"],
    "rig emulate": ["rig", "emulate", "--config", "{config}"],
}
# the emulated rig the README's rig commands use
RIG_CONFIG = Path(__file__).resolve().parents[2] / "examples" / "rig" / "emulated.toml"


def write_rig_config(folder):
    path = folder / "rig.toml"
    shutil.copyfile(RIG_CONFIG, path)
    return str(path)


def _numeric_options():
    parser = build_parser()
    found = {}

    def walk(p, path):
        for a in p._actions:
            if isinstance(a, argparse._SubParsersAction):
                for name, sub in a.choices.items():
                    walk(sub, path + (name,))
            elif a.option_strings and a.type is not None and a.type is not str:
                found.setdefault(" ".join(path), []).append(a.option_strings[-1])
    walk(parser, ())
    return [(base, option) for base in BASES for option in found.get(base, [])]


@pytest.mark.parametrize("base, option", _numeric_options())
@pytest.mark.parametrize("value", ["-1e-3", "-1e308"])
def test_a_negative_number_runs_or_is_one_line(tmp_path, base, option, value):
    out = str(tmp_path / "out.csv")
    config = write_rig_config(tmp_path) if base.startswith("rig") else ""
    argv = [a.replace("{out}", out).replace("{config}", config) for a in BASES[base]]
    outcome = run(argv + [option, value])
    assert "expected one argument" not in outcome.err
    problems = judge(outcome, None, out)
    assert not problems, f"pihyst {' '.join(outcome.argv)}: {problems}"
    if outcome.status == 2 and option not in ("--voltage-gain", "--displacement-gain",
                                              "--skip-until"):
        assert option in outcome.err or value.lstrip("-") in outcome.err or \
            f"{float(value):g}" in outcome.err, outcome.err
    if outcome.status == 0:
        assert os.path.exists(out) or base == "validate"


@pytest.mark.parametrize("value, says", [
    ("nan", "must be a finite number"), ("inf", "must be a finite number"),
    ("-1", "must be a positive number"), ("1e308", "must be at most 9.22337e+09 s"),
])
def test_rig_emulate_duration_is_checked_as_parsed(tmp_path, value, says):
    # a float option once: inf and 1e308 were an OverflowError (internal error), nan and
    # -1 ran and stopped at once
    outcome = run(["rig", "emulate", "--config", write_rig_config(tmp_path),
                   "--duration", value])
    assert outcome.status == 2 and len(outcome.err.splitlines()) == 1
    assert f"argument --duration: {says}" in outcome.err


def test_a_list_option_may_start_with_a_negative_number(tmp_path):
    out = tmp_path / "m.json"
    outcome = run(["fit", LOOP, "-o", str(out), "--model", "classical", "--thresholds",
                   "0,20,40", "--input-range", "-1e1,150"])
    assert outcome.status == 0, outcome.err
    assert pihyst.load_model(out).input_range == (-10.0, 150.0)
    outcome = run(["fit", LOOP, "-o", str(out), "--thresholds", "-1e-3,2"])
    assert outcome.status == 2 and "--thresholds" in outcome.err
    assert "expected one argument" not in outcome.err
