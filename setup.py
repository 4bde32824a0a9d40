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
# the default install's fast reader and writer of numeric text (no pyarrow needed)
fastcsv = Extension("pihyst.io._fastcsv", sources=["src/pihyst/io/_fastcsv.pyx"],
                    extra_compile_args=["-O3"])
setup(ext_modules=cythonize([core, boucwen, fastcsv], language_level=3))
