"""Layers that point one way (issue 29, item 4): ``sigcore/world/`` (the world format: XML to models, spawn requests
to models) imports nothing of the simulation, the recordings or the plugin registry, and the modules of ``sigcore/``
import each other without a cycle, counting the imports made inside functions. (No plugin imports another:
``tests/test_lint.py``.)

The import graph is read from the source with :mod:`ast`: every ``import`` and ``from ... import`` anywhere in a
module, except under ``if TYPE_CHECKING:`` (never run). An edge goes to the module named, or to the module that
defines the name imported (``from ..sim import spawn`` is an edge to ``sigcore.sim.spawn``). Importing a submodule
also runs its package's ``__init__``; that is not counted as an edge (as Python's own cycle rule, which concerns the
modules named)."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "sigcore"


def _modules() -> dict[str, Path]:
    found = {}
    for path in PACKAGE.rglob("*.py"):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


def _type_checking_only(tree: ast.Module) -> set[int]:
    """ids of the import nodes under ``if TYPE_CHECKING:``."""
    skip = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skip.update(id(n) for n in ast.walk(node) if isinstance(n, ast.Import | ast.ImportFrom))
    return skip


def import_graph() -> dict[str, set[str]]:
    """Module -> the modules of ``sigcore`` it imports (see the module docstring)."""
    modules = _modules()

    def known(name: str) -> str | None:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    graph: dict[str, set[str]] = {name: set() for name in modules}
    for name, path in modules.items():
        tree = ast.parse(path.read_text(), str(path))
        skip = _type_checking_only(tree)
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(tree):
            if id(node) in skip:
                continue
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names if a.name.split(".")[0] == "sigcore"]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")
                    base = base[:len(base) - (node.level - 1)]
                    where = ".".join(base + ([node.module] if node.module else []))
                else:
                    where = node.module or ""
                if where.split(".")[0] == "sigcore":
                    targets = [f"{where}.{a.name}" if f"{where}.{a.name}" in modules else where for a in node.names]
            for target in targets:
                module = known(target)
                if module is not None and module != name:
                    graph[name].add(module)
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = 0
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on_stack.add(root)
        while work:
            node, edges = work[-1]
            for nxt in edges:
                if nxt not in index:
                    index[nxt] = low[nxt] = counter
                    counter += 1
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, iter(sorted(graph[nxt]))))
                    break
                if nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == node:
                            break
                    if len(component) > 1:
                        found.append(sorted(component))
    return found


def test_the_cycle_finder_finds_a_cycle() -> None:
    """The check below can fail: a made-up graph with one cycle of three and a tail."""
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"a"}}
    assert cycles(graph) == [["a", "b", "c"]]


def test_the_graph_sees_imports_inside_functions() -> None:
    """The simulation imports the spawnables catalogue only inside a method: the graph has that edge."""
    assert "sigcore.world.spawnables" in import_graph()["sigcore.sim.population"]


def test_the_world_layer_imports_nothing_above_it() -> None:
    """``sigcore/world/`` imports nothing of ``sim/``, ``record/``, ``plugins.py`` (nor the transports, viewers, CLI
    or API table above them)."""
    above = ("sigcore.sim", "sigcore.record", "sigcore.plugins", "sigcore.cli", "sigcore.api", "sigcore.agent",
             "sigcore.transport", "sigcore.viewer", "sigcore.hookspecs", "sigcore.feature")
    wrong = sorted(f"{module} imports {target}" for module, targets in import_graph().items()
                   if module.startswith("sigcore.world") for target in targets
                   if target.startswith(above))
    assert wrong == []


def test_the_world_layer_stands_on_the_foundations_only() -> None:
    """``sigcore/world/`` is the bottom layer: outside itself it imports only the foundations every layer shares
    (errors, geometry, client text), not the scene description, the backend interface or the publications above it
    (an entity's looks are in ``world/appearance.py``, which the scene description reads)."""
    foundations = {"sigcore.errors", "sigcore.geometry", "sigcore.text"}
    wrong = sorted(f"{module} imports {target}" for module, targets in import_graph().items()
                   if module.startswith("sigcore.world") for target in targets
                   if not target.startswith("sigcore.world") and target not in foundations)
    assert wrong == []


def test_no_import_cycle_inside_sigcore() -> None:
    assert cycles(import_graph()) == []
