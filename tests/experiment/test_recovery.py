"""Recovery in physics: a parcel shoved out of the grip mid-carry is picked up where it lies."""

from __future__ import annotations

from pathlib import Path

import pytest

from experiment.episode import run_episode
from worlds.world_file import load_world, world_from_data

pytestmark = pytest.mark.sim

DEFAULT = Path(__file__).resolve().parents[2] / "worlds" / "parcel_pick_place.yaml"


def test_a_shove_that_drops_the_parcel_mid_carry_is_recovered_and_every_move_placed() -> None:
    data = load_world(DEFAULT).model_dump(mode="json")
    # 400 N down for 0.15 s (60 N s) near the top of the first carry's lift: far more than
    # the palms' friction holds (2 x 0.64 x 25 N), so the parcel falls out of the grip.
    data["disturbances"] = [
        {"at_s": 4.3, "object": "parcel", "force_n": [0.0, 0.0, -400.0], "duration_s": 0.15}
    ]
    report = run_episode(world_from_data(data, DEFAULT), None, out=None, animation=False)
    summary = report.summary()
    assert report.dropped, "the shove should have knocked the parcel out of the palms"
    assert summary["disturbances"]["applied"] == 1
    assert report.success, report.failure
    assert all(e is not None and e < 0.02 for e in report.placement_error_m)
    assert all(d is not None and d < 10.0 for d in report.placement_error_deg)
    assert not report.obstacle_contacts and report.arm_contacts == 0
    assert summary["contact_count"] >= 2  # the first grasp, and the one after the drop
