"""A user's own, smaller and lighter box in physics: squeezed between the palms, placed three
times (issue 13: it used to be refused before the robot moved)."""

from __future__ import annotations

from pathlib import Path

import pytest

from experiment.episode import run_episode
from worlds.world_file import load_world

pytestmark = pytest.mark.sim

SMALL_BOX = Path(__file__).resolve().parents[1] / "data" / "worlds" / "small_box.yaml"


def test_a_small_light_box_is_placed_three_times() -> None:
    world = load_world(SMALL_BOX)
    assert world.objects[0].mass == 0.5
    report = run_episode(world, out=None, animation=False)
    assert report.success, report.failure
    assert len(report.placement_error_m) == 3
    assert all(e is not None and e < 0.02 for e in report.placement_error_m)
    assert all(d is not None and d < 10.0 for d in report.placement_error_deg)
    assert not report.obstacle_contacts and report.arm_contacts == 0 and not report.dropped
