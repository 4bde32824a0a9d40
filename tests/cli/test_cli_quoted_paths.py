"""Every examples/ path that the README, the docs and the commands' --help texts quote
exists, and the README's `pihyst.SUBPACKAGE.name` calls work after a plain
``import pihyst``."""

import argparse
import re
import subprocess
import sys
from pathlib import Path

import pytest

from pihyst.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
QUOTED = re.compile(r"examples/[A-Za-z0-9_./-]*[A-Za-z0-9_/]")


def help_texts(parser):
    """The description, epilog and option help of a parser and all its sub-commands."""
    yield parser.description or ""
    yield parser.epilog or ""
    for action in parser._actions:   # argparse has no public walk over sub-commands
        yield action.help or ""
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                yield from help_texts(sub)


def quoted_paths(text):
    return set(QUOTED.findall(text))


def test_help_texts_quote_existing_examples():
    paths = set().union(*(quoted_paths(t) for t in help_texts(build_parser())))
    assert "examples/rig/desired_triangle.csv" in paths   # the walk reaches sub-commands
    assert [p for p in sorted(paths) if not (ROOT / p).exists()] == []


@pytest.mark.parametrize("doc", ["README.md", *sorted(
    str(p.relative_to(ROOT)) for p in (ROOT / "docs").rglob("*.md"))])
def test_docs_quote_existing_examples(doc):
    paths = quoted_paths((ROOT / doc).read_text(encoding="utf-8"))
    assert [p for p in sorted(paths) if not (ROOT / p).exists()] == []


def test_readme_subpackage_calls_work_after_import_pihyst():
    code = ("import numpy as np, pihyst\n"
            "t, u = pihyst.sim.signals.triangle(period_s=10.0, dt=0.5)\n"
            "y = pihyst.sim.make_plant('paper-beam', seed=0).run(u, t)\n"
            "assert y.shape == u.shape\n"
            "assert callable(pihyst.dynamics.fit_hammerstein)\n"
            "assert 'sim' in dir(pihyst)\n"
            "try:\n    pihyst.no_such_thing\n"
            "except AttributeError as err:\n    print(err)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out == "module 'pihyst' has no attribute 'no_such_thing'\n"
