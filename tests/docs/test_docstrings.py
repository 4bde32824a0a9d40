"""Every public callable of pihyst is documented in numpydoc form: numpydoc's own
validation (numpydoc.validate) over the names of each public package's ``__all__``, the
classes' public methods with them.

The checks (numpydoc's codes): GL08 a docstring; PR01 every parameter documented, PR02
no documented parameter that does not exist (a misnamed one), PR10 ``name : type`` with
its spaces, RT01 a Returns section where something is returned, SS01 a summary line,
EX01 an Examples section (its doctests run in ``make test``: ``pytest --doctest-modules``),
GL07 the sections in numpydoc's order.

Every public package is checked, the rig (its PyMeasure classes when PyMeasure is
installed, as in the test extra) and the command line's ``pihyst.cli`` included.
"""

import importlib
import importlib.util
import inspect

import pytest

numpydoc_validate = pytest.importorskip("numpydoc.validate")

#: every public package whose API is checked
CHECKED_MODULES = ("pihyst", "pihyst.model", "pihyst.inverse", "pihyst.sim",
                   "pihyst.sim.signals", "pihyst.metrics", "pihyst.paper", "pihyst.exceptions",
                   "pihyst.control", "pihyst.fleet", "pihyst.study", "pihyst.identify",
                   "pihyst.learn", "pihyst.io", "pihyst.dynamics", "pihyst.rig",
                   "pihyst.rig.sim", "pihyst.rig.pymeasure", "pihyst.cli")
#: the packages of an optional extra, checked when the extra is installed
EXTRAS = {"pihyst.rig.pymeasure": "pymeasure"}
CHECKS = ("GL07", "GL08", "PR01", "PR02", "PR10", "RT01", "SS01", "EX01")


def _owner(obj):
    return getattr(obj, "__module__", "") or ""


def _public_callables():
    """(qualified name to validate, object) for every public function, class and public
    method of a class, over CHECKED_MODULES; each object once, under its first name."""
    seen = set()
    out = []
    for module_name in CHECKED_MODULES:
        extra = EXTRAS.get(module_name)
        if extra is not None and importlib.util.find_spec(extra) is None:
            continue
        module = importlib.import_module(module_name)
        names = getattr(module, "__all__", None)
        if names is None:
            names = [n for n, v in vars(module).items()
                     if not n.startswith("_") and inspect.isfunction(v)
                     and v.__module__ == module_name]
        for name in names:
            obj = getattr(module, name)
            if not (inspect.isclass(obj) or inspect.isfunction(obj)):
                continue
            if id(obj) in seen:
                continue
            seen.add(id(obj))
            out.append((f"{module_name}.{name}", obj))
            if inspect.isclass(obj) and not issubclass(obj, BaseException):
                for attr, member in inspect.getmembers(obj):
                    # functions, and class methods (bound to the class)
                    member = getattr(member, "__func__", member)
                    if attr.startswith("_") or not inspect.isfunction(member) \
                            or not _owner(member).startswith("pihyst") or id(member) in seen:
                        continue
                    seen.add(id(member))
                    out.append((f"{module_name}.{name}.{attr}", member))
    return out


PUBLIC = _public_callables()


def test_the_public_api_is_found():
    names = {n for n, _ in PUBLIC}
    assert "pihyst.ClassicalPI" in names and "pihyst.ClassicalPI.predict" in names
    assert "pihyst.compensate" in names and "pihyst.metrics.rms_error" in names
    assert len(PUBLIC) > 100
    assert "pihyst.rig.Rig.run" in names and "pihyst.cli.main" in names
    if importlib.util.find_spec("pymeasure") is not None:
        assert "pihyst.rig.pymeasure.RecordProcedure" in names


def _problems(name):
    result = numpydoc_validate.validate(name)
    return [f"{code} {message}" for code, message in result["errors"] if code in CHECKS]


@pytest.mark.parametrize("name", [n for n, _ in PUBLIC])
def test_public_callable_is_documented_in_numpydoc_form(name):
    problems = _problems(name)
    assert not problems, f"{name}:\n  " + "\n  ".join(problems)


@pytest.mark.parametrize("name", [n for n, obj in PUBLIC if inspect.isclass(obj)])
def test_constructor_names_its_keywords(name):
    """help() and IDEs show every keyword of a public constructor: no **kwargs."""
    obj = dict(PUBLIC)[name]
    if issubclass(obj, BaseException):
        return
    params = inspect.signature(obj).parameters.values()
    hidden = [p.name for p in params if p.kind is inspect.Parameter.VAR_KEYWORD]
    assert not hidden, f"{name}(..., **{hidden[0]}) hides its keywords"
