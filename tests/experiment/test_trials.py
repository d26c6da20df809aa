"""The experiment's trial generator and campaign bookkeeping."""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from experiment.layout import Posture, RobotClearance, _box_gap, draw_trial, move_postures
from experiment.results import read_results
from experiment.trials import campaign_of, campaign_results, reason_of, summarise
from worlds.adapters import robot_capabilities
from worlds.palm_poses import lateral_grasp_palm_poses
from worlds.world_file import World, load_world, world_from_data

WORLDS = Path(__file__).resolve().parents[2] / "worlds"


@pytest.fixture(scope="module", params=["parcel_pick_place.yaml", "icub_parcel_pick_place.yaml"])
def base(request: pytest.FixtureRequest) -> World:
    return load_world(WORLDS / request.param)


@pytest.fixture(scope="module")
def robot(base: World) -> Iterator[RobotClearance]:
    with RobotClearance(base) as clearance:
        yield clearance


def test_trials_are_deterministic_and_differ(base: World, robot: RobotClearance) -> None:
    a, ka = draw_trial(base, 0, 3, robot)
    b, kb = draw_trial(base, 0, 3, robot)
    c, _ = draw_trial(base, 0, 4, robot)
    assert a.model_dump() == b.model_dump() and ka == kb
    assert a.model_dump() != c.model_dump()


def test_a_scene_of_its_own_draws_the_same_trial(base: World, robot: RobotClearance) -> None:
    assert draw_trial(base, 5, 1)[0].model_dump() == draw_trial(base, 5, 1, robot)[0].model_dump()


@pytest.mark.sim
def test_robot_clearance_knows_where_the_palms_are(base: World, robot: RobotClearance) -> None:
    centre = np.array(base.objects[0].pose.position)
    half_span = base.objects[0].shape.size[1] / 2.0  # type: ignore[union-attr]
    for grip in (0.0, math.radians(20.0)):
        posture = Posture(centre, grip, grip, half_span)
        palms = lateral_grasp_palm_poses(centre, half_span, base.robot.palm_size[2], grip_yaw=grip)
        for position, _ in palms.values():
            assert robot.distance(posture, position, 0.01) < 0.0  # a ball inside the palm
    far = centre + np.array([0.0, 0.0, 1.5])
    assert robot.distance(Posture(centre, 0.0, 0.0, half_span), far, 0.01) > 0.3


@pytest.mark.parametrize("trial", range(12))
def test_a_trial_meets_the_papers_conditions(
    base: World, robot: RobotClearance, trial: int
) -> None:
    world, kinds = draw_trial(base, 7, trial, robot)
    layout = base.trials
    moves = world.task[0].moves
    assert len(moves) == 3
    for move, region in zip(moves, layout.goal_regions(), strict=True):
        (x0, x1), (y0, y1) = region.x, region.y
        assert x0 <= move.goal.position[0] <= x1 and y0 <= move.goal.position[1] <= y1
    assert sum(k != "none" for k in kinds) >= 2  # obstacles on at least two of three moves
    size = np.array(base.objects[0].shape.size)  # type: ignore[union-attr]
    start = np.array(world.objects[0].pose.position)
    start_yaw = math.radians(world.objects[0].pose.rpy_deg[2])
    max_turn = robot_capabilities(base).max_turn_rad
    for move in moves:
        goal = np.array(move.goal.position)
        goal_yaw = math.radians(move.goal.rpy_deg[2])
        lo_yaw, hi_yaw = layout.goal_yaw_deg
        assert lo_yaw <= move.goal.rpy_deg[2] <= hi_yaw
        postures = move_postures(start, start_yaw, goal, goal_yaw, size, max_turn)
        for name in move.obstacles:
            ob = world.obstacle_named(name)
            centre, r = np.array(ob.position), ob.shape.radius  # type: ignore[union-attr]
            lo, hi = layout.sphere_radius
            assert lo <= r <= hi
            for p in postures:
                gap = _box_gap(p.position, size / 2.0, centre, p.object_yaw)
                assert gap - r >= layout.clearance - 1e-12
                for dz in (0.0, layout.lift):
                    lifted = replace(p, position=p.position + [0.0, 0.0, dz])
                    assert robot.distance(lifted, centre, r) >= layout.robot_clearance - 1e-12
        start, start_yaw = goal, goal_yaw


