"""setup.py gives GCC's flags only to compilers that take them (GCC, clang, MinGW) and
MSVC its own: the flags each compiler type gets, and that build_ext applies them."""

import runpy
from pathlib import Path
from types import SimpleNamespace

import pytest

SETUP = Path(__file__).resolve().parents[1] / "setup.py"
pytestmark = pytest.mark.skipif(not SETUP.exists(), reason="runs from a source checkout")


@pytest.fixture(scope="module")
def setup_py():
    return runpy.run_path(str(SETUP), run_name="setup_py_under_test")


def test_gcc_like_compilers_get_gcc_flags(setup_py):
    for compiler_type in ("unix", "mingw32", "cygwin"):
        assert setup_py["compile_args"](compiler_type) == ["-std=c99", "-O3", "-ffp-contract=fast"]


def test_msvc_gets_no_gcc_flag(setup_py):
    args = setup_py["compile_args"]("msvc")
    assert args and all(a.startswith("/") for a in args)
    assert "/std:c11" in args


def test_unknown_compiler_gets_none(setup_py):
    assert setup_py["compile_args"]("bcpp") == []


def test_build_ext_applies_the_compilers_flags(setup_py, monkeypatch):
    build_ext = setup_py["BuildExt"]
    exts = [setup_py["core"], setup_py["boucwen"]]
    for compiler_type, flag in (("msvc", "/O2"), ("unix", "-O3")):
        cmd = build_ext.__new__(build_ext)
        cmd.compiler = SimpleNamespace(compiler_type=compiler_type)
        cmd.extensions = exts
        monkeypatch.setattr(build_ext.__mro__[1], "build_extensions", lambda self: None)
        cmd.build_extensions()
        assert all(flag in e.extra_compile_args for e in exts)
        assert all(len({a[0] for a in e.extra_compile_args}) == 1 for e in exts)
