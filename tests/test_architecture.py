"""Dependencies flow one way, for every package.

skills <- affordances <- planner <- experiment <- app, with worlds beside planner: it
implements the planner's port (``planner.port``) and imports nothing else of the planner, and
nothing of the experiment layer above both. skills, affordances and planner never import the
simulator. Checked statically, every import of every file counted (inside functions and under
``if TYPE_CHECKING:`` too, see :mod:`tests.import_graph`), and by importing the packages.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.import_graph import PACKAGES, Import, imports_of, is_project, module_files

HEAVY = ("pybullet", "fcl", "trimesh")
ROOT = Path(__file__).resolve().parents[1]


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


def test_only_worlds_imports_pybullet_itself() -> None:
    # worlds/__init__.py installs the finder that keeps pybullet's "build time" line off
    # stderr; a module elsewhere importing pybullet before anything imported worlds printed
    # it on every run. Others take it from worlds.bullet, which runs worlds first.
    files = module_files()
    bad = [
        f"{imp.where()}: {imp.module} imports {imp.target}"
        for module in files
        if _top(module) != "worlds"
        for imp in imports_of(module, files)
        if _top(imp.target) == "pybullet"
    ]
    assert not bad, "import pybullet through worlds.bullet:\n" + "\n".join(bad)


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


#: Modules the run path never needs: plotting, the cluster and Groot2 extras, scipy's parts
#: that only fitting, generating demonstrations or the report use, and mesh loading (its
#: hulls come from the cache).
NOT_ON_THE_RUN_PATH = (
    "matplotlib",
    "ray",
    "zmq",
    "scipy.signal",
    "scipy.stats",
    "scipy.optimize",
    "scipy.spatial",
    "scipy.ndimage",
    "trimesh",
)
#: Not even for the figure at the end of a run.
NOT_IN_A_RUN = ("matplotlib.pyplot", "ray", "zmq", "scipy.signal", "scipy.stats", "scipy.spatial")

_RUN_UNTIL = """
import json, os, sys
import app
import planner.runner as runner
first_tick = runner.tick_tree
def tick_tree(tree):
    first_tick(tree)
    if os.environ.get("STOP_AT_FIRST_TICK"):
        print(json.dumps(sorted(sys.modules)), flush=True)
        os._exit(0)
    if not hasattr(tick_tree, "seen"):
        tick_tree.seen = sorted(sys.modules)
runner.tick_tree = tick_tree
code = app.main(["run", "worlds/parcel_pick_place.yaml", "--out", sys.argv[1], "--no-animation"])
print(json.dumps(tick_tree.seen))
print(json.dumps(sorted(sys.modules)))
sys.exit(code)
"""


def _loaded(names: list[str], banned: tuple[str, ...]) -> list[str]:
    return sorted({b for b in banned for n in names if n == b or n.startswith(b + ".")})


def test_importing_the_command_line_imports_no_package_of_a_command() -> None:
    code = "import json, sys, app\nprint(json.dumps(sorted(sys.modules)))"
    names = json.loads(
        subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT
        ).stdout
    )
    heavy = ("numba", "pybullet", "pydantic", "py_trees", "scipy", *NOT_ON_THE_RUN_PATH)
    assert _loaded(names, heavy) == []


@pytest.mark.sim
def test_a_run_imports_only_what_it_uses(tmp_path: Path) -> None:
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "cache")}
    run = [sys.executable, "-c", _RUN_UNTIL, str(tmp_path / "out")]
    # A cold cache: the mesh hulls and the skill library are computed, once.
    cold = subprocess.run(
        run, capture_output=True, text=True, cwd=ROOT, env={**env, "STOP_AT_FIRST_TICK": "1"}
    )
    assert cold.returncode == 0, cold.stderr[-2000:]
    assert "trimesh" in json.loads(cold.stdout.splitlines()[-1])
    warm = subprocess.run(run, capture_output=True, text=True, cwd=ROOT, env=env)
    assert warm.returncode == 0, warm.stderr[-2000:]
    at_first_tick, at_the_end = (json.loads(line) for line in warm.stdout.splitlines()[-2:])
    assert _loaded(at_first_tick, NOT_ON_THE_RUN_PATH) == []
    assert _loaded(at_the_end, NOT_IN_A_RUN) == []
    assert "matplotlib" in at_the_end  # the figure was drawn
