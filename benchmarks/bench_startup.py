"""Start-up time of the command line: `pihyst --help` and `pihyst --version` against a bare
Python interpreter and `import numpy`, measured in the same run (best of 7).

Target (the architecture issue): `pihyst --help` under 0.5 s on the project's 2-core machine.
"""

import shutil
import subprocess
import sys
import time
from pathlib import Path


def best_of(cmd, repeat=7):
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        best = min(best, time.perf_counter() - t0)
    return best


def main():
    pihyst = shutil.which("pihyst") or str(Path(sys.executable).with_name("pihyst"))
    bare = best_of([sys.executable, "-c", "pass"])
    numpy = best_of([sys.executable, "-c", "import numpy"])
    print(f"{'command':<28}{'best (s)':>10}{'x bare python':>16}")
    for label, cmd in (("python -c pass", None), ("python -c 'import numpy'", None),
                       ("pihyst --version", [pihyst, "--version"]),
                       ("pihyst --help", [pihyst, "--help"])):
        t = bare if label.endswith("pass") else numpy if "numpy" in label else best_of(cmd)
        print(f"{label:<28}{t:>10.3f}{t / bare:>16.1f}")


if __name__ == "__main__":
    main()
