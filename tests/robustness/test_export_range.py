"""export --float refuses a value that float cannot hold (issue 24, item 9): one line
naming the value and where it is, exit status 2, no header written (it would hold
``inf``, which does not compile)."""

import json

import pytest
from harness import run


@pytest.mark.parametrize("model, where", [
    ({"family": "classical", "thresholds": [0, 10, 30, 150],
      "weights": [0.008, 1e39, 0.019, 0.582]}, "weights[1] = 1e+39"),
    ({"family": "classical", "thresholds": [0, 10, 30, 150],
      "weights": [0.008, 0.2, 0.019, 0.582], "offset": -5e38}, "offset = -5e+38"),
])
def test_export_float_refuses_values_beyond_float(tmp_path, model, where):
    path = tmp_path / "m.json"
    path.write_text(json.dumps(model))
    out = tmp_path / "m.h"
    outcome = run(["export", str(path), "--c", "--float", "-o", str(out)])
    assert outcome.status == 2, outcome.err
    line = outcome.err.strip()
    assert line.startswith(f"pihyst: error: {path}: ") and where in line, line
    assert "beyond the range of float" in line and "\n" not in line
    assert not out.exists()
    # double precision holds it
    assert run(["export", str(path), "--c", "-o", str(out)]).status == 0
    assert "inf" not in out.read_text()