def test_trials_draw_each_goal_yaw_from_the_seed(base: World, robot: RobotClearance) -> None:
    turned = base.model_copy(
        update={"trials": base.trials.model_copy(update={"goal_yaw_deg": (-90.0, 90.0)})}
    )
    flat = base.model_copy(
        update={"trials": base.trials.model_copy(update={"goal_yaw_deg": (0.0, 0.0)})}
    )
    a, _ = draw_trial(turned, 3, 2, robot)
    b, _ = draw_trial(turned, 3, 2, robot)
    yaws = [m.goal.rpy_deg[2] for m in a.task[0].moves]
    assert yaws == [m.goal.rpy_deg[2] for m in b.task[0].moves]
    assert all(-90.0 <= y <= 90.0 for y in yaws) and len(set(yaws)) == 3
    # Without turns the same starts and goals as ever, at yaw 0.
    c, _ = draw_trial(flat, 3, 2, robot)
    assert [m.goal.rpy_deg[2] for m in c.task[0].moves] == [0.0, 0.0, 0.0]
    assert [m.goal.position for m in c.task[0].moves] == [m.goal.position for m in a.task[0].moves]


def test_move_postures_hold_the_faces_of_each_step() -> None:
    size = np.array([0.2, 0.3, 0.15])
    start, goal = np.array([0.55, 0.0, 0.675]), np.array([0.65, 0.0, 0.675])
    postures = move_postures(start, 0.0, goal, math.radians(90), size, math.radians(45))
    assert [round(math.degrees(p.grip_yaw)) for p in postures] == [0, 45, -45, 0]
    assert [p.half_span for p in postures] == [0.15, 0.15, 0.1, 0.1]
    assert_allclose(postures[0].position, start)
    assert all(np.array_equal(p.position, goal) for p in postures[1:])


