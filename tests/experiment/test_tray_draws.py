"""A trial's tray and the ball loose on it (experiment/tray_draws.py): drawn within the world's
ranges, from the seed alone, the ball inside the tray; bad ranges refused naming the field.

The draws place obstacle spheres against a never-stepped PyBullet scene (no simulation)."""

from __future__ import annotations

import re
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from experiment.layout import RobotClearance, draw_trial, riding
from experiment.tray_draws import PALM_TABLE_GAP_M, least_tray_height, tray_height
from skills import quaternion as quat
from worlds.spec import ShapeSpec
from worlds.trays import TrayFrame
from worlds.world_file import World, load_world

ROOT = Path(__file__).resolve().parents[2]
TRAY = ROOT / "worlds" / "tray_carry.yaml"
TRIALS = range(4)


@pytest.fixture(scope="module")
def base() -> World:
    return load_world(TRAY)


@pytest.fixture(scope="module")
def robot(base: World) -> Iterator[RobotClearance]:
    with RobotClearance(base) as clearance:
        yield clearance


@pytest.fixture(scope="module")
def drawn(base: World, robot: RobotClearance) -> list[World]:
    return [draw_trial(base, 0, t, robot)[0] for t in TRIALS]


def _in_tray(world: World) -> tuple[np.ndarray, TrayFrame, float]:
    """The ball's centre in the tray's frame (3,), the tray's inside and the ball's radius."""
    tray, ball = world.objects[0], world.objects[1]
    q = quat.from_rpy(np.radians(tray.pose.rpy_deg))
    p = quat.rotate(quat.conjugate(q), np.subtract(ball.pose.position, tray.pose.position))
    shape = ShapeSpec.tray(tray.shape.size, tray.shape.floor, tray.shape.rim)
    return p, TrayFrame.of(shape), float(ball.shape.radius)


def test_the_palms_rule_keeps_the_walls_tall_enough() -> None:
    least = least_tray_height(0.12)
    assert least == pytest.approx(0.12 + 2 * PALM_TABLE_GAP_M)
    assert tray_height(0.15, 0.13, 0.12) == pytest.approx(least)  # raised to the rule
    assert tray_height(0.15, 0.16, 0.12) == pytest.approx(0.16)  # taller is kept
    assert tray_height(0.10, 0.09, 0.12) == pytest.approx(0.10)  # never above a low file's


def test_the_tray_and_ball_are_drawn_within_their_ranges(base: World, drawn: list[World]) -> None:
    layout, file_tray, file_ball = base.trials, base.objects[0], base.objects[1]
    riders = layout.riders
    assert layout.size_scale is not None and layout.mass_kg is not None and riders is not None
    assert riders.radius_scale is not None and riders.mass_kg is not None
    lo, hi = layout.size_scale
    palm = float(base.robot.palm_size[0])
    for world in drawn:
        tray, ball = world.objects[0], world.objects[1]
        size, file_size = np.asarray(tray.shape.size), np.asarray(file_tray.shape.size)
        assert np.all(size[:2] >= lo * file_size[:2] - 1e-12)
        assert np.all(size[:2] <= hi * file_size[:2] + 1e-12)
        assert least_tray_height(palm) - 1e-12 <= size[2] <= hi * file_size[2] + 1e-12
        assert (tray.shape.floor, tray.shape.rim) == (file_tray.shape.floor, file_tray.shape.rim)
        assert layout.mass_kg[0] <= tray.mass <= layout.mass_kg[1]
        r = ball.shape.radius / file_ball.shape.radius
        assert riders.radius_scale[0] <= r <= riders.radius_scale[1]
        assert riders.mass_kg[0] <= ball.mass <= riders.mass_kg[1]
        # The tray rests on the table.
        assert tray.pose.position[2] == pytest.approx(base.table.position[2] + size[2] / 2)
    # Drawn, not fixed: the trials differ.
    assert len({w.objects[0].shape.size for w in drawn}) == len(drawn)
    assert len({w.objects[1].shape.radius for w in drawn}) == len(drawn)


def test_the_ball_starts_on_the_floor_clear_of_the_walls(base: World, drawn: list[World]) -> None:
    riders = base.trials.riders
    assert riders is not None and riders.x is not None and riders.y is not None
    for world in drawn:
        p, inside, radius = _in_tray(world)
        room = np.asarray(inside.inner_half) - radius - riders.wall_gap
        assert np.all(room > 0.0)
        fraction = p[:2] / room
        assert riders.x[0] - 1e-9 <= fraction[0] <= riders.x[1] + 1e-9
        assert riders.y[0] - 1e-9 <= fraction[1] <= riders.y[1] + 1e-9
        assert p[2] == pytest.approx(inside.floor_z + radius)  # lying on the floor
        assert riding(world) == [1]  # the trial's world still sees it riding on the tray


