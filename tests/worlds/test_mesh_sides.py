"""Mesh objects: the sides of their hulls a lateral squeeze holds on, and their centring."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
import yaml

from skills.vocabulary import GraspType
from worlds.adapters import object_contexts
from worlds.feasibility import feasibility_problems
from worlds.mesh_sides import mesh_centre, squeeze_axes
from worlds.spec import ShapeSpec
from worlds.world_file import load_world

ROOT = Path(__file__).resolve().parents[2]
#: The grasps the shipped tree makes.
LATERAL = frozenset({GraspType.TWO_PALM_LATERAL})


def mesh(tmp_path: Path, name: str, made: trimesh.Trimesh) -> ShapeSpec:
    path = tmp_path / f"{name}.obj"
    made.export(path)
    return ShapeSpec.mesh(path, 1.0)


def frustum(
    bottom: tuple[float, float], top: tuple[float, float], height: float
) -> trimesh.Trimesh:
    corners = [
        (sx * w / 2, sy * d / 2, z)
        for (w, d), z in ((bottom, -height / 2), (top, height / 2))
        for sx in (-1, 1)
        for sy in (-1, 1)
    ]
    return trimesh.convex.convex_hull(np.array(corners))


def test_a_box_a_prism_and_a_tapered_block(tmp_path: Path) -> None:
    box = mesh(tmp_path, "box", trimesh.creation.box(extents=[0.2, 0.3, 0.15]))
    prism = mesh(tmp_path, "prism", trimesh.creation.cylinder(0.09, 0.16, sections=24))
    taper = mesh(tmp_path, "taper", frustum((0.2, 0.3), (0.1, 0.16), 0.15))
    assert squeeze_axes(box) == ("x", "y")  # four flat sides
    assert squeeze_axes(prism) == ("x", "y")  # a vertical edge on each side, as a cylinder's
    assert squeeze_axes(taper) == ()  # each side touched along its bottom edge alone
    # Sides flat across y only: a wedge lying along x, pointed at +x.
    wedge = trimesh.convex.convex_hull(
        np.array(
            [(x, y, z) for x, y in ((-0.1, -0.1), (-0.1, 0.1), (0.1, 0.0)) for z in (-0.06, 0.06)]
        )
    )
    # +x is a vertical edge on the squeeze line, -x a face; +-y slanted faces meet the palm
    # along a vertical edge at x = -0.1, off the line through the centre.
    assert squeeze_axes(mesh(tmp_path, "wedge", wedge)) == ("x",)


def test_a_mesh_is_centred_on_its_bounding_box(tmp_path: Path) -> None:
    raised = trimesh.creation.box(extents=[0.2, 0.3, 0.15])
    raised.apply_translation([0.01, 0.0, 0.075])
    np.testing.assert_allclose(mesh_centre(mesh(tmp_path, "raised", raised)), [0.01, 0, 0.075])


def mesh_world(tmp_path: Path, made: trimesh.Trimesh) -> Path:
    made.export(tmp_path / "object.obj")
    data = yaml.safe_load((ROOT / "worlds" / "parcel_pick_place.yaml").read_text())
    data["objects"][0]["shape"] = {"type": "mesh", "file": "object.obj"}
    data["skills"]["library"] = "default"
    path = tmp_path / "mesh_world.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("made", "expected"),
    [
        (
            frustum((0.2, 0.3), (0.1, 0.16), 0.15),
            "objects[0]: expected a grasp the robot can "
            "make, got none for parcel: two_palm_lateral: no two sides of its hull a palm can "
            "press, across x or y",
        ),
        (
            trimesh.creation.box(extents=[0.2, 0.3, 0.15]).apply_translation([0, 0, 0.02]),
            "objects[0].shape.file: expected a mesh centred on its origin",
        ),
    ],
    ids=["tapered", "off-centre"],
)
def test_a_mesh_object_the_robot_cannot_hold_is_refused(
    tmp_path: Path, made: trimesh.Trimesh, expected: str
) -> None:
    problems = [
        p.format("w.yaml")
        for p in feasibility_problems(load_world(mesh_world(tmp_path, made)), LATERAL)
    ]
    assert any(p.startswith(f"w.yaml: {expected}") for p in problems), problems


def test_a_mesh_obstacle_is_bounded_about_its_bounding_box_centre(tmp_path: Path) -> None:
    # A 10 cm cube whose file puts its origin at its bottom face, standing at z = 0.8.
    cube = trimesh.creation.box(extents=[0.1, 0.1, 0.1]).apply_translation([0.0, 0.0, 0.05])
    cube.export(tmp_path / "cube.obj")
    data = yaml.safe_load((ROOT / "worlds" / "parcel_pick_place.yaml").read_text())
    data["obstacles"][0]["shape"] = {"type": "mesh", "file": "cube.obj"}
    data["obstacles"][0]["position"] = [0.62, -0.08, 0.8]
    path = tmp_path / "w.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    bound = object_contexts(load_world(path))[0].obstacles[0]
    np.testing.assert_allclose(bound.position, [0.62, -0.08, 0.85])
    assert bound.radius == pytest.approx(0.05 * np.sqrt(3.0))
