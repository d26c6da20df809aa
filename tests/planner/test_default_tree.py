"""The default tree is the shipped XML file, for the task's number of moves."""

from __future__ import annotations

import re
from pathlib import Path

import py_trees
import pytest

from planner.default_tree import (
    PICK_AND_PLACE_XML,
    TaskStep,
    default_tree,
    pick_and_place_xml,
    task_xml,
    template_main_tree,
)
from planner.loader import load_tree, load_tree_string


def outline(root: py_trees.behaviour.Behaviour) -> list[tuple[str, str]]:
    return [(type(n).__name__, n.name) for n in root.iterate()]


def transports(root: py_trees.behaviour.Behaviour) -> list[py_trees.behaviour.Behaviour]:
    return [n for n in root.iterate() if type(n).__name__ == "Transport"]


def test_three_moves_is_the_shipped_file() -> None:
    assert outline(default_tree()) == outline(load_tree(PICK_AND_PLACE_XML))


def test_each_move_tries_the_files_compositions() -> None:
    found = transports(default_tree())
    # 3 moves x ((5 compositions + the careful fallback) with the grip the palms have and
    # again from a new grip, + 2 corrections of a placement)
    assert len(found) == 3 * 14
    assert sorted({int(t.get_input("move")) for t in found}) == [0, 1, 2]
    weights = sorted({float(t.get_input("transport_weight")) for t in found})
    assert weights == [0.1, 0.25, 1.0]
    gains = sorted({float(t.get_input("avoid_gain")) for t in found})
    assert gains == [0.0, 1.0, 2.0]


@pytest.mark.parametrize("moves", [1, 2, 3, 5])
def test_another_number_of_moves_repeats_the_files_move_subtree(moves: int) -> None:
    root = default_tree(moves)
    found = transports(root)
    assert len(found) == moves * 14
    assert sorted({int(t.get_input("move")) for t in found}) == list(range(moves))
    names = [n.name for n in root.iterate()]
    assert len(names) == len(set(names))  # every node's name is its path: unique
    # The same nodes per move as the shipped file's first move.
    shipped = [n for _, n in outline(default_tree()) if ".move_centre." in n]
    first = [n.name for n in root.iterate() if ".move_centre." in n.name]
    assert first == shipped


def test_fewer_than_one_move_is_refused() -> None:
    with pytest.raises(ValueError, match="expected at least 1 move, got 0"):
        pick_and_place_xml(0)


def test_the_shipped_file_runs_one_object_per_pick_and_place_subtree() -> None:
    # The same nodes as the file, for one step of three moves of a named object.
    named = default_tree([TaskStep("parcel", 3)])
    assert [(k, n.replace("task.parcel.", "task.first_object.")) for k, n in outline(named)] == (
        outline(default_tree())
    )


def test_each_object_of_the_task_gets_its_own_subtree_in_task_order() -> None:
    steps = [TaskStep("left box", 2), TaskStep("right", 2), TaskStep("left box", 1, first_move=2)]
    root = default_tree(steps)
    names = [n.name for n in root.iterate()]
    assert len(names) == len(set(names))  # every node's name is its path: unique
    selects = [n.name for n in root.iterate() if type(n).__name__ == "SelectSkills"]
    assert selects == [
        "task.left_box.pick_and_place.select_skills",
        "task.right.pick_and_place.select_skills",
        "task.left_box_2.pick_and_place.select_skills",
    ]
    # Each instance runs its step's moves, with the object's own move indices.
    moves = [
        (n.name.split(".")[1], int(n.get_input("move")))
        for n in transports(root)
        if "with_this_grip" in n.name and n.name.endswith("careful_transport")
    ]
    assert moves == [
        ("left_box", 0),
        ("left_box", 1),
        ("right", 0),
        ("right", 1),
        ("left_box_2", 2),
    ]
    objects = {n.name.split(".")[1]: n.get_input("object") for n in transports(root)}
    assert objects == {"left_box": "left box", "right": "right", "left_box_2": "left box"}


