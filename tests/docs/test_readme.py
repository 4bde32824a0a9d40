"""Every Python example of the README runs as written (in order, in one namespace, in a
scratch folder holding a copy of examples/). The few names the text leaves to the reader
(a measured record u, y, a second one u2, y2 and a desired trajectory y_desired) are provided first."""

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
README = REPO / "README.md"


def _python_blocks():
    text = README.read_text(encoding="utf-8")
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


@pytest.mark.skipif(not README.exists(), reason="runs from a source checkout")
def test_every_python_example_of_the_readme_runs(tmp_path, monkeypatch, capsys):
    blocks = _python_blocks()
    assert blocks, "the README has Python examples"
    shutil.copytree(REPO / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    from pihyst.sim import make_plant
    from pihyst.sim.signals import decaying_triangles

    t, u = decaying_triangles(dt=1.0)
    y = make_plant("paper-beam").run(u, t)
    t2, u2 = decaying_triangles(n_triangles=3, ratio=0.7, dt=1.0)
    y2 = make_plant("paper-beam", seed=1).run(u2, t2)
    namespace = {"u": u, "y": y, "t": t, "u2": u2, "y2": y2,
                 "y_desired": np.interp(np.arange(300.0), [0, 150, 299], [0.0, 30.0, 5.0])}
    for i, block in enumerate(blocks):
        try:
            exec(compile(block, f"README.md python block {i + 1}", "exec"), namespace)
        except Exception as err:  # report which block, with the error
            pytest.fail(f"README python block {i + 1} fails: {type(err).__name__}: {err}\n"
                        f"{block}")
