"""Dependencies flow one way: skills, affordances and planner never import the simulator."""

from __future__ import annotations

import subprocess
import sys

import pytest

HEAVY = ("pybullet", "fcl", "trimesh")


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


def test_skills_imports_only_numpy_and_scipy() -> None:
    # And numba, optional, for skills.compiled: what numba imports itself (it reads a YAML
    # configuration when PyYAML is there) is numba's, so it is imported first.
    code = (
        "import importlib, importlib.util, pkgutil, sys\n"
        "if importlib.util.find_spec('numba'):\n"
        "    import numba\n"
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
