"""An obstacle that appears inside an arm holding the object (worlds.obstacle_holds)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from worlds.obstacle_holds import obstacle_hold_problems
from worlds.world_file import load_world, world_from_data

ROOT = Path(__file__).resolve().parents[2]
DEFAULT = ROOT / "worlds" / "parcel_pick_place.yaml"
IN_THE_ARM = ROOT / "tests" / "data" / "infeasible_worlds" / "obstacle_in_the_holding_arm.yaml"
EXPECTED = (
    "obstacles[1].position: expected ball_left clear of the arms holding parcel at the goal of "
    "its move 2 (task[0].moves[1]) when task[0].moves[2] starts, got [0.74, 0, 0.8]: the left "
    "arm touches it, with "
    "parcel at [0.7, -0.25, 0.675]"
)

pytestmark = pytest.mark.sim


def _edited(path: Path, edit: Any) -> Any:
    world = load_world(path)
    data = world.model_dump(mode="json")
    edit(data)
    return world_from_data(data, world.source)


def test_the_shipped_worlds_obstacles_appear_clear_of_the_arms() -> None:
    assert obstacle_hold_problems(load_world(DEFAULT)) == []
    assert obstacle_hold_problems(load_world(ROOT / "worlds" / "icub_parcel_pick_place.yaml")) == []


def test_a_sphere_appearing_inside_the_forearm_that_holds_the_parcel() -> None:
    problems = obstacle_hold_problems(load_world(IN_THE_ARM))
    assert [p.format("w.yaml") for p in problems] == [f"w.yaml: {EXPECTED}"]


def test_moved_out_of_the_forearm_the_same_sphere_is_clear() -> None:
    def higher(data: dict[str, Any]) -> None:
        data["obstacles"][1]["position"] = [0.74, 0.0, 1.10]  # 30 cm above the forearm

    assert obstacle_hold_problems(_edited(IN_THE_ARM, higher)) == []


def test_only_the_moves_after_the_first_are_asked() -> None:
    # The same sphere in the first move: the palms are still at rest when it appears.
    def first(data: dict[str, Any]) -> None:
        moves = data["task"][0]["moves"]
        moves[0]["obstacles"], moves[2]["obstacles"] = ["ball_left"], []

    assert obstacle_hold_problems(_edited(IN_THE_ARM, first)) == []


def test_validate_exits_2_naming_the_obstacle() -> None:
    done = subprocess.run(
        [sys.executable, str(ROOT / "app.py"), "validate", str(IN_THE_ARM)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=False,
    )
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    assert f"{IN_THE_ARM}: {EXPECTED}" in done.stdout + done.stderr


def test_after_a_move_that_leaves_the_object_on_its_side_nothing_is_asked() -> None:
    # The lateral holds say nothing of how a box on its side is held.
    def on_its_side(data: dict[str, Any]) -> None:
        data["task"][0]["moves"][1]["goal"]["rpy_deg"] = [90.0, 0.0, 0.0]

    assert obstacle_hold_problems(_edited(IN_THE_ARM, on_its_side)) == []


HELD_INTO = ROOT / "tests" / "data" / "infeasible_worlds" / "goal_held_only_into_a_sphere.yaml"


def test_a_goal_the_arms_can_hold_only_into_its_obstacle() -> None:
    problems = obstacle_hold_problems(load_world(HELD_INTO))
    assert [p.format("w.yaml") for p in problems] == [
        "w.yaml: task[0].moves[2].goal: expected parcel held at its goal clear of the move's "
        "obstacles, in a grip the arms reach, got [0.6, 0.15, 0.675] turned -60 deg: grip 30 "
        "deg: the right arm touches it (ball_left)"
    ]


def test_a_goal_with_one_grip_into_its_obstacle_and_one_clear_passes() -> None:
    from skills.turns import Hold
    from worlds.obstacle_holds import goal_hold_touches
    from worlds.sim_world import SimWorld

    def turned_45(data: dict[str, Any]) -> None:
        data["task"][0]["moves"][2]["goal"]["rpy_deg"] = [0.0, 0.0, 45.0]

    world = _edited(DEFAULT, turned_45)
    assert obstacle_hold_problems(world) == []
    # Asked of one grip at a time, the 45 degree grip touches ball_left, the -45 one does not.
    with SimWorld(world) as sim:
        goal = np.array([0.6, 0.15, 0.675])
        yaw = np.radians(45.0)
        into = sim.hold_touches("parcel", ("ball_left",), Hold(goal, yaw, yaw, 0))
        assert into == {"ball_left": "the right arm touches it"}
        assert sim.hold_touches("parcel", ("ball_left",), Hold(goal, yaw, -yaw, 3)) == {}
        assert goal_hold_touches(sim, "parcel", ("ball_left",), goal, yaw) == []
        # The same goal turned -60 reaches one grip only: the problem names it.
        lines = goal_hold_touches(sim, "parcel", ("ball_left",), goal, np.radians(-60.0))
    assert lines == ["grip 30 deg: the right arm touches it (ball_left)"]


def test_an_obstacle_in_the_arm_grasping_the_object_where_it_stands_is_refused() -> None:
    # A first move's sphere in the iCub's left arm, as the arm holds the parcel where it
    # stands: it had validated (only second and later moves were asked), and the run spent
    # 35 s on four grasps before failing as "obstacle spawned inside a body".
    def edit(data: dict[str, Any]) -> None:
        data["obstacles"] = [
            {
                "name": "blk",
                "shape": {"type": "sphere", "radius": 0.03},
                "position": [0.29, 0.065, 0.8],
            }
        ]
        data["task"][0]["moves"] = [
            {"goal": {"position": [0.29, 0.13, 0.68], "rpy_deg": [0, 0, 0]}, "obstacles": ["blk"]}
        ]
        data["trials"] = None

    world = _edited(ROOT / "worlds" / "icub_parcel_pick_place.yaml", edit)
    (problem,) = obstacle_hold_problems(world)
    assert problem.format("w.yaml") == (
        "w.yaml: obstacles[0].position: expected blk clear of the arms holding parcel where it "
        "stands, in the grasp the move starts from when task[0].moves[0] starts, got [0.29, "
        "0.065, 0.8]: the left arm touches it, with parcel at [0.29, 0, 0.68]"
    )
