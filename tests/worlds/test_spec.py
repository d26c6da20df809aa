"""The file boundary: a validated world becomes the core's frozen dataclasses, once."""

from __future__ import annotations

import copy
import dataclasses
import math
from pathlib import Path
from typing import Any

import pytest
import yaml
from numpy.testing import assert_allclose

from skills import quaternion as quat
from worlds.adapters import object_contexts, robot_capabilities
from worlds.spec import RobotModelName, Shape, WorldSpec
from worlds.world_file import load_world, world_spec

REPO = Path(__file__).resolve().parents[2]
DEFAULT_WORLD = REPO / "worlds" / "parcel_pick_place.yaml"


@pytest.fixture
def default_data() -> dict[str, Any]:
    data: dict[str, Any] = yaml.safe_load(DEFAULT_WORLD.read_text(encoding="utf-8"))
    return data


def test_default_world_converts_to_frozen_values() -> None:
    spec = world_spec(load_world(DEFAULT_WORLD))
    assert isinstance(spec, WorldSpec)
    assert spec.scene.robot.model is RobotModelName.KUKA_IIWA
    parcel = spec.scene.object_named("parcel")
    assert parcel.shape.kind is Shape.BOX
    assert parcel.shape.size == (0.2, 0.3, 0.15)
    assert [len(step.moves) for step in spec.task] == [3]
    assert spec.moves_of("parcel")[1].obstacles == ("ball_right",)
    assert spec.skill_library is None
    assert spec.source == DEFAULT_WORLD
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.name = "other"  # type: ignore[misc]


def test_angles_become_quaternions_and_radians(
    default_data: dict[str, Any], tmp_path: Path
) -> None:
    data = copy.deepcopy(default_data)
    data["task"][0]["moves"][0]["goal"]["rpy_deg"] = [0.0, 0.0, 30.0]
    path = tmp_path / "turned.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    move = world_spec(load_world(path)).moves_of("parcel")[0]
    assert move.goal_yaw == pytest.approx(math.radians(30.0))
    expected = quat.from_axis_angle([0.0, 0.0, 1.0], math.radians(30.0))
    assert_allclose(quat.angle_between(move.goal_quaternion, expected), 0.0, atol=1e-12)


def test_mesh_world_reads_the_same_from_another_folder(
    default_data: dict[str, Any], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    trimesh = pytest.importorskip("trimesh")
    (tmp_path / "meshes").mkdir()
    trimesh.creation.box(extents=(0.2, 0.3, 0.15)).export(tmp_path / "meshes" / "parcel.obj")
    data = copy.deepcopy(default_data)
    data["objects"][0]["shape"] = {"type": "mesh", "file": "meshes/parcel.obj", "scale": 0.5}
    path = tmp_path / "mesh_world.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    spec = world_spec(load_world(path))
    shape = spec.scene.objects[0].shape
    assert shape.mesh_path == tmp_path / "meshes" / "parcel.obj"
    (context,) = object_contexts(spec)
    assert context.shape is Shape.MESH
    assert_allclose(context.dimensions, (0.1, 0.15, 0.075), atol=1e-9)


def test_adapters_take_a_world_or_its_spec() -> None:
    world = load_world(DEFAULT_WORLD)
    assert object_contexts(world) == object_contexts(world_spec(world))
    assert robot_capabilities(world) == robot_capabilities(world_spec(world))
    assert robot_capabilities(world).payload_per_arm_kg == 7.0
