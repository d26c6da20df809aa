"""The wheel holds everything the installed command needs: built from a copy of the checkout,
installed into a fresh virtual environment (its dependencies seen through a .pth file to this
interpreter's site-packages), and run from outside the checkout."""

from __future__ import annotations

import shutil
import site
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: What the wheel builds from: the checkout without its tests, outputs and caches.
_SKIP = shutil.ignore_patterns(
    ".git", ".venv", "out", "build", "dist", "*.egg-info", "__pycache__", ".*_cache", "tests",
    "bench",
)  # fmt: skip


def _builds_wheels() -> bool:
    """setuptools can build a wheel without build isolation: its own bdist_wheel (70.1 on)."""
    import importlib.util

    return any(
        importlib.util.find_spec(name) is not None
        for name in ("setuptools.command.bdist_wheel", "wheel")
    )


pytestmark = pytest.mark.skipif(
    not _builds_wheels(),
    reason="needs setuptools>=70.1 (the dev extra, which make test installs) to build the wheel",
)


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """(the wheel, the fresh environment's python, its site-packages)."""
    base = tmp_path_factory.mktemp("wheel")
    source = base / "source"
    shutil.copytree(ROOT, source, ignore=_SKIP)
    built = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
         "-w", str(base / "dist"), str(source)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert built.returncode == 0, built.stderr[-3000:]
    (wheel,) = (base / "dist").glob("duet_robot-*.whl")
    env = base / "env"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(env)], check=True)
    python = env / "bin" / "python"
    purelib = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        capture_output=True, text=True, check=True,
    ).stdout.strip()  # fmt: skip
    # The dependencies: this interpreter's site-packages, after the wheel's own files.
    # (only site folders: never the checkout, which an editable install may put on sys.path).
    deps = [
        *site.getsitepackages(),
        sysconfig.get_paths()["purelib"],
        *(p for p in sys.path if Path(p).name in ("site-packages", "dist-packages")),
    ]
    (Path(purelib) / "zz_dependencies.pth").write_text("\n".join(dict.fromkeys(deps)) + "\n")
    done = subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps",
         "--no-index", "-q", str(wheel)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    return wheel, python, Path(purelib)


def test_the_wheel_holds_the_code_and_the_data_run_reads(
    installed: tuple[Path, Path, Path],
) -> None:
    wheel, _, _ = installed
    names = set(zipfile.ZipFile(wheel).namelist())
    for needed in (
        "app.py",
        "duet_robot/__main__.py",
        "planner/trees/pick_and_place.xml",
        "planner/trees/paper_composition.xml",
        "skills/demos/pick_place.csv",
        "skills/demos/rotate_z.csv",
        "worlds/parcel_pick_place.yaml",
        "worlds/icub_parcel_pick_place.yaml",
        "affordances/rulesets/default.yaml",
        "planner/py.typed",
    ):
        assert needed in names, needed
    assert any(n.endswith(".dist-info/licenses/LICENSE") or n.endswith("/LICENSE") for n in names)
    entry = next(n for n in names if n.endswith(".dist-info/entry_points.txt"))
    assert "duet-robot = duet_robot:main" in zipfile.ZipFile(wheel).read(entry).decode()
    assert not any(n.startswith(("tests/", "bench/")) for n in names)


def test_the_command_runs_from_outside_the_checkout(
    installed: tuple[Path, Path, Path], tmp_path: Path
) -> None:
    _, python, purelib = installed
    command = python.parent / "duet-robot"
    shown = subprocess.run(
        [str(command), "--help"], capture_output=True, text=True, cwd=tmp_path, timeout=120
    )
    assert shown.returncode == 0, shown.stderr
    assert shown.stdout.startswith("usage: duet-robot") and "validate" in shown.stdout
    world = purelib / "worlds" / "parcel_pick_place.yaml"
    tree = purelib / "planner" / "trees" / "pick_and_place.xml"
    for argv in ([str(command)], [str(python), "-m", "duet_robot"]):
        checked = subprocess.run(
            [*argv, "validate", str(world), str(tree)],
            capture_output=True, text=True, cwd=tmp_path, timeout=300,
        )  # fmt: skip
        assert checked.returncode == 0, checked.stderr
        lines = checked.stdout.splitlines()
        assert lines[0].startswith(f"{world}: ok") and lines[1].startswith(f"{tree}: ok")
    where = subprocess.run(
        [str(python), "-c", "import app, planner, worlds; print(app.__file__, planner.__file__)"],
        capture_output=True, text=True, cwd=tmp_path, check=True,
    ).stdout.split()  # fmt: skip
    assert all(Path(p).is_relative_to(purelib) for p in where), where  # not the checkout's
