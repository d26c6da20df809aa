"""A move with no clear carry from its grip grasps again and carries clear, never blindly."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from experiment.episode import run_episode
from worlds.world_file import load_world

pytestmark = pytest.mark.sim

WORLD = Path(__file__).resolve().parents[1] / "data" / "worlds" / "sphere_over_the_carry.yaml"


def test_a_sphere_over_every_carry_from_this_grip_is_passed_from_a_new_grip(
    tmp_path: Path,
) -> None:
    report = run_episode(load_world(WORLD), out=tmp_path, animation=False)
    assert report.success, report.failure
    assert not report.obstacle_contacts and report.arm_contacts == 0
    events = [json.loads(line) for line in (tmp_path / "run.jsonl").read_text().splitlines()]
    ended = {
        (e["node"].split(".")[2], e["to"])
        for e in events
        if e.get("to") and e.get("node", "").endswith("choose_composition.with_this_grip")
    }
    regrasped = {
        e["node"].split(".")[2]
        for e in events
        if e.get("to") == "SUCCESS"
        and e.get("node", "").endswith("regrasp_for_a_clear_carry.from_the_new_grip")
    }
    # The last move's carries were all refused with the grip it had (its careful carry
    # too, for a link predicted on the sphere), and the same move carried from a new grip.
    assert ("move_left", "FAILURE") in ended
    assert regrasped == {"move_left"}