def test_draws_are_reproducible_from_the_seed(
    base: World, robot: RobotClearance, drawn: list[World]
) -> None:
    again = draw_trial(base, 0, 2, robot)[0]
    assert again.model_dump(mode="json") == drawn[2].model_dump(mode="json")
    other = draw_trial(base, 1, 2, robot)[0]
    assert other.objects[1].pose.position != drawn[2].objects[1].pose.position


def test_without_the_new_fields_the_ball_keeps_its_offset(
    base: World, robot: RobotClearance
) -> None:
    trials = base.trials.model_copy(update={"riders": None, "size_scale": None, "mass_kg": None})
    plain = base.model_copy(update={"trials": trials})
    world = draw_trial(plain, 0, 0, robot)[0]
    offset = np.subtract(world.objects[1].pose.position, world.objects[0].pose.position)
    file_offset = np.subtract(base.objects[1].pose.position, base.objects[0].pose.position)
    np.testing.assert_allclose(offset, file_offset, atol=1e-12)
    assert world.objects[1].shape == base.objects[1].shape
    assert world.objects[0].shape == base.objects[0].shape


def _run(tmp_path: Path, old: str, new: str, *command: str) -> subprocess.CompletedProcess[str]:
    text = TRAY.read_text(encoding="utf-8")
    text = text.replace("tree: ../planner/trees/", f"tree: {ROOT}/planner/trees/", 1)
    assert old in text, old
    path = tmp_path / "world.yaml"
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    args = [command[0], str(path), *command[1:]]
    return subprocess.run(
        [sys.executable, str(ROOT / "app.py"), *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
        check=False,
    )


BAD = [
    ("    x: [-0.8, 0.8]", "    x: [-1.5, 0.8]", r"trials\.riders\.x: expected fractions within"),
    ("    y: [-0.8, 0.8]", "    y: [0.5, 0.2]", r"trials\.riders\.y: expected low <= high"),
    ("radius_scale: [0.8, 1.2]", "radius_scale: [0.0, 1.2]", r"riders\.radius_scale: expected"),
    ("mass_kg: [0.03, 0.08]", "mass_kg: [-0.03, 0.08]", r"trials\.riders\.mass_kg: expected"),
    ("wall_gap: 0.005", "wall_gap: -0.005", r"trials\.riders\.wall_gap"),
    (
        "wall_gap: 0.005",
        "wall_gap: 0.005\n    spin: 1",
        r"trials\.riders\.spin: expected only the keys x, y, radius_scale",
    ),
    ("size_scale: [0.9, 1.1]", "size_scale: [-0.9, 1.1]", r"trials\.size_scale: expected"),
]


@pytest.mark.parametrize(("old", "new", "message"), BAD)
def test_a_bad_rider_field_is_refused_naming_it(
    tmp_path: Path, old: str, new: str, message: str
) -> None:
    done = _run(tmp_path, old, new, "validate")
    assert done.returncode == 2, done.stdout + done.stderr
    lines = done.stderr.splitlines()  # the message alone: no "pybullet build time" line
    assert len(lines) == 1, done.stderr
    assert "world.yaml: " in lines[0]
    assert re.search(message, lines[0]), lines[0]


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        # A tray too small for the ball at the low end of the scale.
        ("size_scale: [0.9, 1.1]", "size_scale: [0.3, 1.1]", r"trials\.size_scale: expected the"),
        # Riders drawn, but the ball lies on the table beside the tray.
        ("[0.57, 0.03, 0.735]", "[0.45, 0.40, 0.625]", r"trials\.riders: expected objects\[0\]"),
    ],
)
def test_a_tray_that_cannot_carry_its_ball_is_refused_before_any_trial(
    tmp_path: Path, old: str, new: str, message: str
) -> None:
    done = _run(tmp_path, old, new, "trials", "--n", "1", "--out", str(tmp_path / "c"))
    assert done.returncode == 2, done.stdout + done.stderr
    assert re.search(message, done.stderr), done.stderr
    assert not (tmp_path / "c" / "results.jsonl").exists()
