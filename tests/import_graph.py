"""The project's import graph, read statically with ``ast`` from every ``.py`` file.

Every ``import`` statement counts: at module level, inside functions (late imports) and under
``if TYPE_CHECKING:``. Used by ``test_architecture.py`` (which package may import which) and
``test_import_cycles.py`` (no cycle among modules).

How an import names its target module:

- ``import a.b.c`` depends on ``a.b.c``;
- ``from a.b import c`` depends on ``a.b.c`` when that is a project module (a submodule),
  else on ``a.b`` (a name defined or re-exported by ``a/b/__init__.py``);
- relative imports are resolved against the importing module's package first.

A package's ``__init__`` is a module of its own (``a.b`` for ``a/b/__init__.py``) and counts
only where it is imported by name as above. Python runs ``a/__init__.py`` before importing
``a.b`` too, but counting that would make every package whose ``__init__`` imports its
submodules a cycle with each submodule that imports a sibling; the cycle that breaks imports
is the one through names, e.g. ``worlds.robots.kuka`` importing ``ArmSpec`` from
``worlds.robots`` while ``worlds/robots/__init__.py`` imports ``worlds.robots.kuka``.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The project's top-level packages, and app.py.
PACKAGES = ("skills", "affordances", "worlds", "planner", "experiment")
TOP_MODULES = ("app",)


@dataclass(frozen=True)
class Import:
    """One imported module, as written at ``file:line``."""

    module: str
    target: str
    file: Path
    line: int

    def where(self) -> str:
        return f"{self.file.relative_to(ROOT)}:{self.line}"


def module_files(root: Path = ROOT) -> dict[str, Path]:
    """Dotted module name -> file, for every module of the project's packages and app.py."""
    files: dict[str, Path] = {}
    for package in PACKAGES:
        for path in sorted((root / package).rglob("*.py")):
            parts = path.relative_to(root).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            files[".".join(parts)] = path
    for name in TOP_MODULES:
        files[name] = root / f"{name}.py"
    return files


def _is_package(module: str, files: dict[str, Path]) -> bool:
    return files[module].name == "__init__.py"


def _absolute(node: ast.ImportFrom, module: str, files: dict[str, Path]) -> str:
    """The module an ``ImportFrom`` names, relative levels resolved."""
    if node.level == 0:
        return node.module or ""
    package = module if _is_package(module, files) else module.rpartition(".")[0]
    for _ in range(node.level - 1):
        package = package.rpartition(".")[0]
    return f"{package}.{node.module}" if node.module else package


def imports_of(module: str, files: dict[str, Path]) -> Iterator[Import]:
    """Every module ``module`` imports (project or not), in file order, late ones included."""
    path = files[module]
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    nodes = [n for n in ast.walk(tree) if isinstance(n, ast.Import | ast.ImportFrom)]
    for node in sorted(nodes, key=lambda n: (n.lineno, n.col_offset)):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield Import(module, alias.name, path, node.lineno)
        elif isinstance(node, ast.ImportFrom):
            base = _absolute(node, module, files)
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                yield Import(module, sub if sub in files else base, path, node.lineno)


def is_project(target: str) -> bool:
    """``target`` is one of the project's modules (or a name in one)."""
    return target.split(".")[0] in (*PACKAGES, *TOP_MODULES)


def project_graph(files: dict[str, Path] | None = None) -> dict[str, dict[str, Import]]:
    """module -> {imported project module: the first import statement naming it}."""
    files = files if files is not None else module_files()
    graph: dict[str, dict[str, Import]] = {}
    for module in files:
        edges: dict[str, Import] = {}
        for imp in imports_of(module, files):
            if imp.target in files and imp.target != module:
                edges.setdefault(imp.target, imp)
        graph[module] = edges
    return graph
