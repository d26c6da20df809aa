"""Bodies that start sunk into the table or inside each other (issue 15, item 19)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from worlds.placement import start_problems
from worlds.world_file import load_world, world_from_data, world_spec

ROOT = Path(__file__).resolve().parents[2]
DEFAULT = ROOT / "worlds" / "parcel_pick_place.yaml"
TWO = ROOT / "tests" / "data" / "worlds" / "two_parcels.yaml"


def problems(path: Path, edit: Callable[[dict[str, Any]], None]) -> list[tuple[str | None, str]]:
    world = load_world(path)
    data = world.model_dump(mode="json")
    edit(data)
    spec = world_spec(world_from_data(data, world.source))
    return [(p.field, f"expected {p.expected}, got {p.received}") for p in start_problems(spec)]


def test_the_shipped_worlds_start_clear() -> None:
    assert problems(DEFAULT, lambda d: None) == []
    assert problems(TWO, lambda d: None) == []


def test_a_parcel_sunk_into_the_table() -> None:
    def sink(d: dict[str, Any]) -> None:
        d["objects"][0]["pose"]["position"][2] = 0.65

    assert problems(DEFAULT, sink) == [
        ("objects[0].pose.position",
         "expected z >= 0.675 m, so parcel stands on the table top (0.6 m + half its height "
         "0.075 m), got z = 0.65 m: 0.025 m of it inside the table"),
    ]  # fmt: skip


def test_a_parcel_turned_on_its_side_rests_higher() -> None:
    def turn(d: dict[str, Any]) -> None:
        d["objects"][0]["pose"]["rpy_deg"] = [90.0, 0.0, 0.0]  # its 0.3 m side now upright

    ((field, message),) = problems(DEFAULT, turn)
    assert field == "objects[0].pose.position"
    assert message.startswith("expected z >= 0.75 m")


@pytest.mark.parametrize(("dx", "clear"), [(0.20, True), (0.19, False)])
def test_two_objects_side_by_side_pass_and_overlapping_do_not(dx: float, clear: bool) -> None:
    # The twin behind the parcel, where none of its goals reaches.
    def twin(d: dict[str, Any]) -> None:
        other = dict(d["objects"][0], name="twin")
        other["pose"] = dict(other["pose"], position=[0.55 - dx, 0.0, 0.675])
        d["objects"].append(other)

    found = problems(DEFAULT, twin)
    assert found == [] if clear else found[0][0] == "objects[1].pose.position"
    if not clear:
        assert (
            "expected twin clear of parcel at the start, got [0.36, 0, 0.675]: 10 mm"
            in (found[0][1])
        )


def test_an_object_beside_the_parcel_stays_there_in_the_way_of_its_goal() -> None:
    # The twin face to face in front of the parcel does not ride with it: the centre goal,
    # 10 cm on, runs 10 cm into it, and the right and left goals (x to 0.70) 5 cm.
    def twin(d: dict[str, Any]) -> None:
        other = dict(d["objects"][0], name="twin")
        other["pose"] = dict(other["pose"], position=[0.75, 0.0, 0.675])
        d["objects"].append(other)

    found = problems(DEFAULT, twin)
    assert [field for field, _ in found] == [f"task[0].moves[{j}].goal.position" for j in range(3)]
    assert "parcel is clear of twin (where it stands then)" in found[0][1]


def test_an_obstacle_in_the_way_of_any_object_when_its_move_starts() -> None:
    def post_on_the_right_parcel(d: dict[str, Any]) -> None:
        d["obstacles"][0]["position"] = [0.72, -0.22, 0.70]
        d["task"][0]["moves"][0]["obstacles"] = ["post"]
        for move in d["task"][1]["moves"]:
            move["obstacles"] = []

    (found,) = problems(TWO, post_on_the_right_parcel)
    assert found == (
        "obstacles[0].position",
        "expected post at least 1 mm clear of parcel_right where it stands when task[0].moves[0] "
        "starts, "
        "got [0.72, -0.22, 0.7]: 130 mm inside parcel_right at [0.72, -0.22, 0.675]",
    )


@pytest.mark.parametrize(
    ("bottom_gap", "words"), [(0.0, "touching"), (0.0005, "0.5 mm from"), (0.0015, None)]
)
def test_an_obstacle_resting_on_the_object_is_a_contact(
    bottom_gap: float, words: str | None
) -> None:
    # ball_right (r 0.04) straight over the parcel's top (0.75) at move 1's start, the centre
    # goal: touching, or half a millimetre off, fails whatever the robot does; 1.5 mm passes.
    def rest_on_top(d: dict[str, Any]) -> None:
        d["obstacles"][0]["position"] = [0.65, 0.05, 0.75 + 0.04 + bottom_gap]

    found = problems(DEFAULT, rest_on_top)
    if words is None:
        assert found == []
        return
    assert found == [
        ("obstacles[0].position",
         "expected ball_right at least 1 mm clear of parcel at the goal of its move 1 "
         "(task[0].moves[0]) when "
         f"task[0].moves[1] starts, got [0.65, 0.05, {0.79 + bottom_gap:.3g}]: {words} parcel at "
         "[0.65, 0, 0.675]"),
    ]  # fmt: skip


def test_an_obstacle_where_the_object_is_set_down() -> None:
    # ball_left moved beside the left goal (0.60, 0.15): its surface 2 cm inside the parcel's
    # -x face there, clear of the parcel where move 2 starts (the right goal).
    def beside_the_goal(d: dict[str, Any]) -> None:
        d["obstacles"][1]["position"] = [0.48, 0.15, 0.70]

    assert problems(DEFAULT, beside_the_goal) == [
        ("obstacles[1].position",
         "expected ball_left at least 1 mm clear of parcel at the goal of task[0].moves[2], "
         "got [0.48, 0.15, 0.7]: 20 mm inside parcel at [0.6, 0.15, 0.675]"),
    ]  # fmt: skip


def test_a_goal_on_the_place_another_objects_last_move_put_it() -> None:
    # parcel_right's first goal moved onto parcel_left's last goal (0.48, 0.18): 6 cm apart in
    # x, the two 0.20 m deep boxes overlap by 14 cm.
    def onto_the_other(d: dict[str, Any]) -> None:
        d["task"][1]["moves"][0]["goal"]["position"] = [0.54, 0.18, 0.675]

    assert problems(TWO, onto_the_other) == [
        ("task[1].moves[0].goal.position",
         "expected a goal where parcel_right is clear of parcel_left (where its last move put "
         "it then), got [0.54, 0.18, 0.675]: 140 mm inside parcel_left at [0.48, 0.18, 0.675]"),
    ]  # fmt: skip


@pytest.mark.parametrize(("x", "clear"), [(0.80, True), (0.79, False)])
def test_a_goal_on_an_object_the_task_leaves_where_it_stands(x: float, clear: bool) -> None:
    # A 10 cm crate beyond the centre goal, whose parcel reaches x = 0.75 there: face to face
    # passes, a centimetre into it does not.
    def crate(d: dict[str, Any]) -> None:
        other = dict(d["objects"][0], name="crate")
        other["shape"] = {"type": "box", "size": [0.1, 0.1, 0.1]}
        other["pose"] = {"position": [x, 0.0, 0.65], "rpy_deg": [0.0, 0.0, 0.0]}
        d["objects"].append(other)

    found = problems(DEFAULT, crate)
    if clear:
        assert found == []
        return
    assert found == [
        ("task[0].moves[0].goal.position",
         "expected a goal where parcel is clear of crate (where it stands then), got "
         "[0.65, 0, 0.675]: 10 mm inside crate at [0.79, 0, 0.65]"),
    ]  # fmt: skip


def test_a_ball_on_a_tray_rides_with_it_and_is_not_in_its_way() -> None:
    # The tray's first goal 14 cm on: where the ball started would cut through its back rim,
    # but the ball lies on its floor and goes with it.
    tray = ROOT / "worlds" / "tray_carry.yaml"

    def further(d: dict[str, Any]) -> None:
        d["task"][0]["moves"][0]["goal"]["position"] = [0.69, 0.0, 0.675]

    assert problems(tray, further) == []

    # The same ball standing on the table, not on the tray: in the way of that goal.
    def on_the_table(d: dict[str, Any]) -> None:
        further(d)
        d["objects"][1]["pose"]["position"] = [0.55, -0.0, 0.625]
        d["objects"][0]["pose"]["position"] = [0.55, 0.3, 0.675]

    found = problems(tray, on_the_table)
    assert [field for field, _ in found] == [f"task[0].moves[{j}].goal.position" for j in range(3)]
    assert all("tray is clear of ball (where it stands then)" in m for _, m in found)


SLOT = ROOT / "worlds" / "slot_insertion.yaml"


def test_a_fixture_built_over_the_objects_start_is_refused() -> None:
    # The slot moved next to the parcel's start (0.56, 0.18): its -x wall stands in the parcel.
    def over_the_start(d: dict[str, Any]) -> None:
        d["fixtures"][0]["position"] = [0.62, 0.16]
        d["task"][0]["moves"][0]["goal"]["position"] = [0.62, 0.16, 0.675]

    ((field, message),) = problems(SLOT, over_the_start)
    assert field == "fixtures[0].position"
    assert message.startswith(
        "expected slot's walls clear of parcel at its start, got [0.62, 0.16]: a wall"
    )


def test_a_fixture_turned_into_the_objects_start_is_refused() -> None:
    # Turned 30 degrees where it stands, the slot's corner reaches 4 mm into the parcel.
    def turned(d: dict[str, Any]) -> None:
        d["fixtures"][0]["yaw_deg"] = 30.0
        d["task"][0]["moves"][0]["goal"]["rpy_deg"] = [0.0, 0.0, 30.0]

    ((field, message),) = problems(SLOT, turned)
    assert field == "fixtures[0].position"
    assert "a wall 4.05 mm inside parcel at [0.56, 0.18, 0.675]" in message


def test_a_goal_on_a_fixtures_wall_is_refused_unless_seated_in_it() -> None:
    # A second move, carried back out of the slot onto its +y wall.
    def onto_the_wall(d: dict[str, Any]) -> None:
        d["task"][0]["moves"].append(
            {"goal": {"position": [0.60, -0.04, 0.675], "rpy_deg": [0.0, 0.0, 0.0]}}
        )

    ((field, message),) = problems(SLOT, onto_the_wall)
    assert field == "task[0].moves[1].goal.position"
    assert message.startswith("expected a goal where parcel is clear of slot's walls, got")
    assert problems(SLOT, lambda d: None) == []  # seated in it: inside its walls, clear
