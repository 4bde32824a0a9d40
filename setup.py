# The one thing pyproject.toml cannot express: the C extension.
import glob

from Cython.Build import cythonize
from setuptools import Extension, setup

core = Extension(
    "pihyst._core",
    sources=["src/pihyst/_core.pyx", *sorted(glob.glob("csrc/pihyst_*.c"))],
    include_dirs=["csrc"],
    depends=sorted(glob.glob("csrc/pihyst*.h")),
    # -std=c99 turns off FMA contraction (ISO mode); -ffp-contract=fast turns it back on.
    extra_compile_args=["-std=c99", "-O3", "-ffp-contract=fast"],
)
setup(ext_modules=cythonize([core], language_level=3))
