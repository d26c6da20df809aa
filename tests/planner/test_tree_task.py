"""A tree's moves and grasps against a world's task (no world needed: counts per object)."""

from __future__ import annotations

from pathlib import Path

import pytest

import planner.leaves  # noqa: F401  (registers the leaves the trees use)
from experiment.preflight import tree_task_problems
from planner.default_tree import PICK_AND_PLACE_XML
from planner.tree_reading import read_tree_document, read_tree_document_string
from planner.tree_task import check_tree_moves, tree_grasps
from skills.vocabulary import GraspType
from worlds.world_file import load_world

TWO_OBJECTS = """<root BTCPP_format="4">
  <BehaviorTree ID="Main">
    <Sequence>
      <SelectSkills name="select_a" object="box_a" plan="{plan}" grasp="two_arm_support"/>
      <AtGoal name="a_placed" object="box_a" move="1"/>
      <AtGoal name="b_placed" object="box_b" move="0"/>
      <AtGoal name="c_placed" object="box_c" move="0"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


#: The line of the shipped tree's third move (the one a two-move world lacks).
MOVE_LEFT_LINE = next(
    i
    for i, line in enumerate(PICK_AND_PLACE_XML.read_text(encoding="utf-8").splitlines(), 1)
    if 'name="move_left"' in line
)


def test_a_move_the_world_lacks_names_the_node_and_the_worlds_moves() -> None:
    doc = read_tree_document(PICK_AND_PLACE_XML)
    [problem] = check_tree_moves(doc, {"parcel": 2}, "parcel")
    assert str(problem) == (
        f'{PICK_AND_PLACE_XML}:{MOVE_LEFT_LINE}: <SubTree ID="Move" name="move_left">: move 2, '
        "but the world's task has 2 moves for parcel (indices 0..1)"
    )


def test_a_move_no_node_names_would_be_left_undone() -> None:
    doc = read_tree_document(PICK_AND_PLACE_XML)
    [problem] = check_tree_moves(doc, {"parcel": 4}, "parcel")
    assert str(problem) == (
        f"{PICK_AND_PLACE_XML}: names moves 0, 1, 2 of parcel, but the world's task has "
        "4 moves for parcel (indices 0..3): move 3 would be left undone"
    )


def test_a_grasps_own_no_move_default_written_out_as_groot2_saves_it_is_not_a_move() -> None:
    # Groot2 writes every port's default into the file it saves: Approach's and Grasp's
    # move="-1" ("the faces nearest the robot's y axis") is not an index of the task's moves.
    xml = """<root BTCPP_format="4">
  <BehaviorTree ID="Main">
    <Sequence>
      <Approach object="parcel" move="-1"/>
      <Grasp object="parcel" move="-1" plan="{plan}" state="{state}"/>
      <AtGoal object="parcel" move="0"/>
      <AtGoal object="parcel" move="-1"/>
    </Sequence>
  </BehaviorTree>
</root>
"""
    doc = read_tree_document_string(xml, "saved.xml")
    [problem] = check_tree_moves(doc, {"parcel": 1}, None)
    # AtGoal has no such default: its -1 is still a move the task lacks.
    assert str(problem) == (
        "saved.xml:7: <AtGoal>: move -1, but the world's task has 1 move for parcel (indices 0..0)"
    )


def test_a_no_move_passed_through_a_subtree_port_is_left_to_its_nodes() -> None:
    # <SubTree ID="GraspObject" move="-1" _autoremap="true"/> had been refused at `run` as a
    # move the task lacks, while the same -1 on the Approach inside it was accepted.
    xml = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence>
      <SubTree ID="GraspObject" object="parcel" move="-1" _autoremap="true"/>
      <AtGoal object="parcel" move="0"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="GraspObject">
    <Approach object="{object}" move="{move}"/>
  </BehaviorTree>
</root>
"""
    doc = read_tree_document_string(xml, "saved.xml")
    assert check_tree_moves(doc, {"parcel": 1}, None) == []


def test_the_shipped_tree_matches_a_three_move_task() -> None:
    doc = read_tree_document(PICK_AND_PLACE_XML)
    assert check_tree_moves(doc, {"parcel": 3}, "parcel") == []
    assert check_tree_moves(doc, {"parcel": 2}, None) == []  # {object} unbound: unknown


def test_literal_objects_are_checked_against_their_own_moves() -> None:
    doc = read_tree_document_string(TWO_OBJECTS, source="two.xml")
    problems = [str(p) for p in check_tree_moves(doc, {"box_a": 2, "box_b": 1}, "box_a")]
    assert problems == [
        "two.xml:7: <AtGoal name=\"c_placed\">: object 'box_c' is not in the world's task "
        "(objects: box_a, box_b)",
        "two.xml: names moves 1 of box_a, but the world's task has 2 moves for box_a "
        "(indices 0..1): move 0 would be left undone",
    ]


NO_SELECT = """<root BTCPP_format="4">
  <BehaviorTree ID="Main"><AtGoal name="placed" object="box_a" move="0"/></BehaviorTree>
</root>
"""


@pytest.mark.parametrize(
    ("text", "grasps"),
    [
        (TWO_OBJECTS, frozenset({GraspType.TWO_ARM_SUPPORT})),
        (
            TWO_OBJECTS.replace(' grasp="two_arm_support"', ""),
            frozenset({GraspType.TWO_PALM_LATERAL}),
        ),
        (TWO_OBJECTS.replace('"two_arm_support"', '"{grasp}"'), None),
        (NO_SELECT, None),
    ],
    ids=["literal", "port default", "blackboard key", "no SelectSkills"],
)
def test_tree_grasps_are_what_its_select_skills_ask_for(
    text: str, grasps: frozenset[GraspType] | None
) -> None:
    assert tree_grasps(read_tree_document_string(text)) == grasps


def test_the_shipped_tree_makes_the_lateral_grasp() -> None:
    assert tree_grasps(read_tree_document(PICK_AND_PLACE_XML)) == {GraspType.TWO_PALM_LATERAL}


def test_a_turn_made_in_steps_is_named_where_the_moves_are_counted() -> None:
    # The world file has 3 moves; its last, a quarter turn, is made in two grasps: a tree
    # written for 3 moves is told why the task has 4.
    world = load_world(
        Path(__file__).resolve().parents[1] / "data" / "worlds" / "turned_90_beside_a_sphere.yaml"
    )
    doc = read_tree_document(PICK_AND_PLACE_XML)
    assert tree_task_problems(world, doc) == [
        f"{PICK_AND_PLACE_XML}: names moves 0, 1, 2 of parcel, but the world's task has "
        "4 moves for parcel (indices 0..3) (the world file's move 2 is made in 2 steps, 2 and "
        "3): move 3 would be left undone"
    ]


def test_a_tree_that_inserts_on_a_task_of_no_fixture_is_named() -> None:
    # `validate --tree planner/trees/slot_insertion.xml` of the tray world had said it matched
    # its task; the run then failed after 13 s: "move 0 of 'tray' goes into no fixture".
    root = Path(__file__).resolve().parents[2]
    slot = root / "planner" / "trees" / "slot_insertion.xml"
    doc = read_tree_document(slot)
    tray = tree_task_problems(load_world(root / "worlds" / "tray_carry.yaml"), doc)
    assert any(
        line.endswith(
            '<Insert name="insert">: inserts into a fixture, but no move of the world\'s task '
            "goes into one (a move's `fixture:`)"
        )
        for line in tray
    )
    assert tree_task_problems(load_world(root / "worlds" / "slot_insertion.yaml"), doc) == []
