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
# the Bouc-Wen model and compensator (csrc/pihyst_boucwen.h, with creep:
# pihyst_bw_creep.h), bound on their own
boucwen = Extension(
    "pihyst._boucwen_core",
    sources=["src/pihyst/_boucwen_core.pyx", "csrc/pihyst_boucwen.c",
             "csrc/pihyst_boucwen_f32.c", "csrc/pihyst_model.c",
             # with creep: the lags (whose PI compensator needs the PI core's inverse)
             "csrc/pihyst_creep.c", "csrc/pihyst_bw_creep.c", "csrc/pihyst_inverse.c"],
    include_dirs=["csrc"],
    depends=sorted(glob.glob("csrc/pihyst*.h")),
    extra_compile_args=["-std=c99", "-O3", "-ffp-contract=fast"],
)
setup(ext_modules=cythonize([core, boucwen], language_level=3))
