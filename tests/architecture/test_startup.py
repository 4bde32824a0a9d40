"""A fast start: ``import pihyst`` and ``pihyst --help`` load neither SciPy's heavy
sub-packages nor matplotlib, nor the optional Dask and python-control (they are imported
where they are used). The time itself is
measured in benchmarks/bench_startup.py, not asserted here."""

import subprocess
import sys

import pytest

HEAVY = ("scipy.optimize", "scipy.signal", "scipy.linalg", "scipy.special", "matplotlib",
         "dask", "distributed", "control")


@pytest.mark.parametrize("code", [
    "import pihyst",
    "import pihyst.cli",
    "import sys; sys.argv = ['pihyst', '--help']\n"
    "from pihyst.cli import main\n"
    "try:\n    main()\nexcept SystemExit:\n    pass",
])
def test_start_loads_no_heavy_module(code):
    probe = code + "\nimport sys\nprint('LOADED:' + ' '.join(m for m in %r if m in sys.modules))" \
        % (HEAVY,)
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         check=True).stdout.splitlines()[-1]
    assert out == "LOADED:", f"loaded at start: {out}"