def test_results_resume_and_summarise(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    rows = [
        {
            "trial": 0,
            "seed": 1,
            "success": True,
            "failure": "",
            "sim_time_s": 20.0,
            "wall_time_s": 5.0,
            "min_obstacle_distance_m": 0.02,
            "compositions": [
                {"transport_weight": 1.0, "avoid_gain": 0.0},
                {"transport_weight": 0.25, "avoid_gain": 0.0},
                {"transport_weight": 1.0, "avoid_gain": 0.0},
            ],
        },
        {
            "trial": 1,
            "seed": 1,
            "success": False,
            "sim_time_s": 10.0,
            "wall_time_s": 5.0,
            "failure": "obstacle contact: right_arm ~ ball_3, parcel ~ ball_3",
        },
    ]
    path.write_text("\n".join(json.dumps(r) for r in rows) + '\n{"trial": 2, "se')  # torn line
    read = read_results(path)
    done = read.records
    assert [r["trial"] for r in done] == [0, 1] and read.skipped == 1
    s = summarise(done)
    assert s["trials"] == 2 and s["successes"] == 1
    assert s["failure_reasons"] == {"obstacle contact: parcel/right_arm": 1}
    assert s["realtime_factor"] == 3.0
    assert s["compositions"] == {
        "pick-and-place x1, no avoidance": 2,
        "pick-and-place x0.25, no avoidance": 1,
    }
    assert reason_of("move 2 placed 3.1 cm, 1.0 deg from its goal") == "move 2"
    assert reason_of("not placed: parcel move 2, parcel move 3") == "not placed"
    # The figures of a knock are its own, not a category of their own.
    for knock in ("4.0 cm, 16.9 deg", "5.3 cm, 20.0 deg"):
        failure = f"parcel moved {knock} after it was placed"
        assert reason_of(failure) == "parcel moved after it was placed"
    assert reason_of("stopped: time limit 120 s reached; task.move: 0.2 of 6.6 s") == "stopped"


def test_a_campaign_owns_the_records_of_its_world_seed_and_tree(tmp_path: Path) -> None:
    iiwa = load_world(WORLDS / "parcel_pick_place.yaml")
    icub = load_world(WORLDS / "icub_parcel_pick_place.yaml")
    tree = WORLDS.parent / "planner" / "trees" / "pick_and_place.xml"
    key = campaign_of(iiwa, 0, None)
    assert key["world"] == iiwa.name and len(key["world_sha256"]) == 64
    with_tree = campaign_of(iiwa, 0, tree)
    assert with_tree["tree"] == "planner/trees/pick_and_place.xml"  # relative: merges
    assert len(with_tree["tree_sha256"]) == 64
    results = tmp_path / "results.jsonl"
    records = [
        {"trial": 0, **key, "success": True},
        {"trial": 1, **with_tree, "success": True},
        {"trial": 0, **key, "success": False},  # run again: the last counts
        {"trial": 2, **campaign_of(iiwa, 1, None), "success": True},
        {"trial": 3, **campaign_of(icub, 0, None), "success": True},
        {"trial": 4, "seed": 0, "tree": "", "success": True},  # an old record: no world
    ]
    results.write_text("".join(json.dumps(r) + "\n" for r in records), encoding="utf-8")
    assert sorted(campaign_results(results, key)) == [0]
    assert campaign_results(results, key)[0]["success"] is False
    assert list(campaign_results(results, with_tree)) == [1]
    assert list(campaign_results(results, campaign_of(iiwa, 1, None))) == [2]
    assert list(campaign_results(results, campaign_of(icub, 0, None))) == [3]
    # A world that differs in anything but its name is another campaign.
    data = iiwa.model_dump(mode="json")
    data["sim"]["seed"] = int(data["sim"].get("seed") or 0) + 1
    assert not campaign_results(results, campaign_of(world_from_data(data, iiwa.source), 0, None))
    # So is a tree file whose content changed, at the same path.
    own = tmp_path / "tree.xml"
    own.write_bytes(tree.read_bytes())
    before = campaign_of(iiwa, 0, own)
    own.write_bytes(tree.read_bytes() + b"\n")
    assert campaign_of(iiwa, 0, own)["tree_sha256"] != before["tree_sha256"]
    assert campaign_of(iiwa, 0, own)["tree"] == own.name  # outside the project: its name


def test_a_negative_clearance_counts_as_an_obstacle_contact() -> None:
    records = [
        {
            "trial": 0,
            "seed": 0,
            "success": False,
            "obstacle_contacts": {},
            "min_obstacle_distance_m": -0.04,
            "failure": "obstacle penetration: a ~ b overlap",
        },
        {
            "trial": 1,
            "seed": 0,
            "success": True,
            "obstacle_contacts": {},
            "min_obstacle_distance_m": 0.02,
            "failure": "",
        },
    ]
    s = summarise(records)
    assert s["obstacle_contacts"] == 1
    assert s["failure_reasons"] == {"obstacle penetration": 1}


def test_a_shared_robot_draws_each_trial_as_one_of_its_own(
    base: World, robot: RobotClearance
) -> None:
    # The shared robot solves each posture once per draw, from the robot as loaded, as a
    # scene of its own does: the trials drawn in a row are those drawn alone, bit for bit.
    in_a_row = [draw_trial(base, 2, t, robot)[0].model_dump() for t in (4, 0, 4)]
    alone = [draw_trial(base, 2, t)[0].model_dump() for t in (4, 0)]
    assert in_a_row == [alone[0], alone[1], alone[0]]


@pytest.mark.sim
def test_robot_clearance_measures_within_a_reach(base: World, robot: RobotClearance) -> None:
    centre = np.array(base.objects[0].pose.position)
    posture = Posture(centre, 0.0, 0.0, base.objects[0].shape.size[1] / 2.0)  # type: ignore[union-attr]
    ball = centre + np.array([0.0, 0.0, 0.3])
    gap = robot.distance(posture, ball, 0.02)
    assert 0.0 < gap < 0.3
    assert robot.distance(posture, ball, 0.02, within=gap + 0.01) == gap
    assert robot.distance(posture, ball, 0.02, within=gap - 0.01) == math.inf


def test_a_worker_keeps_one_robot_per_base_world() -> None:
    from experiment.trials import _close_worker_clearance, _worker_clearance

    iiwas = load_world(WORLDS / "parcel_pick_place.yaml")
    icub = load_world(WORLDS / "icub_parcel_pick_place.yaml")
    first = _worker_clearance(iiwas)
    assert _worker_clearance(iiwas) is first  # built once for its campaign's world
    other = _worker_clearance(icub)
    assert other is not first  # another world: another robot, the first one closed
    assert draw_trial(icub, 3, 2, other)[0].model_dump() == draw_trial(icub, 3, 2)[0].model_dump()
    _close_worker_clearance()


def test_a_tree_given_as_written_that_lacks_a_trials_moves_fails_it_at_once() -> None:
    from experiment.episode import robot_moves
    from experiment.trials import campaign_of, run_trial
    from planner.default_tree import PICK_AND_PLACE_XML

    base = load_world(WORLDS / "parcel_pick_place.yaml")
    # Trial 1 of seed 0 turns goals further than one grip can: seven moves, not three.
    trial, _ = draw_trial(base, 0, 1)
    assert sum(len(m) for m in robot_moves(trial).values()) > 3
    payload = {
        "world": base.model_dump(mode="json"),
        "source": str(base.source),
        "tree": str(PICK_AND_PLACE_XML),
        "key": campaign_of(base, 0, PICK_AND_PLACE_XML),
    }
    record = run_trial((payload, 0, 1))
    assert not record["success"] and record["sim_time_s"] == 0.0
    assert record["failure"].startswith("tree does not fit this trial's task: ")
    assert "would be left undone" in record["failure"]
    assert "the world's tree field" in record["failure"]


def test_a_trial_whose_layout_cannot_be_drawn_is_recorded_as_not_drawn() -> None:
    from experiment.trials import campaign_of, run_trial

    base = load_world(WORLDS / "parcel_pick_place.yaml")
    data = base.model_dump(mode="json")
    data["trials"]["clearance"] = 5.0  # no sphere is 5 m from the parcel and on its way
    tight = world_from_data(data, base.source)
    payload = {
        "world": data,
        "source": str(base.source),
        "tree": None,
        "key": campaign_of(tight, 0, None),
    }
    record = run_trial((payload, 0, 4))
    assert not record["success"] and record["sim_time_s"] == 0.0
    assert record["failure"] == (
        "layout not drawn: the sphere drawn for a move (ball_2): none of 200 drawn kept clear "
        "of the object and the robot at the move's start and goal (widen the trials regions, "
        "draw smaller or farther spheres: trials.sphere_radius, line_gap, ahead_gap, or lower "
        "trials.clearance or trials.robot_clearance)"
    )
    assert reason_of(record["failure"]) == "layout not drawn"


def test_a_move_the_world_carries_with_its_own_skill_keeps_it_in_every_trial() -> None:
    # A campaign of a world whose move 1 names a taught skill had run every trial with the
    # plan's transport skill instead, silently (the drawn task dropped `skill`).
    base = load_world(WORLDS / "parcel_pick_place.yaml")
    data = base.model_dump(mode="json")
    data["task"][0]["moves"][1]["skill"] = "pick_and_place"
    world = world_from_data(data, base.source)
    for trial in range(3):
        drawn, _ = draw_trial(world, 0, trial)
        assert [m.skill for m in drawn.task[0].moves] == [None, "pick_and_place", None]
        plain, _ = draw_trial(base, 0, trial)
        assert [m.goal for m in drawn.task[0].moves] == [m.goal for m in plain.task[0].moves]
