"""Dependencies flow one way, for every package.

skills <- affordances <- planner <- experiment <- app, with worlds beside planner: it
implements the planner's port (``planner.port``) and imports nothing else of the planner, and
nothing of the experiment layer above both. skills, affordances and planner never import the
simulator. Checked statically, every import of every file counted (inside functions and under
``if TYPE_CHECKING:`` too, see :mod:`tests.import_graph`), and by importing the packages.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable

import pytest

from tests.import_graph import PACKAGES, Import, imports_of, is_project, module_files

HEAVY = ("pybullet", "fcl", "trimesh")


def _top(target: str) -> str:
    return target.split(".")[0]


def _only(*allowed: str) -> Callable[[str], bool]:
    return lambda target: _top(target) in allowed


def _worlds_may_import(target: str) -> bool:
    if _top(target) == "planner":
        return target == "planner.port" or target.startswith("planner.port.")
    return _top(target) in ("worlds", "skills", "affordances")


#: package -> which project modules its files may import, and what the rule says.
LAYERS: dict[str, tuple[Callable[[str], bool], str]] = {
    "skills": (_only("skills"), "no other project package"),
    "affordances": (_only("affordances", "skills"), "skills only"),
    "planner": (_only("planner", "skills", "affordances"), "skills and affordances only"),
    "worlds": (_worlds_may_import, "skills, affordances and planner.port only"),
    "experiment": (_only(*PACKAGES), "any package but app"),
}


def _imports_of_package(package: str) -> list[Import]:
    files = module_files()
    return [imp for module in files if _top(module) == package for imp in imports_of(module, files)]


def test_every_package_has_a_layer_rule() -> None:
    assert set(LAYERS) == set(PACKAGES)


@pytest.mark.parametrize("package", sorted(LAYERS))
def test_package_imports_only_the_layers_below(package: str) -> None:
    allowed, rule = LAYERS[package]
    bad = [
        f"{imp.where()}: {imp.module} imports {imp.target}"
        for imp in _imports_of_package(package)
        if is_project(imp.target) and not allowed(imp.target)
    ]
    assert not bad, f"{package} may import {rule}; got:\n" + "\n".join(bad)


@pytest.mark.parametrize("package", ["skills", "affordances", "planner"])
def test_package_never_names_the_simulator(package: str) -> None:
    bad = [
        f"{imp.where()}: {imp.module} imports {imp.target}"
        for imp in _imports_of_package(package)
        if _top(imp.target) in HEAVY
    ]
    assert not bad, f"{package} imports the simulator:\n" + "\n".join(bad)


def test_the_rules_catch_a_late_import_of_the_planner() -> None:
    allowed, _ = LAYERS["worlds"]
    assert allowed("planner.port") and allowed("skills.vocabulary")
    assert not allowed("planner.leaves") and not allowed("planner")
    assert not allowed("experiment.episode")
    assert not LAYERS["planner"][0]("worlds.sim_world")


@pytest.mark.parametrize("package", ["skills", "affordances", "planner"])
def test_package_does_not_import_simulator(package: str) -> None:
    code = (
        "import importlib, pkgutil, sys\n"
        f"pkg = importlib.import_module({package!r})\n"
        "for m in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + '.'):\n"
        "    importlib.import_module(m.name)\n"
        f"bad = [m for m in {HEAVY!r} if m in sys.modules]\n"
        "print(','.join(bad))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert out == "", f"{package} imported {out}"


def test_skills_imports_only_numpy_scipy_and_numba() -> None:
    # numba compiles the kernels: what numba imports itself (it reads a YAML configuration
    # when PyYAML is there) is numba's, so it is imported first.
    code = (
        "import importlib, pkgutil, sys\n"
        "import numba\n"
        "before = set(sys.modules)\n"
        "import skills\n"
        "for m in pkgutil.walk_packages(skills.__path__, 'skills.'):\n"
        "    importlib.import_module(m.name)\n"
        "new = {n.split('.')[0] for n in set(sys.modules) - before}\n"
        "bad = sorted(n for n in new if n in ('py_trees', 'pydantic', 'yaml', 'matplotlib',"
        " 'pybullet', 'fcl', 'trimesh', 'worlds', 'planner', 'affordances'))\n"
        "print(','.join(bad))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert out == "", f"skills imported {out}"
