"""The experiment's trial generator and campaign bookkeeping (no physics)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from worlds.trials import (
    CLEARANCE_M,
    FOREARM_CLEARANCE_M,
    REGIONS,
    _box_gap,
    draw_trial,
    read_results,
    reason_of,
    summarise,
)
from worlds.world_file import World, load_world

DEFAULT = Path(__file__).resolve().parents[2] / "worlds" / "parcel_pick_place.yaml"


@pytest.fixture(scope="module")
def base() -> World:
    return load_world(DEFAULT)


def test_trials_are_deterministic_and_differ(base: World) -> None:
    a, ka = draw_trial(base, 0, 3)
    b, kb = draw_trial(base, 0, 3)
    c, _ = draw_trial(base, 0, 4)
    assert a.model_dump() == b.model_dump() and ka == kb
    assert a.model_dump() != c.model_dump()


@pytest.mark.parametrize("trial", range(25))
def test_a_trial_meets_the_papers_conditions(base: World, trial: int) -> None:
    world, kinds = draw_trial(base, 7, trial)
    moves = world.task[0].moves
    assert len(moves) == 3
    for move, region in zip(moves, ("centre", "right", "left"), strict=True):
        (x0, x1), (y0, y1) = REGIONS[region]
        assert x0 <= move.goal.position[0] <= x1 and y0 <= move.goal.position[1] <= y1
    assert sum(k != "none" for k in kinds) >= 2  # obstacles on at least two of three moves
    half = np.array([0.10, 0.15, 0.075])
    start = np.array(world.objects[0].pose.position)
    for move in moves:
        goal = np.array(move.goal.position)
        for name in move.obstacles:
            ob = world.obstacle_named(name)
            centre, r = np.array(ob.position), ob.shape.radius  # type: ignore[union-attr]
            for p in (start, goal):
                assert _box_gap(p, half, centre) - r >= CLEARANCE_M - 1e-12
                for side in (1.0, -1.0):
                    palm = p[:2] + [0.0, side * (half[1] + 0.01)]
                    assert np.linalg.norm(centre[:2] - palm) - r >= FOREARM_CLEARANCE_M - 1e-12
        start = goal


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
    done = read_results(path)
    assert sorted(done) == [0, 1]
    s = summarise(done.values())
    assert s["trials"] == 2 and s["successes"] == 1
    assert s["failure_reasons"] == {"obstacle contact: parcel/right_arm": 1}
    assert s["realtime_factor"] == 3.0
    assert reason_of("move 2 placed 3.1 cm, 1.0 deg from its goal") == "move 2"
