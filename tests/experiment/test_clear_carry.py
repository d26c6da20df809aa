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

    def moves_where(branch: str, status: str) -> set[str]:
        return {
            e["node"].split(".")[3]  # task.<object>.pick_and_place.<move>...
            for e in events
            if e.get("to") == status and e.get("node", "").endswith(f"{branch}.carry_clear")
        }

    # One move's carries were all refused with the grip it had (its careful carry too, for a
    # link predicted on the sphere), and that move carried from a new grip.
    refused = moves_where("choose_composition.with_this_grip", "FAILURE")
    assert len(refused) == 1
    assert moves_where("regrasp_for_a_clear_carry.from_the_new_grip", "SUCCESS") == refused
