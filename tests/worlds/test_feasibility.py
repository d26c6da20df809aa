"""Feasibility before simulation: each infeasible world's exact problem, and the reach model."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from skills import quaternion as quat
from skills.vocabulary import Arm, GraspType
from worlds.feasibility import check_feasible, feasibility_problems, resting_half_height
from worlds.placement import off_face_deg
from worlds.robots import robot_model_of
from worlds.robots.kuka import MOUNT_PITCH_DEG, palm2flange_position
from worlds.robots.reach import arm_reach
from worlds.spec import ShapeSpec
from worlds.world_file import WorldFileError, load_world, world_spec

ROOT = Path(__file__).resolve().parents[2]
INFEASIBLE = ROOT / "tests" / "data" / "infeasible_worlds"
LATERAL = frozenset({GraspType.TWO_PALM_LATERAL})

PROBLEMS = {
    "goal_off_table.yaml": (
        "task[0].moves[1].goal.position: expected a goal over the table top "
        "(x 0.35..0.95 m, y -0.5..0.5 m), got [0.6, -0.65, 0.675]: "
        "0.15 m beyond the table's edge at y = -0.5 m"
    ),
    "goal_in_the_air.yaml": (
        "task[0].moves[0].goal.position: expected z = 0.675 m within 0.01 m, where parcel "
        "rests on the table top (0.6 m + half its height 0.075 m), got z = 0.875 m"
    ),
    "goal_on_an_edge.yaml": (
        "task[0].moves[2].goal.rpy_deg: expected parcel resting on a face, one of its axes "
        "vertical (roll and pitch multiples of 90 deg) within 2 deg, got rpy_deg [30, 0, 0]: "
        "30 deg off its nearest face, on an edge it cannot stay on"
    ),
    "goal_out_of_reach.yaml": (
        "task[0].moves[2].goal.position: expected a goal within the arms' reach, got "
        "two_palm_lateral puts the left palm at [1.45, 0.3, 0.675], 1.42 m from the centre "
        "of the left arm's reach (lbr_iiwa_joint_2 at [0.0563, 0.35, 0.956]); the arm reaches "
        "at most 0.969 m"
    ),
    "robot_in_the_table.yaml": (
        "robot.base.position: expected a robot beside the table, its arms' bases off the "
        "table top (x 0.35..0.95 m, y -0.5..0.5 m), got [0.5, 0, 0]: the left arm's base at "
        "[0.5, 0.35] m stands inside it"
    ),
    "slot_turned_90.yaml": (
        "task[0].moves[0].goal.rpy_deg: expected a goal in fixture slot the grip turns to in "
        "one carry (at most 45 deg from where the object stands before the move), got a turn of "
        "90 deg, 2 carries, each set down turned part of the way where the walls stand: turn "
        "the fixture, or start the object, within 45 deg of it"
    ),
    "too_wide.yaml": (
        "objects[0]: expected a grasp the robot can make, got none for parcel: "
        "two_palm_lateral: faces 0.7 m, 0.65 m apart, outside the palms' span 0.1..0.6 m; "
        "two_arm_support: the tree makes only two_palm_lateral; "
        "one_arm_side: needs a gripper, the robot has flat palms; "
        "one_arm_top: needs a gripper, the robot has flat palms"
    ),
}


@pytest.mark.parametrize("name", sorted(PROBLEMS))
def test_each_infeasible_world_gets_its_one_problem(name: str) -> None:
    problems = feasibility_problems(load_world(INFEASIBLE / name), LATERAL)
    assert [p.format("w.yaml") for p in problems] == [f"w.yaml: {PROBLEMS[name]}"]


def test_check_feasible_raises_naming_the_file() -> None:
    path = INFEASIBLE / "goal_off_table.yaml"
    with pytest.raises(WorldFileError, match=r"^x\.yaml: task\[0\]\.moves\[1\]\.goal\.position"):
        check_feasible(load_world(path), "x.yaml")


@pytest.mark.parametrize(
    "world",
    [
        ROOT / "worlds" / "parcel_pick_place.yaml",
        ROOT / "worlds" / "icub_parcel_pick_place.yaml",
        ROOT / "tests" / "data" / "worlds" / "small_box.yaml",
    ],
)
def test_shipped_and_small_box_worlds_are_feasible(world: Path) -> None:
    assert feasibility_problems(load_world(world), LATERAL) == []


def test_a_wide_box_any_tree_could_support_is_feasible_without_a_tree() -> None:
    # two_arm_support is a palm grasp the reasoner offers; only a tree that cannot make it
    # turns the box away
    assert feasibility_problems(load_world(INFEASIBLE / "too_wide.yaml")) == []


def test_iiwa_reach_is_its_chain_from_the_second_joint_to_the_palm() -> None:
    spec = world_spec(load_world(ROOT / "worlds" / "parcel_pick_place.yaml"))
    reach = arm_reach(robot_model_of(spec.scene.robot))
    lean = math.radians(MOUNT_PITCH_DEG)
    # joint 2 sits 0.1575 + 0.2025 m up the leaning base, on joint 1's axis
    shoulder_up = 0.1575 + 0.2025
    for arm, side in ((Arm.LEFT, 1.0), (Arm.RIGHT, -1.0)):
        assert_allclose(
            reach[arm].shoulder,
            (shoulder_up * math.sin(lean), side * 0.35, 0.6 + shoulder_up * math.cos(lean)),
            atol=1e-9,
        )
        # joints 3..7 of pybullet_data's iiwa URDF, then the palm centre on the flange
        links = 0.2045 + 0.2155 + 0.1845 + 0.2155 + 0.081
        palm = math.hypot(*palm2flange_position((0.12, 0.09, 0.02)))
        assert_allclose(reach[arm].radius_m, links + palm, rtol=1e-12)


def test_icub_reach_is_about_its_torso_and_arm_length() -> None:
    spec = world_spec(load_world(ROOT / "worlds" / "icub_parcel_pick_place.yaml"))
    reach = arm_reach(robot_model_of(spec.scene.robot))
    # The torso moves both shoulders: both spheres centre on its pitch axis at the waist, and
    # reach the torso's height to the shoulders (about 0.25 m) plus an arm of about 0.3 m, the
    # hand and its palm.
    assert_allclose(reach[Arm.LEFT].shoulder, reach[Arm.RIGHT].shoulder, atol=1e-12)
    assert_allclose(reach[Arm.LEFT].shoulder[2], spec.scene.robot.mount_height, atol=0.01)
    # A refusal names that centre as the torso's joint, not as a shoulder.
    assert reach[Arm.LEFT].joint == reach[Arm.RIGHT].joint == "torso_pitch"
    for arm in (Arm.LEFT, Arm.RIGHT):
        assert 0.6 < reach[arm].radius_m < 0.8


def test_resting_height_of_a_box_on_its_side() -> None:
    obj = world_spec(load_world(ROOT / "worlds" / "parcel_pick_place.yaml")).scene.objects[0]
    assert_allclose(resting_half_height(obj, (0.0, 0.0, 0.0, 1.0)), 0.075)
    on_side = quat.as_tuple(quat.from_axis_angle([1.0, 0.0, 0.0], math.pi / 2))
    assert_allclose(resting_half_height(obj, on_side), 0.15, atol=1e-12)  # the 0.30 m side up
    turned = quat.as_tuple(quat.from_axis_angle([0.0, 0.0, 1.0], 1.0))
    assert_allclose(resting_half_height(obj, turned), 0.075, atol=1e-12)


def test_a_resting_pose_is_on_a_face_of_the_shape() -> None:
    # A box on any of its faces, a cylinder standing or lying; on an edge, neither.
    box, cylinder = ShapeSpec.box((0.2, 0.3, 0.15)), ShapeSpec.cylinder(0.05, 0.2)
    turned = {
        rpy: tuple(quat.from_rpy(np.radians(rpy)))
        for rpy in ((0, 0, 37), (90, 0, 0), (0, -90, 45), (30, 0, 0), (0, 1.5, 0), (45, 0, 0))
    }
    off = {rpy: (off_face_deg(box, q), off_face_deg(cylinder, q)) for rpy, q in turned.items()}
    for rpy in ((0, 0, 37), (90, 0, 0), (0, -90, 45)):
        assert off[rpy] == pytest.approx((0.0, 0.0), abs=1e-6)
    assert off[(30, 0, 0)] == pytest.approx((30.0, 30.0))
    assert off[(0, 1.5, 0)][0] == pytest.approx(1.5)  # within REST_TILT_DEG: let be
    assert off[(45, 0, 0)] == pytest.approx((45.0, 45.0))
    assert off_face_deg(ShapeSpec.sphere(0.05), turned[(30, 0, 0)]) == 0.0


def test_an_object_starting_on_an_edge_is_refused_naming_its_pose(tmp_path: Path) -> None:
    text = (INFEASIBLE / "goal_in_the_air.yaml").read_text(encoding="utf-8")
    text = text.replace("position: [0.65, 0.0, 0.875]", "position: [0.65, 0.0, 0.675]")
    start = "      position: [0.55, 0.0, 0.675]  # m; z = table top 0.6 + half height 0.075\n"
    assert start in text
    text = text.replace(
        start + "      rpy_deg: [0.0, 0.0, 0.0]", start + "      rpy_deg: [0.0, 20.0, 0.0]"
    )
    path = tmp_path / "tilted_start.yaml"
    path.write_text(text, encoding="utf-8")
    found = [p.format("w.yaml") for p in feasibility_problems(load_world(path), LATERAL)]
    assert "w.yaml: objects[0].pose.rpy_deg: expected parcel resting on a face" in found[0]
    assert "got rpy_deg [0, 20, 0]: 20 deg off its nearest face" in found[0]


@pytest.mark.parametrize(
    ("shape", "rpy", "z", "hint"),
    [
        (
            "{type: box, size: [0.20, 0.30, 0.15]}",
            "[90.0, 0.0, 0.0]",
            0.75,
            "the same box standing is size [0.2, 0.15, 0.3] with rpy_deg [0, 0, 0]",
        ),
        (
            "{type: cylinder, radius: 0.07, height: 0.25}",
            "[90.0, 0.0, 0.0]",
            0.67,
            "a cylinder is grasped standing, across its diameter",
        ),
    ],
    ids=["box on its side", "lying cylinder"],
)
def test_an_object_the_task_moves_must_start_upright(
    tmp_path: Path, shape: str, rpy: str, z: float, hint: str
) -> None:
    # Resting on a face, but not on its own z axis: its grasps would be planned on the wrong
    # axes (the palms closed on air, or a lying cylinder's arms touched).
    text = (INFEASIBLE / "goal_in_the_air.yaml").read_text(encoding="utf-8")
    text = text.replace("shape: {type: box, size: [0.20, 0.30, 0.15]}", f"shape: {shape}")
    start = "      position: [0.55, 0.0, 0.675]  # m; z = table top 0.6 + half height 0.075\n"
    assert start in text
    text = text.replace(
        start + "      rpy_deg: [0.0, 0.0, 0.0]",
        f"      position: [0.55, 0.0, {z}]\n      rpy_deg: {rpy}",
    )
    path = tmp_path / "lying.yaml"
    path.write_text(text, encoding="utf-8")
    found = [p.format("w.yaml") for p in feasibility_problems(load_world(path), LATERAL)]
    assert found[0] == (
        "w.yaml: objects[0].pose.rpy_deg: expected parcel upright at its start, its z axis up "
        "within 2 deg (its grasps are planned on the axes it stands on), got rpy_deg [90, 0, "
        f"0]: its z axis 90 deg from up; {hint}"
        + (
            " (a box standing on another face is its size given in that frame)"
            if "box" in hint
            else ""
        )
    )


@pytest.mark.parametrize(
    ("shape", "moves", "received"),
    [
        # Each had validated "ok" and been dropped in physics: the reasoner plans only the
        # turn about the grasp's y axis, so a roll was carried as no turn at all.
        (
            None,
            [([0.65, 0.0, 0.75], [90, 0, 0])],
            "rpy_deg [90, 0, 0]: its y axis 90 deg from level, a roll the grip across its y "
            "faces cannot make",
        ),
        (
            None,
            [([0.65, 0.0, 0.675], [0, 180, 0])],
            "rpy_deg [0, 180, 0]: a turn of 180 deg about its y axis from where its last move "
            "left it",
        ),
        (  # two quarter turns the same way: the second is a half turn from upright too
            None,
            [([0.65, 0.0, 0.7], [0, 90, 0]), ([0.65, 0.1, 0.7], [0, -90, 0])],
            "rpy_deg [0, -90, 0]: a turn of 180 deg about its y axis",
        ),
        (
            {"type": "cylinder", "radius": 0.06, "height": 0.15},
            [([0.65, 0.0, 0.675], [180, 0, 0])],
            "(a cylinder upside down is the same cylinder upright: rpy_deg [0, 0, yaw])",
        ),
    ],
)
def test_a_goal_the_grip_cannot_turn_the_object_to_is_refused(
    tmp_path: Path,
    shape: dict[str, object] | None,
    moves: list[tuple[list[float], list[float]]],
    received: str,
) -> None:
    import yaml

    data = yaml.safe_load((ROOT / "worlds" / "parcel_pick_place.yaml").read_text())
    if shape is not None:
        data["objects"][0]["shape"] = shape
        data["objects"][0]["category"] = "tin"
    data["task"][0]["moves"] = [{"goal": {"position": p, "rpy_deg": r}} for p, r in moves]
    path = tmp_path / "turned.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    problems = feasibility_problems(load_world(path), LATERAL)
    assert len(problems) == 1, [p.format("w") for p in problems]
    (problem,) = problems
    assert problem.field == f"task[0].moves[{len(moves) - 1}].goal.rpy_deg"
    assert problem.expected.startswith("a goal the grip turns ")
    assert received in problem.received


def test_the_box_flips_quarter_turns_and_yaws_are_feasible(tmp_path: Path) -> None:
    import yaml

    data = yaml.safe_load((ROOT / "worlds" / "parcel_pick_place.yaml").read_text())
    data["task"][0]["moves"] = [
        {"goal": {"position": [0.65, 0.0, 0.7], "rpy_deg": [0, 90, 0]}},
        {"goal": {"position": [0.6, 0.1, 0.7], "rpy_deg": [0, 90, 40]}},
        {"goal": {"position": [0.6, -0.1, 0.675], "rpy_deg": [0, 0, 135]}},
    ]
    path = tmp_path / "flips.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    assert feasibility_problems(load_world(path), LATERAL) == []


def test_the_turn_check_goes_on_from_where_an_earlier_task_step_left_the_object(
    tmp_path: Path,
) -> None:
    # It had started every task step from upright: a second step turning the box back by a
    # half turn validated, and one turning it on by a quarter turn was refused.
    import yaml

    data = yaml.safe_load((ROOT / "worlds" / "parcel_pick_place.yaml").read_text())
    first = {"goal": {"position": [0.65, 0.0, 0.7], "rpy_deg": [0, 90, 0]}}

    def problems(second: list[float], z: float) -> list[str]:
        data["task"] = [
            {"object": "parcel", "moves": [first]},
            {
                "object": "parcel",
                "moves": [{"goal": {"position": [0.6, 0.1, z], "rpy_deg": second}}],
            },
        ]
        path = tmp_path / "steps.yaml"
        path.write_text(yaml.safe_dump(data), encoding="utf-8")
        return [p.format("w") for p in feasibility_problems(load_world(path), LATERAL)]

    (back,) = problems([0, -90, 0], 0.7)
    assert back.startswith("w: task[1].moves[0].goal.rpy_deg: expected a goal the grip turns")
    assert "got rpy_deg [0, -90, 0]: a turn of 180 deg about its y axis" in back
    assert problems([0, 180, 0], 0.675) == []  # on over: a quarter turn from where it lay
