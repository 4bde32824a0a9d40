# The one thing pyproject.toml cannot express: the C extension.
import glob

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

# -std=c99 turns off FMA contraction (ISO mode); -ffp-contract=fast turns it back on.
# GCC's spelling, which clang and MinGW share (compiler types unix, mingw32, cygwin).
GCC_ARGS = ["-std=c99", "-O3", "-ffp-contract=fast"]
# MSVC: its C11 dialect (the core compiles there: make -C csrc portable), no contraction
MSVC_ARGS = ["/std:c11", "/O2"]


def compile_args(compiler_type):
    """The extra compile arguments for a distutils compiler type: GCC's flags only for
    compilers that take them, MSVC's for MSVC, none for any other."""
    if compiler_type in ("unix", "mingw32", "cygwin"):
        return list(GCC_ARGS)
    if compiler_type == "msvc":
        return list(MSVC_ARGS)
    return []


class BuildExt(build_ext):
    """build_ext that gives each extension the flags of the compiler actually used."""

    def build_extensions(self):
        args = compile_args(self.compiler.compiler_type)
        for ext in self.extensions:
            ext.extra_compile_args = args
        super().build_extensions()


core = Extension(
    "pihyst._core",
    sources=["src/pihyst/_core.pyx", *sorted(glob.glob("csrc/pihyst_*.c"))],
    include_dirs=["csrc"],
    depends=sorted(glob.glob("csrc/pihyst*.h")),
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
)
# the default install's fast reader and writer of numeric text (no pyarrow needed)
fastcsv = Extension("pihyst.io._fastcsv", sources=["src/pihyst/io/_fastcsv.pyx"])
# the identification's one-pass turning-point search (its plain twin: pihyst._reference)
turning = Extension("pihyst.identify._turning", sources=["src/pihyst/identify/_turning.pyx"])

if __name__ == "__main__":  # setuptools runs it so; tests/test_setup.py only reads it
    from Cython.Build import cythonize  # a build requirement (pyproject.toml), not a runtime one

    setup(ext_modules=cythonize([core, boucwen, fastcsv, turning], language_level=3),
          cmdclass={"build_ext": BuildExt})
