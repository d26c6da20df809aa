"""Inputs and outputs a user's machine gives that the corpus of issue 15 did not: a flat mesh,
an integer too long to read, a full stdout, output names taken by folders. Each through the
real command: exit 2, its message, never a traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.worlds.test_adapters import write_mesh_world

ROOT = Path(__file__).resolve().parents[1]
WORLD = ROOT / "worlds" / "parcel_pick_place.yaml"


def app(*args: str, stdout: int | None = subprocess.PIPE) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(ROOT / "app.py"), *args],
        cwd=ROOT,
        stdout=stdout,
        stderr=subprocess.PIPE,
        text=True,
        timeout=300,
    )


def said(done: subprocess.CompletedProcess[str], message: str) -> None:
    text = done.stderr + (done.stdout or "")
    assert done.returncode == 2 and "Traceback" not in text, text
    assert message in text, text


@pytest.mark.parametrize(
    ("vertices", "flat"),
    [("v 0 0 0\nv 1 0 0\nv 0 1 0\n", "z"), ("v 0 0 0\nv 0.2 0 0\nv 0 0 0.15\n", "y")],
)
def test_a_mesh_without_volume_is_refused_naming_the_axis(
    tmp_path: Path, vertices: str, flat: str
) -> None:
    # It had passed the schema, then been a traceback in `run` and "internal error" (exit 1)
    # in `validate`: ObjectContext 'parcel'.dimensions.z: expected > 0 m.
    world = write_mesh_world(tmp_path, parcel_mesh=True)
    (tmp_path / "meshes" / "box.obj").write_text(vertices + "f 1 2 3\n", encoding="utf-8")
    for command in ("validate", "affordances"):
        said(
            app(command, str(world)),
            "objects[0].shape.file: expected a mesh with volume (an extent along x, y and z), "
            f"got 'meshes/box.obj' (flat along {flat}",
        )


@pytest.mark.parametrize("suffix", ["yaml", "json"])
def test_an_integer_too_long_to_read_is_named(tmp_path: Path, suffix: str) -> None:
    world = tmp_path / f"w.{suffix}"
    digits = "9" * 5000
    world.write_text(f'{{"name": "w", "seed": {digits}}}', encoding="utf-8")
    said(app("validate", str(world)), "a number it cannot read: Exceeds the limit (4300 digits)")


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs Linux's /dev/full")
def test_a_full_stdout_is_said_on_stderr() -> None:
    with open("/dev/full", "w") as full:
        said(app("schema", stdout=full.fileno()), "stdout: cannot write: No space left on device")


def test_output_names_taken_by_folders_are_named(tmp_path: Path) -> None:
    out = tmp_path / "trial"
    (out / "trial_0.yaml").mkdir(parents=True)
    said(
        app("trials", str(WORLD), "--trial", "0", "--out", str(out)),
        f"{out / 'trial_0.yaml'}: cannot write it",
    )
    campaign = tmp_path / "campaign"
    (campaign / "report.png").mkdir(parents=True)
    (campaign / "results.jsonl").write_text(
        '{"trial": 0, "seed": 0, "success": true, "failure": ""}\n', encoding="utf-8"
    )
    said(app("report", str(campaign)), f"not written: {campaign / 'report.png'}")
