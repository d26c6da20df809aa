"""Trials of a world with other objects standing on the table: the drawn object, its goals and
spheres keep out of them; a task moving more than one object is refused before a campaign."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from experiment.layout import TrialLayoutError, check_trial_layout, draw_trial
from worlds.placement import start_problems
from worlds.world_file import load_world, world_from_data, world_spec

ROOT = Path(__file__).resolve().parents[2]
DEFAULT = ROOT / "worlds" / "parcel_pick_place.yaml"
TWO = ROOT / "tests" / "data" / "worlds" / "two_parcels.yaml"


def with_crate(position: list[float]) -> Any:
    world = load_world(DEFAULT)
    data = world.model_dump(mode="json")
    crate = dict(data["objects"][0], name="crate")
    crate["shape"] = {"type": "box", "size": [0.12, 0.12, 0.1]}
    crate["pose"] = {"position": position, "rpy_deg": [0.0, 0.0, 0.0]}
    data["objects"].append(crate)
    return world_from_data(data, world.source)


def test_a_task_that_moves_two_objects_is_refused_before_a_campaign() -> None:
    with pytest.raises(TrialLayoutError) as err:
        check_trial_layout(load_world(TWO), 0, "two.yaml")
    assert str(err.value) == (
        "two.yaml: task: expected a task that moves objects[0] ('parcel_left') alone for trials "
        "(each trial draws its start, goals and spheres; the other objects stand where the file "
        "puts them), got moves of 'parcel_right' too"
    )


def test_the_drawn_trials_keep_out_of_a_crate_standing_in_a_goal_region() -> None:
    # The crate stands beside the right goal region (x 0.55-0.65, y -0.18..-0.12), where a
    # 0.30 m wide parcel at some of its goals reaches it: those draws are drawn again.
    base = with_crate([0.62, -0.36, 0.65])
    check_trial_layout(base, 0, "w.yaml")
    redrawn = 0
    for trial in range(12):
        world, _ = draw_trial(base, 0, trial)
        assert [o.name for o in world.objects] == ["parcel", "crate"]
        assert world.objects[1].pose.position == (0.62, -0.36, 0.65)
        assert start_problems(world_spec(world)) == []
        first, _ = draw_trial(load_world(DEFAULT), 0, trial)
        redrawn += first.task[0].moves[1].goal.position != world.task[0].moves[1].goal.position
    assert redrawn > 0  # the crate was in the way of some draws, and they were drawn again


@pytest.mark.sim
def test_a_standing_crate_shoved_in_physics_is_measured_from_where_it_stood() -> None:
    # What the judge reads of a bystander (experiment.judge, ``standing``): the crate, not the
    # task's parcel, measured from its start; a tray's loose ball is the tray's to judge.
    import pybullet as pb

    from experiment.episode import move_keys, robot_moves
    from experiment.move_recorder import MoveRecorder
    from worlds.sim_world import SimWorld

    world = with_crate([0.62, -0.36, 0.65])
    with SimWorld(world) as sim:
        recorder = MoveRecorder(sim, move_keys(world), robot_moves(world), 1 / 60)
        assert set(recorder.standing) == {"crate"}
        assert recorder.standing_moved() == [("crate", 0.0, 0.0)]
        crate, c = sim.scene.object_ids["crate"], sim.scene.client
        for _ in range(60):  # a quarter second's sideways shove at its centre
            pb.applyExternalForce(
                crate, -1, [0.0, 8.0, 0.0], [0, 0, 0], pb.LINK_FRAME, physicsClientId=c
            )
            sim.scene.step(1)
        for _ in range(120):
            sim.scene.step(1)
        ((name, metres, _),) = recorder.standing_moved()
        assert name == "crate" and 0.03 < metres < 0.3, metres
    with SimWorld(load_world(ROOT / "worlds" / "tray_carry.yaml")) as sim:
        tray = load_world(ROOT / "worlds" / "tray_carry.yaml")
        recorder = MoveRecorder(sim, move_keys(tray), robot_moves(tray), 1 / 60)
        assert recorder.standing == {}  # the ball rides on the tray
