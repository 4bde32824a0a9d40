"""The demo's report, made once for the tests of this folder (it takes a few seconds)."""

import pytest

from pihyst.study import paper_study, write_report


@pytest.fixture(scope="session")
def demo(tmp_path_factory):
    """``(study, out_dir, files, progress_lines)`` of the paper's study at 2 s steps."""
    study = paper_study(dt=2.0, variants=True, progress=None)
    out = tmp_path_factory.mktemp("demo")
    lines = []
    files = write_report(study, out, command="pihyst demo (test)", progress=lines.append)
    return study, out, files, lines
