"""A user's object given as a mesh is grasped by its hull's sides and carried in physics."""

from __future__ import annotations

from pathlib import Path

import pytest
import trimesh

from experiment.episode import run_episode
from tests.worlds.test_mesh_sides import mesh_world
from worlds.world_file import load_world


@pytest.mark.sim
@pytest.mark.parametrize(
    "made",
    [
        trimesh.creation.box(extents=[0.2, 0.3, 0.15]),  # the parcel, as a mesh
        trimesh.creation.cylinder(0.09, 0.15, sections=24),  # a 24-sided prism
    ],
    ids=["box", "prism"],
)
def test_a_mesh_object_is_carried_through_the_default_task(
    tmp_path: Path, made: trimesh.Trimesh
) -> None:
    report = run_episode(load_world(mesh_world(tmp_path, made)), out=None, animation=False)
    assert report.success, report.failure
    assert max(report.placement_error_m) < 0.01
    assert not report.obstacle_contacts
