"""`make data` (the README's documented place for the measured sets): each set's folder,
with its LICENSE and SOURCE.md, linked into data/ from $PIHYST_DATA, else from
../shared/data beside the clone; without either, one line saying what to set."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

MAKEFILE = Path(__file__).resolve().parents[2] / "Makefile"
pytestmark = pytest.mark.skipif(not MAKEFILE.exists() or shutil.which("make") is None,
                                reason="runs from a source checkout with make")


def make_data(cwd, **env):
    shutil.copy(MAKEFILE, cwd / "Makefile")
    environ = {k: v for k, v in os.environ.items() if k != "PIHYST_DATA"} | env
    return subprocess.run(["make", "-s", "data"], cwd=cwd, env=environ, capture_output=True,
                          text=True, timeout=60)


def a_set(root, name):
    (root / name).mkdir(parents=True)
    for f in ("LICENSE", "SOURCE.md", "record.csv"):
        (root / name / f).write_text(f"{name} {f}\n")


def test_sets_from_pihyst_data_are_linked_with_their_licences(tmp_path):
    sets, clone = tmp_path / "sets", tmp_path / "clone"
    a_set(sets, "stack-a")
    a_set(sets, "mirror-b")
    clone.mkdir()
    proc = make_data(clone, PIHYST_DATA=str(sets))
    assert proc.returncode == 0, proc.stderr
    for name in ("stack-a", "mirror-b"):
        link = clone / "data" / name
        assert link.is_symlink() and link.resolve() == (sets / name).resolve()
        assert (link / "LICENSE").read_text() == f"{name} LICENSE\n"
    assert proc.stdout.count("make: data/") == 2


def test_the_shared_folder_beside_the_clone_is_the_default(tmp_path):
    a_set(tmp_path / "shared" / "data", "stack-a")
    clone = tmp_path / "clone"
    clone.mkdir()
    assert make_data(clone).returncode == 0
    assert (clone / "data" / "stack-a" / "SOURCE.md").exists()


def test_without_any_set_it_says_what_to_set(tmp_path):
    clone = tmp_path / "clone"
    clone.mkdir()
    proc = make_data(clone)
    assert proc.returncode != 0
    assert "set PIHYST_DATA" in proc.stdout + proc.stderr
    assert not (clone / "data").exists()
