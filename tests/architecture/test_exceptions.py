"""pihyst raises its own exceptions (docs/errors.md): no module raises a bare ValueError,
RuntimeError or TypeError, and no ``assert`` checks an argument (asserts vanish under
``python -O``). The few raises left are internal consistency checks that no input
reaches (their callers validate first), listed here with the reason."""

import ast
from pathlib import Path

import numpy as np
import pytest

import pihyst
from pihyst.exceptions import InvalidArgumentError
from pihyst.sim._boucwen import BoucWen

SRC = Path(pihyst.__file__).parent
BARE = {"ValueError", "RuntimeError", "TypeError", "Exception"}

# (module, message start): internal checks behind validated callers
INTERNAL = {
    ("identify/_qp.py", "{name} contains NaN"),              # fit checks the record first
    ("identify/_qp.py", "A_eq must be"),
    ("identify/_qp.py", "equality constraints must be finite"),
    ("identify/_qp.py", "H must be"),
    ("identify/_qp.py", "H and g must be finite"),
    ("identify/_subsets.py", "cannot choose"),                # sizes come from the search
    ("io/_numbers.py", "{shown} is too large"),               # turned into CSVError by callers
    ("io/_numbers.py", "missing value"),
    ("io/_numbers.py", "{shown} is not a finite number"),
    ("io/_numbers.py", "{shown} is not a number (a decimal comma?"),
    ("io/_numbers.py", "{shown} is not a number (this file"),
    ("io/_numbers.py", "{shown} is not a number"),
    ("io/_array_sources.py", "unknown record kind"),          # kinds come from a fixed table
    ("sim/_population.py", "no Bouc-Wen parameters"),         # a draw that cannot fail in 200
    ("cli/rig.py", "expected DEVICE:KIND"),                   # caught two lines below
    # metrics is layer 0 beside exceptions and may not import it (docs/architecture.md):
    # its two checks stay ValueErrors, which InvalidArgumentError is too
    ("metrics.py", "y_true and y_pred have different shapes"),
    ("metrics.py", "no samples to compare"),
}


def _message_start(call):
    if not call.args:
        return ""
    arg = call.args[0]
    if isinstance(arg, ast.Constant):
        return str(arg.value)
    if isinstance(arg, ast.JoinedStr):
        return "".join(v.value if isinstance(v, ast.Constant) else
                       "{" + ast.unparse(v.value) + "}" for v in arg.values)
    return ast.unparse(arg)


def _bare_raises():
    for path in sorted(SRC.rglob("*.py")):
        module = path.relative_to(SRC).as_posix()
        if module == "_reference.py":      # the tests' oracle, not a user-facing module
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call) and \
                    isinstance(node.exc.func, ast.Name) and node.exc.func.id in BARE:
                yield module, node.lineno, _message_start(node.exc)
            elif isinstance(node, ast.Assert):
                yield module, node.lineno, "assert"


def test_no_bare_builtin_exception_is_raised():
    found = [(m, line, text) for m, line, text in _bare_raises()
             if not any(m == mod and text.startswith(start) for mod, start in INTERNAL)]
    assert not found, "raise a pihyst exception (src/pihyst/exceptions.py) instead: " + \
        "; ".join(f"{m}:{line}: {text[:60]!r}" for m, line, text in found)


def test_the_internal_list_is_current():
    raised = list(_bare_raises())
    stale = [entry for entry in INTERNAL
             if not any(m == entry[0] and text.startswith(entry[1]) for m, _, text in raised)]
    assert not stale


@pytest.mark.parametrize("call, says", [
    (lambda: BoucWen(150.0, 0.3, 0.4, 0.03, 0.005, n=0.5), "exponent n must be"),
    (lambda: pihyst.io.open_record("x.csv", need=("force",)), "unknown quantities"),
    (lambda: pihyst.dynamics.compensate_hammerstein(
        pihyst.dynamics.HammersteinModel(
            hysteresis=(pihyst.ClassicalPI([0], [1.0]), pihyst.ClassicalPI([0], [1.0])),
            a=(np.array([1.0]), np.array([1.0])),
            b=((np.array([1.0]), np.array([1.0])), (np.array([1.0]), np.array([1.0])))),
        [1.0]), "single-input single-output model, got 2 input"),
])
def test_public_functions_raise_pihyst_errors(call, says):
    with pytest.raises(InvalidArgumentError, match=says):
        call()


def test_fit_many_refuses_two_records_of_one_name(tmp_path):
    with pytest.raises(InvalidArgumentError, match="two records are named 'a.csv'"):
        pihyst.fleet.fit_many([tmp_path / "a.csv", tmp_path / "b" / "a.csv"])
