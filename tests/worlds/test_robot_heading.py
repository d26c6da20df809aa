"""A robot may face the table from any side: a world turned about the vertical is the same task.

Turning a whole world (robot, table, object, obstacles, goals and trial layout) by a quarter
turn about z changes nothing the robot can feel: where its palms wait, how it grips, where a
trial's spheres stand relative to it, and how well it places the parcel.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from numpy.testing import assert_allclose
from pydantic import ValidationError

from experiment.episode import run_episode
from experiment.layout import Posture, RobotClearance, draw_trial
from planner.grips import robot_yaw
from skills import quaternion as quat
from skills.vocabulary import Arm
from worlds.palm_poses import LATERAL_PALM_QUATERNIONS, lateral_grasp_palm_poses, rest_palm_poses
from worlds.sim_world import SimWorld
from worlds.world_file import World, as_world_spec, load_world, world_from_data

ROOT = Path(__file__).resolve().parents[2]
DEFAULT = ROOT / "worlds" / "parcel_pick_place.yaml"


def _turn_xy(point: list[float], quarter_turns: int) -> list[float]:
    x, y = point[0], point[1]
    for _ in range(quarter_turns % 4):
        x, y = -y, x
    return [x, y, *point[2:]]


def _turn_region(region: dict[str, Any], quarter_turns: int) -> dict[str, Any]:
    """A trial region {x: [lo, hi], y: [lo, hi]} turned by quarter turns about the origin."""
    x, y = list(region["x"]), list(region["y"])
    for _ in range(quarter_turns % 4):
        x, y = [-y[1], -y[0]], x
    return {**region, "x": x, "y": y}


def turned_world(world: World, quarter_turns: int, trials: bool = True) -> World:
    """``world`` turned about the world's z axis through the origin by ``quarter_turns``
    (its trial layout too, or, without ``trials``, left out)."""
    data = copy.deepcopy(world.model_dump(mode="json"))
    deg = 90.0 * quarter_turns
    robot = data["robot"]["base"]
    robot["position"] = _turn_xy(robot["position"], quarter_turns)
    robot["rpy_deg"][2] += deg
    table = data["table"]
    table["position"] = _turn_xy(table["position"], quarter_turns)
    if quarter_turns % 2:
        table["size"] = [table["size"][1], table["size"][0], table["size"][2]]
    for obj in data["objects"]:
        obj["pose"]["position"] = _turn_xy(obj["pose"]["position"], quarter_turns)
        obj["pose"]["rpy_deg"][2] += deg
    for obstacle in data["obstacles"]:
        obstacle["position"] = _turn_xy(obstacle["position"], quarter_turns)
    for fixture in data.get("fixtures") or []:
        fixture["position"] = _turn_xy(fixture["position"], quarter_turns)
        fixture["yaw_deg"] += deg
    for push in data.get("disturbances") or []:
        for key in ("force_n", "torque_nm"):
            if push.get(key) is not None:
                push[key] = _turn_xy(push[key], quarter_turns)
    for step in data["task"]:
        for move in step["moves"]:
            move["goal"]["position"] = _turn_xy(move["goal"]["position"], quarter_turns)
            move["goal"]["rpy_deg"][2] += deg
    if not trials:
        data.pop("trials", None)
    elif data.get("trials"):
        trials = data["trials"]
        for key in ("start", "centre", "right", "left"):
            trials[key] = _turn_region(trials[key], quarter_turns)
        trials["goal_yaw_deg"] = [a + deg for a in trials["goal_yaw_deg"]]
    data["name"] = f"{data['name']}_turned_{quarter_turns}"
    return world_from_data(data, world.source)


def _rotation(quarter_turns: int) -> np.ndarray:
    c, s = math.cos(quarter_turns * math.pi / 2.0), math.sin(quarter_turns * math.pi / 2.0)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_the_default_robot_waits_above_the_table_s_near_edge() -> None:
    poses = rest_palm_poses(as_world_spec(load_world(DEFAULT)).scene, (0.10, 0.38, 0.25))
    # The table's near edge is at x = 0.65 - 0.3; its top at 0.6.
    assert_allclose(poses[Arm.LEFT][0], [0.45, 0.38, 0.85])
    assert_allclose(poses[Arm.RIGHT][0], [0.45, -0.38, 0.85])
    for arm in (Arm.LEFT, Arm.RIGHT):
        assert_allclose(poses[arm][1], LATERAL_PALM_QUATERNIONS[arm], atol=1e-12)


ICUB = ROOT / "worlds" / "icub_parcel_pick_place.yaml"


def _icub_parcel_at(y: float) -> World:
    """The iCub's world with its parcel starting ``y`` m to the side (its goals' y), carried to
    the centre in one move."""
    world = load_world(ICUB)
    data = world.model_dump(mode="json")
    start = data["objects"][0]["pose"]["position"]
    data["objects"][0]["pose"]["position"] = [start[0], y, start[2]]
    data["task"] = [
        {"object": data["objects"][0]["name"], "moves": [dict(data["task"][0]["moves"][0])]}
    ]
    return world_from_data(data, world.source)


def test_a_palm_waits_above_an_object_that_stands_where_it_would_wait() -> None:
    # The iCub's palms wait 14 cm to the side, 10 cm over the table: inside a parcel put at
    # its own world's left or right goal, which they knocked off the table.
    rest = (0.08, 0.14, 0.10)
    shipped = rest_palm_poses(as_world_spec(load_world(ICUB)).scene, rest)
    moved = as_world_spec(_icub_parcel_at(0.12)).scene
    waiting = rest_palm_poses(moved, rest)
    parcel = moved.objects[0]
    top = parcel.position[2] + 0.5 * parcel.shape.extents()[2]
    assert waiting[Arm.LEFT][0][2] > top + 0.03  # above it, with room
    assert_allclose(waiting[Arm.LEFT][0][:2], shipped[Arm.LEFT][0][:2])  # only raised
    assert_allclose(waiting[Arm.RIGHT][0], shipped[Arm.RIGHT][0])  # the other palm is clear


@pytest.mark.sim
def test_the_icub_carries_a_parcel_from_where_its_palm_waits() -> None:
    report = run_episode(_icub_parcel_at(-0.12), None, out=None, animation=False)
    assert report.success, report.failure


@pytest.mark.parametrize("quarter_turns", [1, 2, 3])
def test_the_waiting_palms_turn_with_the_world(quarter_turns: int) -> None:
    world = load_world(DEFAULT)
    rest = (0.10, 0.38, 0.25)
    before = rest_palm_poses(as_world_spec(world).scene, rest)
    turned = turned_world(world, quarter_turns)
    after = rest_palm_poses(as_world_spec(turned).scene, rest)
    turn = quat.from_axis_angle(np.array([0.0, 0.0, 1.0]), quarter_turns * math.pi / 2.0)
    for arm in (Arm.LEFT, Arm.RIGHT):
        assert_allclose(after[arm][0], _rotation(quarter_turns) @ before[arm][0], atol=1e-12)
        expected = quat.multiply(turn, before[arm][1])
        # q and -q are the same orientation.
        assert (
            min(np.abs(after[arm][1] - expected).max(), np.abs(after[arm][1] + expected).max())
            < 1e-12
        )


def test_a_robot_off_the_table_s_centre_line_waits_either_side_of_its_own() -> None:
    data = load_world(DEFAULT).model_dump(mode="json")
    data["robot"]["base"]["position"] = [0.0, 0.1, 0.0]
    poses = rest_palm_poses(as_world_spec(world_from_data(data, DEFAULT)).scene, (0.1, 0.38, 0.25))
    assert_allclose([poses[Arm.LEFT][0][1], poses[Arm.RIGHT][0][1]], [0.48, -0.28])


def test_the_robot_s_clearance_poses_its_grip_turned_with_it() -> None:
    """A sphere where the turned robot's left palm holds the box touches the robot."""
    world = turned_world(load_world(DEFAULT), 1)
    centre = np.array([0.0, 0.6, 0.675])
    half_span = 0.15  # the parcel's y extent, 0.30 m, as gripped on its +-y faces
    palms = lateral_grasp_palm_poses(centre, half_span, 0.02, grip_yaw=math.pi / 2.0)
    with RobotClearance(world) as robot:
        posture = Posture(centre, math.pi / 2.0, 0.0, half_span)
        assert robot.distance(posture, palms[Arm.LEFT][0], 0.01) < 0.0
        # Where the palm would stand with the grip not turned, nothing of the robot is.
        unturned = lateral_grasp_palm_poses(centre, half_span, 0.02)
        assert robot.distance(posture, unturned[Arm.LEFT][0], 0.01) > 0.02


