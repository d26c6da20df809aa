"""The tray carry's world (``worlds/tray_carry.yaml``): the tray shape, the loose ball, one run."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from numpy.testing import assert_allclose

from experiment.episode import run_episode
from experiment.layout import draw_trial, riding
from worlds.sim_world import SimWorld
from worlds.trays import TrayFrame, riders
from worlds.world_file import World, as_world_spec, load_world, world_cli_validate, world_from_data

REPO = Path(__file__).resolve().parents[2]
TRAY_WORLD = REPO / "worlds" / "tray_carry.yaml"


def _data() -> dict[str, Any]:
    return load_world(TRAY_WORLD).model_dump(mode="json")


def _world(data: dict[str, Any]) -> World:
    return world_from_data(data, TRAY_WORLD)


def test_the_world_loads_with_a_tray_a_loose_ball_and_its_own_tree() -> None:
    world = load_world(TRAY_WORLD)
    spec = as_world_spec(world)
    tray, ball = spec.scene.objects
    assert tray.shape.is_tray and not ball.shape.is_tray
    assert_allclose(tray.shape.extents(), (0.24, 0.30, 0.15))  # the outer box, as a box's
    assert [o.name for o in riders(spec.scene.objects, "tray", ["tray"])] == ["ball"]
    tree = world.tree_path()
    assert tree is not None and tree.resolve() == REPO / "planner" / "trees" / "tray_carry.xml"
    # Five boxes: the floor and four walls, not overlapping, all inside the outer box.
    boxes = tray.shape.tray_boxes()
    assert len(boxes) == 5
    volume = sum(8 * np.prod(h) for h, _ in boxes)
    inner = TrayFrame.of(tray.shape)
    hollow = 4 * np.prod(inner.inner_half) * (inner.rim_z - inner.floor_z)
    assert_allclose(volume + hollow, np.prod(tray.shape.size), rtol=1e-12)


@pytest.mark.parametrize(
    ("shape", "field", "expected"),
    [
        ({"floor": 0.2}, r"objects\[0\]\.shape\.floor", "a floor thinner than the tray's height"),
        ({"rim": 0.2}, r"objects\[0\]\.shape\.rim", "a rim thinner than half the tray's width"),
        ({"rim": -0.01}, r"objects\[0\]\.shape\.rim", "greater than 0"),
    ],
)
def test_a_bad_tray_names_its_field(
    shape: dict[str, float], field: str, expected: str, tmp_path: Path, capsys: Any
) -> None:
    data = yaml.safe_load(TRAY_WORLD.read_text())
    data["objects"][0]["shape"].update(shape)
    data["tree"] = str(REPO / "planner" / "trees" / "tray_carry.xml")
    path = tmp_path / "bad_tray.yaml"
    path.write_text(yaml.safe_dump(data))
    assert world_cli_validate(str(path)) == 2
    err = capsys.readouterr().err
    assert err.startswith(str(path))
    assert pytest.importorskip("re").search(field, err), err
    assert expected in err


def test_trials_carry_the_ball_with_the_trays_start() -> None:
    """Without drawn trays and balls (trials.size_scale, mass_kg, riders), the ball keeps its
    place on the tray wherever the trial starts the tray (tests/experiment/test_tray_draws.py
    checks the drawn ones)."""
    data = _data()
    for key in ("size_scale", "mass_kg", "riders"):
        data["trials"].pop(key, None)
    base = _world(data)
    assert riding(base) == [1]
    world, _ = draw_trial(base, 0, 3)
    offset = np.subtract(base.objects[1].pose.position, base.objects[0].pose.position)
    moved = np.subtract(world.objects[1].pose.position, world.objects[0].pose.position)
    assert_allclose(moved, offset, atol=1e-12)


def _own_world() -> World:
    """Another tray and ball: narrower, shallower floor, a bigger, heavier ball off centre."""
    data = _data()
    data["objects"][0]["shape"] = {
        "type": "tray",
        "size": [0.22, 0.28, 0.15],
        "floor": 0.015,
        "rim": 0.008,
    }
    data["objects"][1]["shape"] = {"type": "sphere", "radius": 0.035}
    data["objects"][1]["mass"] = 0.12
    data["objects"][1]["pose"]["position"] = [0.52, -0.06, 0.6 + 0.015 + 0.035]
    return _world(data)


@pytest.mark.sim
def test_the_planner_sees_the_loose_ball() -> None:
    with SimWorld(_own_world()) as sim:
        (ball,) = sim.loose_balls("tray")
        assert ball.radius_m == 0.035
        assert_allclose(ball.rim_m, 0.135)
        assert sim.loose_balls("ball") == ()


@pytest.mark.sim
def test_a_tray_of_our_own_is_carried_level_with_its_ball_on() -> None:
    report = run_episode(_own_world(), out=None, animation=False)
    assert report.success, report.failure
    (tray,) = report.tray
    assert tray["peak_tilt_deg"] <= 5.0
    assert tray["ball_off_samples"] == 0
    assert report.skills == ["level_carry"] * 3
    assert max(report.placement_error_m) <= 0.02
