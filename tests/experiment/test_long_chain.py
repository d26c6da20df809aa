"""The long chain (``worlds/long_chain.yaml``) and trials sections with any number of moves."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from numpy.testing import assert_allclose

from experiment.episode import run_episode
from experiment.layout import RobotClearance, draw_trial
from experiment.preflight import preflight_problems
from worlds.world_file import World, load_world, world_from_data

WORLDS = Path(__file__).resolve().parents[2] / "worlds"
LONG_CHAIN = WORLDS / "long_chain.yaml"
DEFAULT = WORLDS / "parcel_pick_place.yaml"


@pytest.fixture(scope="module")
def chain() -> World:
    return load_world(LONG_CHAIN)


@pytest.fixture(scope="module")
def robot(chain: World) -> Iterator[RobotClearance]:
    # The same robot and parcel as the default world: one clearance scene serves both.
    with RobotClearance(chain) as clearance:
        yield clearance


def _with_trials(world: World, trials: dict[str, Any]) -> World:
    data = world.model_dump(mode="json")
    data["trials"] = trials
    return world_from_data(data, world.source)


def test_the_long_chain_is_eight_moves_each_with_a_new_obstacle(chain: World) -> None:
    assert preflight_problems(chain, str(LONG_CHAIN)) == []
    moves = chain.task[0].moves
    assert len(chain.task) == 1 and len(moves) == 8
    named = [name for move in moves for name in move.obstacles]
    assert all(len(move.obstacles) == 1 for move in moves) and len(set(named)) == 8
    assert all(-90.0 <= move.goal.rpy_deg[2] <= 90.0 for move in moves)
    assert len({move.goal.rpy_deg[2] for move in moves}) > 4  # goals turned, not one yaw
    assert len(chain.trials.goal_regions()) == 8


@pytest.fixture(scope="module")
def drawn(chain: World, robot: RobotClearance) -> tuple[World, list[str]]:
    """Trial 0 of seed 0 of the chain's trials section (drawing eight moves takes seconds)."""
    return draw_trial(chain, 0, 0, robot)


def test_the_shipped_task_is_a_trial_of_its_own_section_rounded(
    chain: World, drawn: tuple[World, list[str]]
) -> None:
    world, kinds = drawn
    assert kinds.count("none") == 0
    assert_allclose(chain.objects[0].pose.position, world.objects[0].pose.position, atol=5e-4)
    for shipped, move in zip(chain.task[0].moves, world.task[0].moves, strict=True):
        assert_allclose(shipped.goal.position, move.goal.position, atol=5e-4)
        assert_allclose(shipped.goal.rpy_deg, move.goal.rpy_deg, atol=0.5)
        assert shipped.obstacles == move.obstacles
    for shipped_ball, ball in zip(chain.obstacles, world.obstacles, strict=True):
        assert shipped_ball.name == ball.name
        assert_allclose(shipped_ball.position, ball.position, atol=5e-4)


def test_n_moves_draw_each_goal_in_its_region(chain: World, drawn: tuple[World, list[str]]) -> None:
    # From (seed, trial) alone: the shipped task, drawn once and written down, is drawn again
    # (test_the_shipped_task_is_a_trial_of_its_own_section_rounded).
    world, kinds = drawn
    moves = world.task[0].moves
    regions = chain.trials.goal_regions()
    assert len(moves) == len(kinds) == 8
    for move, region in zip(moves, regions, strict=True):
        x, y, _ = move.goal.position
        assert region.x[0] <= x <= region.x[1] and region.y[0] <= y <= region.y[1]
        assert region.yaw_deg is not None
        assert region.yaw_deg[0] <= move.goal.rpy_deg[2] <= region.yaw_deg[1]
    assert sum(k != "none" for k in kinds) >= 7  # at least seven of eight moves
    named = [name for move in moves for name in move.obstacles]
    assert len(named) == len(set(named)) == len(world.obstacles)  # each sphere new