def test_spheres_ahead_stand_in_front_of_the_turned_robot() -> None:
    world = turned_world(load_world(DEFAULT), 1)  # the robot faces +y
    ahead = 0
    with RobotClearance(world) as robot:
        for trial in range(6):
            drawn, kinds = draw_trial(world, 0, trial, robot)
            moves = drawn.task[0].moves
            starts = [drawn.objects[0].pose.position, *(m.goal.position for m in moves[:-1])]
            for kind, move, start in zip(kinds, moves, starts, strict=True):
                if kind != "ahead":
                    continue
                ahead += 1
                (name,) = move.obstacles
                sphere = next(o for o in drawn.obstacles if o.name == name)
                # Beyond the start and the goal along the robot's forward axis (+y here).
                assert sphere.position[1] > max(start[1], move.goal.position[1]) + 0.1
    assert ahead


def test_the_default_world_turned_a_quarter_turn_is_done_as_well() -> None:
    world = load_world(DEFAULT)
    turned = turned_world(world, 1)
    with SimWorld(turned) as sim:
        assert math.degrees(robot_yaw(sim)) == pytest.approx(90.0, abs=1e-6)
    base = run_episode(world, animation=False)
    report = run_episode(turned, animation=False)
    assert base.success and report.success, report.failure
    assert not report.obstacle_contacts
    assert_allclose(report.placement_error_m, base.placement_error_m, atol=0.002)


