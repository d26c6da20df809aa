"""A user's object given as a mesh is grasped by its hull's sides and carried in physics."""

from __future__ import annotations

from pathlib import Path

import pytest
import trimesh
import yaml

from experiment.episode import run_episode
from experiment.layout import TrialLayoutError, check_trial_layout, draw_trial
from tests.worlds.test_mesh_sides import mesh_world
from worlds.world_file import load_world

ROOT = Path(__file__).resolve().parents[2]


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


@pytest.mark.sim
def test_trials_draw_around_a_mesh_as_around_its_bounding_box(tmp_path: Path) -> None:
    # The parcel as a mesh: the same starts, goals and spheres as the box it is.
    meshed = load_world(mesh_world(tmp_path, trimesh.creation.box(extents=[0.2, 0.3, 0.15])))
    boxed = load_world(ROOT / "worlds" / "parcel_pick_place.yaml")
    check_trial_layout(meshed, 0, "w.yaml")
    for trial in range(2):
        (a, kinds_a), (b, kinds_b) = draw_trial(meshed, 0, trial), draw_trial(boxed, 0, trial)
        assert kinds_a == kinds_b
        assert a.objects[0].pose == b.objects[0].pose
        assert a.obstacles == b.obstacles
        assert [m.goal for m in a.task[0].moves] == [m.goal for m in b.task[0].moves]
    data = yaml.safe_load(Path(meshed.source).read_text(encoding="utf-8"))
    data["trials"]["size_scale"] = [0.8, 1.2]
    scaled = Path(meshed.source).with_name("scaled.yaml")
    scaled.write_text(yaml.safe_dump(data), encoding="utf-8")
    with pytest.raises(TrialLayoutError, match=r"trials.size_scale: expected none for a mesh"):
        check_trial_layout(load_world(scaled), 0, "w.yaml")
