"""One physics episode of the slot insertion: the parcel seated within 3 mm and 3 degrees."""

from __future__ import annotations

from pathlib import Path

import pytest

from experiment.episode import run_episode
from experiment.insertion import SEATED_TOLERANCE_DEG, SEATED_TOLERANCE_M, WALL_FORCE_LIMIT_S
from worlds.world_file import load_world

SLOT = Path(__file__).resolve().parents[2] / "worlds" / "slot_insertion.yaml"


@pytest.mark.sim
def test_the_parcel_is_seated_in_its_fixture_by_both_palms() -> None:
    report = run_episode(load_world(SLOT), out=None, animation=False)
    assert report.success, report.failure
    seat = report.insertion["slot"]
    assert abs(seat["seat_bottom_m"]) <= SEATED_TOLERANCE_M
    assert seat["seat_angle_deg"] <= SEATED_TOLERANCE_DEG
    assert seat["longest_above_limit_s"] <= WALL_FORCE_LIMIT_S
    assert report.insertion["robot_contacts"] == {}
    assert report.skills == ["insert"]  # the move's result is the insertion's, not the carry's
    assert not report.dropped