def test_the_icub_turned_a_quarter_turn_places_as_it_does_unturned() -> None:
    """One body carrying both arms (and a torso): its palms wait, and its grips turn, with it."""
    world = load_world(ROOT / "worlds" / "icub_parcel_pick_place.yaml")
    report = run_episode(turned_world(world, 1, trials=False), animation=False)
    assert report.success, report.failure
    assert not report.obstacle_contacts
    assert all(e is not None and e < 0.005 for e in report.placement_error_m)


def test_a_robot_facing_minus_x_draws_its_goal_yaws_across_180_degrees() -> None:
    """[90, 270] is to a robot facing -x what [-90, 90] is to one facing +x."""
    world = turned_world(load_world(DEFAULT), 2)
    assert world.trials.goal_yaw_deg == (90.0, 270.0)
    with RobotClearance(world) as robot:
        for trial in range(3):
            drawn, _ = draw_trial(world, 0, trial, robot)
            for move in drawn.task[0].moves:
                yaw = move.goal.rpy_deg[2]
                assert 90.0 <= yaw <= 270.0 or (yaw - 90.0) % 360.0 <= 180.0


@pytest.mark.parametrize("yaws", [(-200.0, 200.0), (-400.0, -300.0), (100.0, 370.0)])
def test_a_goal_yaw_range_is_one_turn_within_two(yaws: tuple[float, float]) -> None:
    data = load_world(DEFAULT).model_dump(mode="json")
    data["trials"]["goal_yaw_deg"] = list(yaws)
    with pytest.raises(ValidationError, match="spanning at most one turn"):
        world_from_data(data, DEFAULT)
