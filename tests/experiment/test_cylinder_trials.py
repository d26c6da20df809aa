"""Trial campaigns of an upright cylinder: drawn around its bounding box like a box's, kept
round when scaled, refused a pitch it would roll off from, and carried in physics."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from experiment.layout import TrialLayoutError, check_trial_layout, draw_trial, object_size
from experiment.trials import campaign_of, run_trial
from worlds.world_file import CylinderShape, load_world, world_from_data

DEFAULT = Path(__file__).resolve().parents[2] / "worlds" / "parcel_pick_place.yaml"
RADIUS, HEIGHT = 0.09, 0.15


def _cylinder(**trials: Any) -> Any:
    world = load_world(DEFAULT)
    data = world.model_dump(mode="json")
    data["objects"][0]["shape"] = {"type": "cylinder", "radius": RADIUS, "height": HEIGHT}
    data["trials"].update(trials)
    return world_from_data(data, world.source)


def test_a_cylinders_layout_is_drawn_around_its_bounding_box() -> None:
    world = _cylinder()
    assert object_size(world) == (2 * RADIUS, 2 * RADIUS, HEIGHT)
    check_trial_layout(world, 0, "w.yaml")
    for trial in range(5):
        drawn, kinds = draw_trial(world, 0, trial)
        shape = drawn.objects[0].shape
        assert isinstance(shape, CylinderShape)
        assert (shape.radius, shape.height) == (RADIUS, HEIGHT)
        # Standing on the table, every goal at its half height above the top.
        top = world.table.position[2]
        assert drawn.objects[0].pose.position[2] == pytest.approx(top + HEIGHT / 2)
        for step in drawn.task:
            assert all(m.goal.position[2] == pytest.approx(top + HEIGHT / 2) for m in step.moves)
        assert len(kinds) == 3


def test_a_scaled_cylinder_stays_round() -> None:
    world = _cylinder(size_scale=[0.8, 1.2])
    radii, heights = set(), set()
    for trial in range(6):
        shape = draw_trial(world, 2, trial)[0].objects[0].shape
        assert isinstance(shape, CylinderShape)
        assert 0.8 * RADIUS <= shape.radius <= 1.2 * RADIUS
        assert 0.8 * HEIGHT <= shape.height <= 1.2 * HEIGHT
        radii.add(shape.radius)
        heights.add(shape.height)
    assert len(radii) == 6 and len(heights) == 6  # drawn per trial, radius and height apart


def test_a_cylinder_turned_off_its_end_is_refused_naming_the_move() -> None:
    world = load_world(DEFAULT)
    data = world.model_dump(mode="json")
    data["objects"][0]["shape"] = {"type": "cylinder", "radius": RADIUS, "height": HEIGHT}
    for region in ("centre", "right", "left"):
        data["trials"].pop(region)
    data["trials"]["moves"] = [
        {"x": [0.58, 0.66], "y": [-0.05, 0.05]},
        {"x": [0.58, 0.66], "y": [-0.05, 0.05], "pitch_deg": [90, -90]},
    ]
    data["task"][0]["moves"] = data["task"][0]["moves"][:2]
    with pytest.raises(
        TrialLayoutError,
        match=r"w\.yaml: trials\.moves\[1\]\.pitch_deg: expected none for a cylinder .*"
        r"got \[90\.0, -90\.0\]",
    ):
        check_trial_layout(world_from_data(data, world.source), 0, "w.yaml")


@pytest.mark.sim
def test_a_cylinder_trial_is_carried_in_physics() -> None:
    world = _cylinder(size_scale=[0.9, 1.1])
    payload = {
        "world": world.model_dump(mode="json"),
        "source": str(world.source or ""),
        "tree": "",
        "key": campaign_of(world, 3, None),
        "leaves": [],
        "backend": "local",
    }
    record = run_trial((payload, 3, 0))
    assert record["success"], record["failure"]
    assert len(record["placement_error_m"]) >= 3
    assert all(e < 0.02 for e in record["placement_error_m"])
    assert not record["obstacle_contacts"] and not record["dropped"]