def test_the_papers_regions_draw_as_the_recorded_campaigns_did() -> None:
    # Trial 0 of seed 0 of the default world, as drawn before trials could list moves.
    world, kinds = draw_trial(load_world(DEFAULT), 0, 0)
    assert kinds == ["line", "none", "ahead"]
    assert_allclose(
        world.objects[0].pose.position, [0.5636961687321455, -0.018417062898890377, 0.675]
    )
    goals = [m.goal.position for m in world.task[0].moves]
    assert_allclose(
        goals,
        [
            [0.5840973523936195, -0.029008341868288254, 0.675],
            [0.6313270239200273, -0.1252346653633367, 0.675],
            [0.610663577576718, 0.1637697936590399, 0.675],
        ],
        rtol=0,
        atol=1e-15,
    )
    yaws = [m.goal.rpy_deg[2] for m in world.task[0].moves]
    assert_allclose(yaws, [-9.137012613899827, -19.61250509961691, 13.854381357806787], atol=0)
    ball = world.obstacle_named("ball_3")
    assert_allclose(ball.position, [0.8439019139036036, 0.019267564147851607, 0.7606942043409506])


def test_the_papers_regions_written_as_moves_draw_the_same(robot: RobotClearance) -> None:
    paper = load_world(DEFAULT)
    layout = paper.trials.model_dump(mode="json")
    as_moves = {k: v for k, v in layout.items() if k not in ("centre", "right", "left")}
    as_moves["moves"] = [layout[k] for k in ("centre", "right", "left")]
    listed = _with_trials(paper, as_moves)
    assert "centre" not in listed.model_dump()["trials"]
    assert "moves" not in paper.model_dump()["trials"]  # its content hash is as it was
    assert world_from_data(listed.model_dump(mode="json"), DEFAULT) == listed  # round trip
    for trial in (1, 4):  # goals turned, spheres of both kinds
        a, ka = draw_trial(paper, 1, trial, robot)
        b, kb = draw_trial(listed, 1, trial, robot)
        assert ka == kb
        for part in ("objects", "obstacles", "task"):
            assert getattr(a, part) == getattr(b, part)


def test_a_moves_kinds_and_yaw_are_its_own(robot: RobotClearance) -> None:
    paper = load_world(DEFAULT)
    layout = paper.trials.model_dump(mode="json")
    layout = {k: v for k, v in layout.items() if k not in ("centre", "right", "left")}
    layout["goal_yaw_deg"] = [0.0, 0.0]
    layout["moves"] = [
        {"x": [0.62, 0.68], "y": [-0.03, 0.03], "obstacles": []},
        {"x": [0.55, 0.65], "y": [-0.18, -0.12], "obstacles": ["ahead"], "yaw_deg": [30, 30]},
        {"x": [0.55, 0.65], "y": [0.12, 0.18], "obstacles": ["ahead"]},
    ]
    world = _with_trials(paper, layout)
    for trial in range(4):
        drawn, kinds = draw_trial(world, 2, trial, robot)
        assert kinds[0] == "none" and set(kinds[1:]) <= {"ahead", "none"}
        yaws = [m.goal.rpy_deg[2] for m in drawn.task[0].moves]
        assert yaws == [0.0, 30.0, 0.0]


@pytest.mark.sim
def test_the_chains_first_three_moves_are_placed_in_physics(chain: World) -> None:
    # The chain's first three moves (two turned, each with its sphere) in one episode; the
    # whole chain is app.py run worlds/long_chain.yaml (some 130 s simulated).
    data = chain.model_dump(mode="json")
    moves = data["task"][0]["moves"][:3]
    data["task"][0]["moves"] = moves
    names = {name for move in moves for name in move["obstacles"]}
    data["obstacles"] = [o for o in data["obstacles"] if o["name"] in names]
    report = run_episode(world_from_data(data, chain.source), out=None, animation=False)
    assert report.success, report.failure
    assert len(report.placement_error_m) == 3
    for err_m, err_deg in zip(report.placement_error_m, report.placement_error_deg, strict=True):
        assert err_m is not None and err_m < 0.02
        assert err_deg is not None and err_deg < 10.0
    assert not report.obstacle_contacts and report.arm_contacts == 0
    assert math.isfinite(report.min_obstacle_distance_m) and report.min_obstacle_distance_m > 0
