"""The layering contract of docs/architecture.md: every import inside the package goes down.

Each module of ``solver/tapecoil`` is parsed (``ast``, nothing imported) and every import of
tapecoil's is checked against :data:`LAYERS`: a package imports from the layers below its own
and from its own package, never from a layer above nor from another package of its own layer.
An import inside a function counts (a lazy import is still a dependency), and so does one
under ``if TYPE_CHECKING:``: a lower layer reads what a higher one hands it without naming its
class. Neither the packages nor the modules may import each other in a cycle.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "solver" / "tapecoil"

# The layers from the bottom up. "__init__" is the package's root module (the version, imported
# for it by the command line and the results) and "__main__" `python3 -m tapecoil`.
LAYERS = (
    ("__init__",),
    ("theory",),  # the physics brief's formulas: numpy and scipy only
    ("config",),  # the parameters: a wall is built and a hub angle checked by theory's formulas
    ("core",),  # generic FEniCSx numerics, no tape knowledge; the stepping reads config's StepControl
    ("geometry",),
    ("models",),
    ("hub", "contact"),  # the hub's attachment and contact act on the shell; the turns' contact too
    ("measures",),  # what a state is measured by: read by the phases, reading the models
    ("phases",),
    ("verification", "post"),  # the cases run the phases; the pictures read the measures
    ("app",),
    ("__main__",),
)

# Imports that go up and cannot come down without changing behaviour: (importing module,
# imported module) -> why: a debt, named, to be paid by moving what the lower layer needs.
EXCEPTIONS: dict[tuple[str, str], str] = {}


def _layer_of() -> dict[str, int]:
    return {package: rank for rank, packages in enumerate(LAYERS) for package in packages}


def package_of(module: str) -> str:
    """The package a module belongs to: ``tapecoil.phases.stepped`` -> ``phases``."""
    parts = module.split(".")
    if len(parts) == 1:
        return "__init__"
    return parts[1]


def module_names(root: Path = PACKAGE) -> dict[str, Path]:
    """Every module of the package by its dotted name (a package by its ``__init__``'s)."""
    names = {}
    for path in sorted(root.rglob("*.py")):
        parts = list(path.relative_to(root.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        names[".".join(parts)] = path
    return names


def imports(module: str, source: str, is_package: bool, known: set[str]) -> list[tuple[int, str, str]]:
    """Every import of tapecoil's in ``source``: (line, the statement, the module imported).

    ``from a import b`` imports ``a.b`` when that is a module of ``known``, else ``a``; a name
    imported from a module that is not in ``known`` is taken to its nearest enclosing module.
    """
    tree = ast.parse(source)
    here = module if is_package else module.rpartition(".")[0]
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Import | ast.ImportFrom):
            continue
        statement = ast.unparse(node)
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        else:
            base = node.module or ""
            if node.level:
                parent = here.split(".")[: len(here.split(".")) - node.level + 1]
                base = ".".join(parent + ([node.module] if node.module else []))
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]
        for target in dict.fromkeys(targets):
            if target == "tapecoil" or target.startswith("tapecoil."):
                while target not in known and "." in target:
                    target = target.rpartition(".")[0]
                found.append((node.lineno, statement, target))
    return found


def import_graph(root: Path = PACKAGE) -> dict[str, list[tuple[int, str, str]]]:
    """Each module's imports of tapecoil's, by :func:`imports`."""
    names = module_names(root)
    return {
        module: imports(module, path.read_text(), path.name == "__init__.py", set(names))
        for module, path in names.items()
    }


def upward_imports(graph: dict[str, list[tuple[int, str, str]]]) -> list[tuple[str, int, str, str]]:
    """The imports :data:`LAYERS` forbids: (module, line, statement, why)."""
    layer = _layer_of()
    found = []
    for module, edges in graph.items():
        mine = package_of(module)
        for line, statement, target in edges:
            theirs = package_of(target)
            if theirs == mine or (module, target) in EXCEPTIONS:
                continue
            if theirs not in layer or mine not in layer:
                found.append((module, line, statement, f"{mine} or {theirs} has no layer in LAYERS"))
            elif layer[theirs] >= layer[mine]:
                where = "the same layer" if layer[theirs] == layer[mine] else "a higher layer"
                found.append((module, line, statement, f"{mine} imports {theirs}, {where}"))
    return found


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one node (Tarjan's), each a cycle's nodes."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for other in sorted(edges.get(node, ())):
            if other not in index:
                visit(other)
                low[node] = min(low[node], low[other])
            elif other in on_stack:
                low[node] = min(low[node], index[other])
        if low[node] == index[node]:
            component = []
            while True:
                other = stack.pop()
                on_stack.discard(other)
                component.append(other)
                if other == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(edges):
        if node not in index:
            visit(node)
    return found


def _where(graph, members: list[str], key) -> list[str]:
    """The imports that join the members of a cycle, as file:line statement."""
    names = module_names()
    return [
        f"{names[module].relative_to(PACKAGE.parent)}:{line}: {statement}"
        for module, edges in sorted(graph.items())
        for line, statement, target in edges
        if key(module) in members and key(target) in members and key(module) != key(target)
    ]


@pytest.fixture(scope="module")
def graph():
    return import_graph()


def test_every_package_has_a_layer():
    packages = {package_of(module) for module in module_names()}
    placed = set(_layer_of())
    assert packages <= placed, f"place {sorted(packages - placed)} in LAYERS (and docs/architecture.md)"
    assert placed <= packages, f"LAYERS names packages that are gone: {sorted(placed - packages)}"


def test_no_import_goes_up(graph):
    names = module_names()
    found = [
        f"{names[module].relative_to(PACKAGE.parent)}:{line}: {statement} ({why})"
        for module, line, statement, why in upward_imports(graph)
    ]
    assert not found, "imports against the layers of docs/architecture.md:\n" + "\n".join(found)


def test_the_exceptions_are_still_needed(graph):
    present = {(module, target) for module, edges in graph.items() for _, _, target in edges}
    assert set(EXCEPTIONS) <= present, f"remove the exceptions no module needs: {set(EXCEPTIONS) - present}"


def test_no_cycle_between_packages(graph):
    edges = {}
    for module, imported in graph.items():
        for _, _, target in imported:
            if package_of(target) != package_of(module):
                edges.setdefault(package_of(module), set()).add(package_of(target))
    found = [" <-> ".join(c) + "\n  " + "\n  ".join(_where(graph, c, package_of)) for c in cycles(edges)]
    assert not found, "packages importing each other:\n" + "\n".join(found)


def test_no_cycle_between_modules(graph):
    edges = {module: {t for _, _, t in imported if t != module} for module, imported in graph.items()}
    found = [" <-> ".join(c) + "\n  " + "\n  ".join(_where(graph, c, str)) for c in cycles(edges)]
    assert not found, "modules importing each other:\n" + "\n".join(found)


KNOWN = {"tapecoil.measures.coil_section", "tapecoil.phases.stepped", "tapecoil.phases", "tapecoil.config"}


@pytest.mark.parametrize(
    "source, caught",
    [
        ("from tapecoil.phases.stepped import SteppedRun", True),
        ("def f():\n    from tapecoil.phases import stepped", True),
        ("import tapecoil.phases.stepped as s", True),
        (
            "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from tapecoil.phases import stepped",
            True,
        ),
        ("from tapecoil.config import Config", False),
    ],
    ids=["top-level", "lazy", "import-as", "type-checking", "downward"],
)
def test_the_contract_sees_an_upward_import(source, caught):
    """The checker on a planted measure importing a phase: caught at the top, in a function and
    under TYPE_CHECKING, and a downward import passes."""
    found = upward_imports(
        {"tapecoil.measures.coil_section": imports("tapecoil.measures.coil_section", source, False, KNOWN)}
    )
    assert bool(found) == caught, found


def test_the_contract_sees_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []
