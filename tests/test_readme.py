"""The README's code examples run: the blocks marked with a file name, outside the project.

A fenced block whose info string names a file (```` ```python file=test_my_leaves.py ````) is
written to a folder of its own; pytest runs there (its own rootdir, the plugins loaded with
``-p`` as a checkout would, strict markers), and the documented commands run on the files.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BLOCK = re.compile(r"^```(\w+) file=(\S+)\n(.*?)^```$", re.MULTILINE | re.DOTALL)


def readme_files() -> dict[str, str]:
    """File name -> text of the README's blocks marked with a file name."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return {name: body for _, name, body in BLOCK.findall(text)}


def _run(args: list[str], cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}  # this checkout's packages, not another's
    env.pop("PYTEST_ADDOPTS", None)
    return subprocess.run(
        [sys.executable, *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=300
    )


def test_the_readme_marks_its_runnable_examples() -> None:
    files = readme_files()
    assert set(files) >= {"my_world.yaml", "my_leaves.py", "my_tree.xml", "test_my_leaves.py"}
    assert "import pytest\n" in files["test_my_leaves.py"]


@pytest.mark.sim
def test_the_readme_leaf_tests_pass_outside_the_project(tmp_path: Path) -> None:
    for name, body in readme_files().items():
        (tmp_path / name).write_text(body, encoding="utf-8")
    plugins = ["-p", "planner.testing.fixtures", "-p", "worlds.testing"]
    run = _run(
        [
            "-m",
            "pytest",
            *plugins,
            "--rootdir",
            str(tmp_path),
            "--strict-markers",
            "-q",
            "-p",
            "no:cacheprovider",
            "test_my_leaves.py",
        ],
        tmp_path,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert "4 passed" in run.stdout
    # The documented commands on the documented files.
    app = str(ROOT / "app.py")
    assert _run([app, "validate", "my_world.yaml"], tmp_path).returncode == 0
    bare = _run([app, "validate", "my_tree.xml"], tmp_path)
    assert bare.returncode == 2 and "register it with --leaves my_leaves.py" in bare.stderr
    good = _run([app, "validate", "my_tree.xml", "--leaves", "my_leaves.py"], tmp_path)
    assert good.returncode == 0, good.stderr
    nodes = _run([app, "nodes", "--leaves", "my_leaves.py"], tmp_path)
    assert '<Condition ID="HeightAtLeast">' in nodes.stdout


def test_the_plugins_do_not_import_the_simulator() -> None:
    code = "import planner.testing.fixtures, worlds.testing, sys; print('pybullet' in sys.modules)"
    run = _run(["-c", code], ROOT)
    assert run.stdout.strip() == "False", run.stderr


def test_pyproject_registers_the_plugins() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    plugins = project["entry-points"]["pytest11"]
    assert plugins == {
        "planner.testing.fixtures": "planner.testing.fixtures",
        "worlds.testing": "worlds.testing",
    }
