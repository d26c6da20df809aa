"""The robot where a run starts: arms standing inside each other are refused before a step."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import app
from worlds.start_checks import start_pose_problems
from worlds.world_file import load_world

WriteWorld = Callable[[dict[str, Any], str], Path]


def test_arms_standing_in_each_other_are_refused_at_validate(
    default_data: dict[str, Any], write_world: WriteWorld, capsys: pytest.CaptureFixture[str]
) -> None:
    # 0.2 m apart the iiwas' bases overlap by 6 cm: the world had validated "ok" and every run
    # failed as "arms touched", from the first physics step.
    default_data["robot"]["arm_separation"] = 0.2
    path = write_world(default_data, "narrow.yaml")
    (problem,) = start_pose_problems(load_world(path))
    assert problem.field == "robot.arm_separation"
    assert problem.received == (
        "0.2 m: the left arm's base is 60 mm into the right arm's base; set them farther apart"
    )
    assert app.main(["validate", str(path)]) == app.EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert f"{path}: robot.arm_separation: expected arms apart where a run starts" in err


def test_arms_apart_and_a_one_body_robot_pass(
    default_data: dict[str, Any], write_world: WriteWorld
) -> None:
    default_data["robot"]["arm_separation"] = 0.3  # the narrowest the iiwas run at, apart
    assert start_pose_problems(load_world(write_world(default_data, "close.yaml"))) == []
    icub = Path(__file__).resolve().parents[2] / "worlds" / "icub_parcel_pick_place.yaml"
    assert start_pose_problems(load_world(icub)) == []
