"""A world names the tree its task runs (the world file's ``tree``): the template is made into
the task as the shipped tree is, its content keys the world's campaigns, and a template without
the shipped structure is refused naming the file and what it lacks."""

from __future__ import annotations

from pathlib import Path

import pytest

from experiment.preflight import preflight_problems
from experiment.trials import campaign_of
from planner.default_tree import PICK_AND_PLACE_XML, TaskStep, default_tree
from planner.tree_problems import TreeFileError
from worlds.world_file import load_world

DEFAULT_WORLD = Path(__file__).resolve().parents[2] / "worlds" / "parcel_pick_place.yaml"


def _world_with_tree(tmp_path: Path, tree_text: str):
    (tmp_path / "task.xml").write_text(tree_text)
    text = DEFAULT_WORLD.read_text().replace("tree: null", "tree: task.xml")
    (tmp_path / "world.yaml").write_text(text)
    return load_world(tmp_path / "world.yaml")


def _names(root) -> set[str]:
    # subtree instances show as components of their nodes' dotted names
    return {part for node in root.iterate() for part in node.name.split(".")}


def test_the_world_tree_is_made_into_its_task(tmp_path: Path) -> None:
    renamed = PICK_AND_PLACE_XML.read_text().replace('name="move_centre"', 'name="move_first"')
    world = _world_with_tree(tmp_path, renamed)
    assert world.tree_path() == tmp_path / "task.xml"
    root = default_tree([TaskStep("parcel", 3)], world.tree_path())
    names = _names(root)
    assert "move_first" in names and "move_centre" not in names
    assert {"move_right", "move_left"} <= names
    assert preflight_problems(world, str(tmp_path / "world.yaml")) == []


def test_a_world_without_a_tree_dumps_as_before() -> None:
    world = load_world(DEFAULT_WORLD)
    assert world.tree is None and "tree" not in world.model_dump(mode="json")


def test_the_template_content_keys_the_campaign(tmp_path: Path) -> None:
    text = PICK_AND_PLACE_XML.read_text()
    first = campaign_of(_world_with_tree(tmp_path, text), 0, None)
    second = campaign_of(
        _world_with_tree(tmp_path, text.replace("move_left", "move_last")), 0, None
    )
    assert first["settings"]["world_tree_sha256"] != second["settings"]["world_tree_sha256"]
    assert campaign_of(load_world(DEFAULT_WORLD), 0, None)["settings"] == {}


def test_a_template_without_the_structure_is_refused(tmp_path: Path) -> None:
    flat = (
        '<root BTCPP_format="4" main_tree_to_execute="A"><BehaviorTree ID="A">'
        "<Sequence><AlwaysSuccess/></Sequence></BehaviorTree></root>"
    )
    world = _world_with_tree(tmp_path, flat)
    with pytest.raises(
        TreeFileError, match=r"task\.xml: as a task's tree template: .*PickAndPlace"
    ):
        default_tree([TaskStep("parcel", 3)], world.tree_path())
    (problem,) = preflight_problems(world, str(tmp_path / "world.yaml"))
    assert "task.xml" in problem and "PickAndPlace" in problem
