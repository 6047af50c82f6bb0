"""No import circles in the core (issue #42) nor in the plugins' packages (issue #59): a module
never imports, directly or through others, a module that imports it back.
Imports inside functions count (they are deferred, not absent); imports made only for type
annotations do not (as in the import contract)."""

from __future__ import annotations

from pathlib import Path

import grimp
import pytest

ROOT = Path(__file__).resolve().parents[1]
PLUGIN_PACKAGES = sorted(
    p.parent.name
    for folder in ("plugins", "examples")
    for p in ROOT.glob(f"{folder}/*/src/*/__init__.py")
)
"""The built-in plugins' packages (``plugins/*/src``) and the examples' (``examples/*/src``)."""


def _cycles(graph: grimp.ImportGraph, package: str) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    modules = sorted(m for m in graph.modules if m == package or m.startswith(package + "."))
    inside = set(modules)
    edges = {m: sorted(set(graph.find_modules_directly_imported_by(m)) & inside) for m in modules}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in edges[v]:
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
            if len(component) > 1:
                found.append(sorted(component))

    for m in modules:
        if m not in index:
            visit(m)
    return found


def test_the_cycle_finder_finds_a_circle() -> None:
    """The check itself can fail: two modules that import each other are one circle."""
    graph = grimp.ImportGraph()
    for m in ("pkg", "pkg.a", "pkg.b", "pkg.c"):
        graph.add_module(m)
    graph.add_import(importer="pkg.a", imported="pkg.b")
    graph.add_import(importer="pkg.b", imported="pkg.a")
    graph.add_import(importer="pkg.c", imported="pkg.a")
    assert _cycles(graph, "pkg") == [["pkg.a", "pkg.b"]]


def test_devlearn_has_no_import_circles() -> None:
    graph = grimp.build_graph("devlearn", exclude_type_checking_imports=True)
    assert _cycles(graph, "devlearn") == []


@pytest.mark.parametrize("package", PLUGIN_PACKAGES)
def test_plugin_package_has_no_import_circles(package: str) -> None:
    graph = grimp.build_graph(package, exclude_type_checking_imports=True)
    assert _cycles(graph, package) == []


def test_every_plugin_package_is_checked() -> None:
    """The list above is read from the tree; it must not silently come up empty."""
    assert {"devlearn_self_touch", "devlearn_hand_regard", "devlearn_curiosity"} <= set(
        PLUGIN_PACKAGES
    )
