"""The package's shape: no import cycles, and no layer importing a higher one.

Every ``import`` in every module counts, including those inside functions (a lazy
import hides a cycle from Python, not from this test). Layers, lowest first
(docs/architecture.md):

0. ``_version``, ``_atomic``, ``_core``, ``_boucwen_core``, ``_reference``, ``exceptions``,
   ``paper``, ``metrics``
1. ``_arguments``, ``_frozen`` (shared checks and read-only values)
2. ``model``
3. ``io``, ``inverse``
4. ``identify``, ``sim``, ``control``, ``dynamics``
5. ``rig``, ``fleet``, ``learn``
6. ``study`` (the paper's experiment runs through everything below, the rig included)
7. ``cli``

A module may import its own sub-package and lower layers, never a higher layer nor a
sibling of its own layer; nothing imports the top-level ``pihyst`` facade.
"""

import ast
import functools
from pathlib import Path

import pytest

import pihyst

PACKAGE = Path(pihyst.__file__).parent
LAYERS = [
    {"_version", "_atomic", "_core", "_boucwen_core", "_reference", "exceptions", "paper",
     "metrics"},
    {"_arguments", "_frozen"},
    {"model"},
    {"io", "inverse"},
    {"identify", "sim", "control", "dynamics"},
    {"rig", "fleet", "learn"},
    {"study"},
    {"cli"},
]
LAYER_OF = {unit: i for i, units in enumerate(LAYERS) for unit in units}


def _module_name(path):
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules():
    files = sorted(PACKAGE.rglob("*.py")) + sorted(PACKAGE.glob("*.pyx"))
    return {_module_name(p): p for p in files}


def _imports(name, path):
    """The pihyst modules ``name`` imports (absolute and relative, at any depth)."""
    if path.suffix == ".pyx":
        return set()  # Cython: imports only NumPy and the C core
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    # imports for the type checker only (``if TYPE_CHECKING:``) never run: no cycle,
    # no layer crossed at run time
    typing_only = {id(n) for block in ast.walk(tree) if isinstance(block, ast.If)
                   and isinstance(block.test, ast.Name) and block.test.id == "TYPE_CHECKING"
                   for stmt in block.body for n in ast.walk(stmt)}
    for node in ast.walk(tree):
        if id(node) in typing_only:
            continue
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.split(".")[0] == "pihyst")
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                target = f"{base}.{node.module}" if node.module else base
            else:
                target = node.module or ""
            if target.split(".")[0] != "pihyst":
                continue
            # "from pihyst.x import y" imports the module pihyst.x.y if there is one,
            # else the name y of pihyst.x
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                found.add(sub if sub in MODULES else target)
    return found


MODULES = _modules()


@functools.cache
def _graph():
    modules = MODULES
    return {name: {m for m in _imports(name, path) if m in modules and m != name}
            for name, path in modules.items()}


def _unit(module):
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def test_the_package_has_its_pipeline_layout():
    units = {p.stem if p.is_file() else p.name for p in PACKAGE.iterdir()
             if (p.suffix in (".py", ".pyx") or (p.is_dir() and (p / "__init__.py").exists()))}
    units -= {"__init__", "__main__"}
    assert units <= set(LAYER_OF), f"not placed in a layer: {sorted(units - set(LAYER_OF))}"


def test_no_import_cycles():
    graph = _graph()
    state = {}

    def visit(node, path):
        state[node] = "open"
        for nxt in sorted(graph[node]):
            if state.get(nxt) == "open":
                cycle = path[path.index(nxt):] + [nxt]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if nxt not in state:
                visit(nxt, path + [nxt])
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node, [node])


@pytest.mark.parametrize("module", sorted(MODULES))
def test_layers_import_only_downwards(module):
    if module in ("pihyst", "pihyst.__main__"):
        return  # the facade and the entry point sit above everything
    own = _unit(module)
    for target in _graph()[module]:
        assert target != "pihyst", f"{module} imports the top-level pihyst facade"
        other = _unit(target)
        if other == own:
            continue
        assert LAYER_OF[other] < LAYER_OF[own], (
            f"{module} (layer {LAYER_OF[own]}, {own}) imports {target} "
            f"(layer {LAYER_OF[other]}, {other})")


def test_the_checker_sees_a_cycle_and_an_upward_import(tmp_path):
    """The parser finds lazy and relative imports (else the tests above prove nothing)."""
    src = tmp_path / "pihyst" / "model"
    src.mkdir(parents=True)
    (src / "_m.py").write_text("def f():\n    from pihyst.study import x\n"
                               "from . import _n\nfrom ..io import y\n", encoding="utf-8")
    found = _imports("pihyst.model._m", src / "_m.py")
    assert {"pihyst.study", "pihyst.model", "pihyst.io"} <= found


def test_the_module_maps_list_every_identification_module():
    """identify/__init__'s docstring and docs/architecture.md name every module of
    pihyst.identify (the procedure a newcomer reads)."""
    import pihyst.identify

    architecture = (PACKAGE.parents[1] / "docs" / "architecture.md").read_text(
        encoding="utf-8")
    names = sorted(p.stem for p in (PACKAGE / "identify").glob("_*.py")
                   if p.stem != "__init__")
    missing_init = [n for n in names if f"``{n}``" not in pihyst.identify.__doc__]
    missing_docs = [n for n in names if n not in architecture]
    assert not missing_init and not missing_docs, (missing_init, missing_docs)
