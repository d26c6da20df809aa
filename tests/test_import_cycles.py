"""No import cycle among the project's modules, late and ``TYPE_CHECKING`` imports included.

A cycle works at run time only while every import on it stays inside a function or under
``TYPE_CHECKING``; the next module-level import on the loop breaks it, so the graph is read
statically (:mod:`tests.import_graph` says how an import names its module).
"""

from __future__ import annotations

from collections import deque
from itertools import pairwise
from pathlib import Path

from tests.import_graph import Import, module_files, project_graph


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components with a cycle in them, each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = 0

    def visit(node: str) -> None:
        nonlocal counter
        index[node] = low[node] = counter
        counter += 1
        stack.append(node)
        on_stack.add(node)
        for nxt in sorted(graph[node]):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1 or node in graph[node]:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def shortest_cycle_through(start: str, graph: dict[str, set[str]], within: set[str]) -> list[str]:
    """The shortest path ``start -> ... -> start`` inside ``within`` (breadth first)."""
    parent: dict[str, str] = {}
    queue = deque([start])
    seen = {start}
    while queue:
        node = queue.popleft()
        for nxt in sorted(graph[node] & within):
            if nxt == start:
                path = [node]
                while path[-1] != start:
                    path.append(parent[path[-1]])
                return [*reversed(path), start]
            if nxt not in seen:
                seen.add(nxt)
                parent[nxt] = node
                queue.append(nxt)
    raise AssertionError(f"{start}: expected a cycle inside its component")


def cycles(edges: dict[str, dict[str, Import]]) -> list[list[str]]:
    """Each distinct shortest cycle through each module that lies on one."""
    graph = {module: set(targets) for module, targets in edges.items()}
    out: list[list[str]] = []
    seen: set[tuple[str, ...]] = set()
    for component in strongly_connected(graph):
        for module in component:
            cycle = shortest_cycle_through(module, graph, set(component))
            ring = cycle[:-1]
            first = ring.index(min(ring))
            key = tuple(ring[first:] + ring[:first])  # the same cycle from any start
            if key not in seen:
                seen.add(key)
                out.append([*key, key[0]])
    return out


def describe(cycle: list[str], edges: dict[str, dict[str, Import]]) -> str:
    steps = [f"{a} -> {b} ({edges[a][b].where()})" for a, b in pairwise(cycle)]
    return " -> ".join(cycle) + "\n      " + "\n      ".join(steps)


def test_the_cycle_finder_finds_a_late_import_loop() -> None:
    edges = {"a": {"b": None}, "b": {"c": None}, "c": {"a": None, "d": None}, "d": {}}
    assert cycles(edges) == [["a", "b", "c", "a"]]  # type: ignore[arg-type]
    assert cycles({"a": {"b": None}, "b": {}}) == []  # type: ignore[dict-item]


def test_late_and_type_checking_imports_count(tmp_path: Path) -> None:
    robots = tmp_path / "worlds" / "robots"
    robots.mkdir(parents=True)
    (tmp_path / "app.py").write_text("")
    (tmp_path / "worlds" / "__init__.py").write_text("")
    (robots / "__init__.py").write_text(
        "def build():\n    from worlds.robots import kuka\n    return kuka\n"
    )
    (robots / "kuka.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .model import Spec\n"
        "    from worlds.robots import Builder\n"
    )
    (robots / "model.py").write_text("import worlds\n")
    edges = project_graph(module_files(tmp_path))
    assert set(edges["worlds.robots"]) == {"worlds.robots.kuka"}  # a submodule by name
    assert set(edges["worlds.robots.kuka"]) == {"worlds.robots.model", "worlds.robots"}
    assert set(edges["worlds.robots.model"]) == {"worlds"}  # a package's __init__ by name
    assert cycles(edges) == [["worlds.robots", "worlds.robots.kuka", "worlds.robots"]]


def test_no_import_cycle_among_the_projects_modules() -> None:
    edges = project_graph()
    found = cycles(edges)
    assert not found, f"{len(found)} import cycle(s):\n  " + "\n  ".join(
        describe(c, edges) for c in found
    )
