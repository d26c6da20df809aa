"""The reasoner's view of a world file, and the scene beside it, from any working directory."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from affordances import AffordanceReasoner
from skills.vocabulary import EndEffector, GraspType
from worlds.adapters import object_contexts, robot_capabilities
from worlds.robots import robot_model_of
from worlds.sim_world import SimWorld
from worlds.world_file import load_world, world_spec

DEFAULT_WORLD = Path(__file__).resolve().parents[2] / "worlds" / "parcel_pick_place.yaml"

# A 0.2 x 0.3 x 0.15 box as a Wavefront OBJ, centred on its origin, outward faces.
_BOX_OBJ = """\
v -0.1 -0.15 -0.075
v 0.1 -0.15 -0.075
v 0.1 0.15 -0.075
v -0.1 0.15 -0.075
v -0.1 -0.15 0.075
v 0.1 -0.15 0.075
v 0.1 0.15 0.075
v -0.1 0.15 0.075
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
"""


def write_mesh_world(folder: Path, parcel_mesh: bool) -> Path:
    """The default world in ``folder``, its first obstacle (and the parcel, if asked) a mesh
    file in ``folder/meshes``, named by a path relative to the world file."""
    (folder / "meshes").mkdir(parents=True)
    (folder / "meshes" / "box.obj").write_text(_BOX_OBJ, encoding="utf-8")
    data: dict[str, Any] = copy.deepcopy(yaml.safe_load(DEFAULT_WORLD.read_text("utf-8")))
    if parcel_mesh:
        data["objects"][0]["shape"] = {"type": "mesh", "file": "meshes/box.obj", "scale": 1.0}
    data["obstacles"][0]["shape"] = {"type": "mesh", "file": "meshes/box.obj", "scale": 0.25}
    path = folder / "mesh_world.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


@pytest.mark.sim
def test_a_mesh_world_builds_from_another_working_directory(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    world_file = write_mesh_world(tmp_path / "world", parcel_mesh=True)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)  # relative mesh paths must not resolve against this
    world = load_world(world_file)
    contexts = {c.name: c for c in object_contexts(world)}
    parcel = contexts["parcel"]
    np.testing.assert_allclose(parcel.dimensions, (0.2, 0.3, 0.15), atol=1e-12)
    reasoner = AffordanceReasoner(robot_capabilities(world))
    assert reasoner.rank_all(list(contexts.values()))
    obstacle = next(o for o in parcel.obstacles if o.name == "ball_right")
    corner = 0.5 * float(np.linalg.norm((0.05, 0.075, 0.0375)))  # the scaled box bounded
    assert obstacle.radius == pytest.approx(corner)
    with SimWorld(world, "parcel") as sim:
        np.testing.assert_allclose(
            sim.object_pose("parcel").position, world.objects[0].pose.position, atol=0.01
        )


@pytest.mark.parametrize("name", ["parcel_pick_place.yaml", "icub_parcel_pick_place.yaml"])
def test_robots_declare_flat_palms_and_the_reasoner_sees_them(name: str) -> None:
    world = load_world(DEFAULT_WORLD.parent / name)
    spec = world_spec(world)
    assert robot_model_of(spec.scene.robot).end_effectors == {EndEffector.FLAT_PALM}
    assert robot_capabilities(world).end_effectors == {EndEffector.FLAT_PALM}


def test_the_small_box_world_gets_the_lateral_squeeze_first() -> None:
    world = load_world(DEFAULT_WORLD.parents[1] / "tests" / "data" / "worlds" / "small_box.yaml")
    ranked = AffordanceReasoner(robot_capabilities(world)).rank_all(object_contexts(world))
    assert [a.grasp for a in ranked["parcel"]] == [
        GraspType.TWO_PALM_LATERAL,
        GraspType.TWO_ARM_SUPPORT,
    ]
