"""The package's layout: imports point down the stack, no import cycles, modules of a readable size.

The graph is read from the source (``ast``), not from ``sys.modules``: every ``import`` and
``from … import`` counts, at module level or inside a function (a lazy import is still a
dependency), and ``from .. import name`` counts as an import of the package's ``__init__``.
The stack, bottom up (``docs/architecture.md``)::

    errors ← output, workers, memory, _version ← geometry ← mesh ← minkowski ← cobstacle ← scene
           ← check, viz ← planning ← cli ← the package root (the public API), __main__
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "cspace"

# Rank of each layer; a module may import its own layer (without cycles) and lower ranks.
RANKS = {
    "errors": 0,
    "output": 1, "workers": 1, "memory": 1, "_version": 1,
    "geometry": 2,
    "mesh": 3,
    "minkowski": 4,
    "cobstacle": 5,
    "scene": 6,
    "check": 7, "viz": 7,
    "planning": 8,
    "cli": 9,
    "": 10, "__main__": 10,  # the package root re-exports the public API from every layer
}
LONG = 800  # lines; a longer module says why in its docstring ("Length: ...")


def _modules() -> dict[str, Path]:
    out = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = path
    for path in PACKAGE.rglob("*.pyx"):  # compiled kernels
        out[".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts)] = path
    return out


# Cython is not Python: its imports are read line by line (``cimport`` is C, not a module).
PYX_IMPORT = re.compile(r"^\s*(?:from\s+(cspace[\w.]*)\s+import\s|import\s+(cspace[\w.]*))", re.M)


def import_graph() -> dict[str, set[str]]:
    """``module -> modules of cspace it imports`` (dotted names; packages by their name)."""
    mods = _modules()
    graph: dict[str, set[str]] = {m: set() for m in mods}
    for name, path in mods.items():
        if path.suffix == ".pyx":
            graph[name].update(a or b for a, b in PYX_IMPORT.findall(path.read_text()))
            continue
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - node.level + 1]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                if target != "cspace" and not target.startswith("cspace."):
                    continue
                for alias in node.names:
                    sub = f"{target}.{alias.name}"
                    graph[name].add(sub if sub in mods else target)
            elif isinstance(node, ast.Import):
                graph[name].update(a.name for a in node.names
                                   if a.name == "cspace" or a.name.startswith("cspace."))
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (or a self-import)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:  # Tarjan; the graph is a few dozen modules deep at most
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1 or v in graph.get(v, ()):
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def layer(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def test_the_graph_is_read_from_every_module():
    graph = import_graph()
    assert "cspace.minkowski.ncc_cvms" in graph and "cspace.scene.model" in graph
    # lazy imports inside functions count, and the compiled kernels' imports
    assert "cspace.mesh.self_intersection" in graph["cspace.mesh.closed"]
    assert "cspace.geometry.homogeneous" in graph["cspace.geometry._kernels.planar"]


def test_no_import_cycles():
    assert cycles(import_graph()) == []


def test_the_cycle_finder_finds_cycles():
    """The check itself can fail: a two-module loop, a self-import and a longer ring."""
    assert cycles({"a": {"b"}, "b": {"a"}}) == [["a", "b"]]
    assert cycles({"a": {"a"}}) == [["a"]]
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_imports_point_down_the_stack():
    graph = import_graph()
    assert set(map(layer, graph)) <= set(RANKS), set(map(layer, graph)) - set(RANKS)
    upward = [(a, b) for a, targets in graph.items() for b in targets
              if layer(a) != layer(b) and RANKS[layer(b)] >= RANKS[layer(a)]]
    assert upward == []


def test_nothing_imports_the_package_root():
    """``from cspace import x`` inside the package would make every module depend on all of
    them (the root re-exports the API); the version lives in ``cspace._version``."""
    graph = import_graph()
    assert [m for m, targets in graph.items() if "cspace" in targets and m != "cspace.__main__"] == []


@pytest.mark.parametrize("path", sorted(PACKAGE.rglob("*.py")), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_long_modules_say_why(path):
    lines = path.read_text().count("\n")
    if lines > LONG:
        doc = ast.get_docstring(ast.parse(path.read_text())) or ""
        assert "Length:" in doc, f"{path.name}: {lines} lines and no reason in its docstring"


def test_subpackages_say_what_they_offer():
    for init in PACKAGE.glob("*/__init__.py"):
        doc = ast.get_docstring(ast.parse(init.read_text()))
        assert doc and len(doc.splitlines()) >= 3, init