def test_each_object_has_its_own_blackboard_keys() -> None:
    root = default_tree([TaskStep("a", 1), TaskStep("b", 1)])
    grasps = [n for n in root.iterate() if type(n).__name__ == "Grasp"]
    keys = {
        n.name.split(".")[1]: sorted(
            k for k in set(n.blackboard_client.remappings.values()) if k.count("/") == 2
        )
        for n in grasps
    }
    assert keys == {"a": ["/a/plan", "/a/state"], "b": ["/b/plan", "/b/state"]}


def test_a_task_without_steps_or_moves_is_refused() -> None:
    with pytest.raises(ValueError, match="expected at least 1 task step, got none"):
        task_xml([])
    with pytest.raises(ValueError, match="TaskStep 'parcel': expected at least 1 move, got 0"):
        TaskStep("parcel", 0)


def test_a_task_move_made_in_steps_names_each_step_after_it() -> None:
    # The right move turned past the grip: two steps, then the left move.
    step = TaskStep("parcel", 4, task_moves=(0, 1, 1, 2))
    assert step.move_names(["move_centre", "move_right", "move_left"]) == [
        "move_centre",
        "move_right_step_1",
        "move_right_step_2",
        "move_left",
    ]
    root = default_tree([step])
    moves = sorted(
        {(n.name.split(".")[3], int(n.get_input("move"))) for n in transports(root)},
        key=lambda m: m[1],
    )
    assert moves == [
        ("move_centre", 0),
        ("move_right_step_1", 1),
        ("move_right_step_2", 2),
        ("move_left", 3),
    ]
    # Without task moves each move is a task move of its own, named by its index.
    assert TaskStep("parcel", 2, first_move=3).move_names(["a", "b", "c"]) == [
        "move_4",
        "move_5",
    ]
    assert TaskStep("box", 3, first_move=2, task_moves=(3, 3, 4)).move_names(["a"]) == [
        "move_4_step_1",
        "move_4_step_2",
        "move_5",
    ]
    with pytest.raises(ValueError, match="one task move per move"):
        TaskStep("parcel", 2, task_moves=(0,))


def test_a_leaf_skips_only_the_port_debug_lines_nothing_shows() -> None:
    from py_trees.ports_utils import LogLevel

    from planner.leaves.base import WorldLeaf

    leaf = transports(default_tree())[0]
    assert isinstance(leaf, WorldLeaf)
    leaf.feedback_message = "before"
    # built by the XML parser, its ports log to a logger that drops every line
    assert leaf.log(LogLevel.DEBUG, "registered a key") == ""
    assert leaf.log(LogLevel.DEBUG, "x", return_only=True).endswith(": x")
    assert leaf.feedback_message == "before"
    assert leaf.log(LogLevel.INFO, "shown").endswith(": shown")  # INFO sets the feedback
    assert leaf.feedback_message.endswith(": shown")
    previous = py_trees.logging.level
    py_trees.logging.level = py_trees.logging.Level.DEBUG
    try:
        leaf._ports_logger = leaf.logger  # py_trees' own logger, at DEBUG: shown
        assert leaf.log(LogLevel.DEBUG, "registered a key").endswith(": registered a key")
    finally:
        py_trees.logging.level = previous


def test_a_template_saved_by_groot2_without_a_main_tree_is_read_by_its_structure(
    tmp_path: Path,
) -> None:
    # Groot2 saves no main_tree_to_execute: a world's `tree:` of such a file had been refused
    # ("cannot tell the main tree"), and --main-tree does not reach a world's template.
    text = PICK_AND_PLACE_XML.read_text(encoding="utf-8")
    saved = tmp_path / "saved.xml"
    saved.write_text(re.sub(r'\s+main_tree_to_execute="[^"]*"', "", text, count=1), "utf-8")
    assert 'main_tree_to_execute="' not in saved.read_text(encoding="utf-8")
    assert template_main_tree(saved) == template_main_tree(PICK_AND_PLACE_XML)
    made = load_tree_string(task_xml([TaskStep("{object}", 2)], saved))
    shipped = load_tree_string(task_xml([TaskStep("{object}", 2)], PICK_AND_PLACE_XML))
    assert outline(made) == outline(shipped)
