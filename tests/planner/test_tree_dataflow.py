"""Blackboard dataflow, tree size limits, objects against a world (issue 15, items 7 and 8)."""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

import py_trees
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from py_trees.common import Status

import planner.leaves  # noqa: F401  (registers the robot leaves)
import tests.planner.stub_leaves  # noqa: F401  (registers the stub leaves)
from planner.default_tree import PICK_AND_PLACE_XML
from planner.leaves import IsHeld, SelectSkills
from planner.loader import load_tree_string
from planner.testing import FakeWorld, tick_until
from planner.tree_dataflow import RUN_WRITES, dataflow_problems, port_uses
from planner.tree_limits import MAX_TREE_DEPTH, MAX_TREE_NODES
from planner.tree_objects import check_tree_objects
from planner.tree_problems import TreeFileError
from planner.tree_reading import read_tree_document, read_tree_document_string
from planner.validate import validate_tree, validate_tree_string
from planner.wiring import wire
from skills.default_library import build_default_library
from skills.library import SkillLibrary
from tests.planner.test_validate import problems_of, wrap


@pytest.fixture(scope="module")
def library() -> SkillLibrary:
    return build_default_library()


def test_the_shipped_tree_reads_only_what_it_writes() -> None:
    doc = read_tree_document(PICK_AND_PLACE_XML)
    assert dataflow_problems(doc) == []
    uses = port_uses(doc)
    grasp_writes = {u.binding.key for u in uses if u.elem.tag == "Grasp" and u.port == "state"}
    # Each instance of the GraspObject subtree writes the PickAndPlace instance's own state.
    assert grasp_writes == {"/first_object/state"}
    carried = [u for u in uses if u.elem.tag == "Transport" and u.port == "transport_weight"]
    assert {u.binding.literal for u in carried} >= {"1.0", "0.25", "0.1"}


def test_a_key_nothing_writes_is_a_problem() -> None:
    text = wrap(
        """    <Sequence name="s">
      <StubGrasp name="grip" force_n="3.0" holding="{held}"/>
      <StubCheck name="check" value="{held}"/>
      <StubCheck name="typo" value="{hled}"/>
    </Sequence>"""
    )
    assert problems_of(text) == [
        (6, "port 'value' reads {hled} (blackboard key /hled), which nothing writes: expected a "
            "node's output port, a SetBlackboard or a script to write it, or a key the run sets "
            "before the first tick ({object} at the top level)"),
    ]  # fmt: skip


ROOT_KEY_TREE = """<root BTCPP_format="4" main_tree_to_execute="Task">
  <BehaviorTree ID="Task">
    <Sequence>
      <Script code="{writes} := 'parcel'"/>
      <SubTree ID="Inner"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Inner">
    <Sequence>
      <StubCheck value="{{@target}}"/>
      <StubCheck value="{{@object}}"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


def test_a_root_key_read_in_a_subtree_is_the_root_blackboards() -> None:
    # {@target} in a subtree reads the root's /target, which the main tree's script writes;
    # {@object} is the key the run seeds. Both had been refused as /ROOT__target unwritten.
    doc = read_tree_document_string(ROOT_KEY_TREE.format(writes="target"), "t.xml")
    assert dataflow_problems(doc) == []
    reads = {u.binding.key for u in port_uses(doc) if u.elem.tag == "StubCheck"}
    assert reads == {"/target", "/object"}
    doc = read_tree_document_string(ROOT_KEY_TREE.format(writes="other"), "t.xml")
    [problem] = dataflow_problems(doc)
    assert problem.message.startswith(
        "port 'value' reads {@target} (blackboard key /target), which nothing writes"
    )


def test_transport_reading_a_state_nothing_writes_is_refused() -> None:
    text = (
        '<root main_tree_to_execute="M"><BehaviorTree ID="M"><Sequence name="s">'
        '<SelectSkills name="sel" object="{object}" plan="{plan}"/>'
        '<Transport name="t" object="{object}" move="0" plan="{plan}" from_state="{state}" '
        'to_state="{after}"/></Sequence></BehaviorTree></root>'
    )
    (problem,) = validate_tree_string(text, run_keys=RUN_WRITES)
    assert "port 'from_state' reads {state} (blackboard key /state), which nothing writes" in (
        problem.message
    )


def test_subtree_keys_resolve_per_instance_and_run_keys_count() -> None:
    text = wrap(
        """    <Sequence name="s">
      <SubTree ID="Use" name="a" flag="{made}"/>
      <StubGrasp name="maker" force_n="1.0" holding="{made}"/>
      <SubTree ID="Use" name="b" flag="true"/>
      <SubTree ID="Own"/>
    </Sequence>""",
        extra=(
            '  <BehaviorTree ID="Use"><StubCheck name="c" value="{flag}"/></BehaviorTree>\n'
            '  <BehaviorTree ID="Own"><StubCheck name="o" value="{object}"/></BehaviorTree>\n'
        ),
    )
    # {flag} is the parent's {made} in one instance and a constant in the other; {object}
    # inside an unremapped subtree is that instance's own key, which nothing writes.
    assert [(line, m.split(",")[0]) for line, m in problems_of(text)] == [
        (11, "port 'value' reads {object} (blackboard key /<unnamed 1>/object)"),
    ]


@pytest.mark.parametrize(
    ("writer", "ok"),
    [
        ('<SetBlackboard output_key="held" value="true"/>', True),
        ('<SetBlackboard output_key="{held}" value="true"/>', True),
        ('<Script code="held := true; other = 2"/>', True),
        ('<StubCheck name="w" value="true" _post="held += 1"/>', True),
        ('<Script code="held == true"/>', False),
        ('<Script code="x := held &lt;= 3"/>', False),
    ],
)
def test_setblackboard_and_script_assignments_are_writes(writer: str, ok: bool) -> None:
    doc = read_tree_document_string(
        wrap(f'    <Sequence name="s">{writer}<StubCheck name="c" value="{{held}}"/></Sequence>')
    )
    assert (dataflow_problems(doc) == []) is ok


def _nested(depth: int) -> str:
    body = "".join(f'<Sequence name="n{i}">' for i in range(depth))
    return wrap(body + '<StubCheck name="leaf" value="true"/>' + "</Sequence>" * depth)


def test_deep_nesting_is_one_problem_not_a_recursion_error() -> None:
    assert validate_tree_string(_nested(MAX_TREE_DEPTH - 1), run_keys=RUN_WRITES) == []
    (problem,) = validate_tree_string(_nested(5000), run_keys=RUN_WRITES)
    assert problem.message == (
        f"nested 5001 levels deep; expected at most {MAX_TREE_DEPTH} (a deeper tree cannot be "
        "built, ticked or drawn)"
    )


def test_a_subtree_fan_out_is_refused_before_it_is_expanded() -> None:
    trees = "".join(
        f'<BehaviorTree ID="T{i}"><Sequence name="s"><SubTree ID="T{i + 1}" name="a"/>'
        f'<SubTree ID="T{i + 1}" name="b"/></Sequence></BehaviorTree>'
        for i in range(22)
    )
    text = (
        f'<root main_tree_to_execute="T0">{trees}<BehaviorTree ID="T22">'
        '<StubCheck name="leaf" value="true"/></BehaviorTree></root>'
    )
    (problem,) = validate_tree_string(text, run_keys=RUN_WRITES)
    assert problem.node == '<BehaviorTree ID="T0">'
    assert f"expands to more than {MAX_TREE_NODES} nodes through its subtrees" in problem.message
    # Expanded depth counts too: a chain of subtrees each two deep.
    chain = "".join(
        f'<BehaviorTree ID="C{i}"><Sequence name="s"><SubTree ID="C{i + 1}" name="x"/>'
        "</Sequence></BehaviorTree>"
        for i in range(MAX_TREE_DEPTH + 5)
    )
    text = (
        f'<root main_tree_to_execute="C0">{chain}<BehaviorTree ID="C{MAX_TREE_DEPTH + 5}">'
        '<StubCheck name="leaf" value="true"/></BehaviorTree></root>'
    )
    (problem,) = validate_tree_string(text, run_keys=RUN_WRITES)
    assert f"nested more than {MAX_TREE_DEPTH} levels deep once its subtrees" in problem.message


def test_a_cycle_of_unnamed_subtrees_is_found() -> None:
    text = wrap(
        '    <SubTree ID="A"/>',
        extra=(
            '  <BehaviorTree ID="A"><Sequence name="a"><SubTree ID="B"/></Sequence>'
            "</BehaviorTree>\n"
            '  <BehaviorTree ID="B"><SubTree ID="A"/></BehaviorTree>\n'
        ),
    )
    assert problems_of(text) == [(6, "subtree cycle A -> B -> A; a tree cannot contain itself")]
    with pytest.raises(TreeFileError, match="subtree cycle A -> B -> A"):
        load_tree_string(text, run_keys=RUN_WRITES)


def test_objects_are_checked_against_the_world_through_subtrees() -> None:
    xml = PICK_AND_PLACE_XML.read_text().replace(
        'name="first_object" object="{object}"', 'name="first_object" object="ghost"'
    )
    doc = read_tree_document_string(xml)
    (problem,) = check_tree_objects(doc, ["parcel"])
    assert problem.node == '<SubTree ID="PickAndPlace" name="first_object">'
    assert problem.message.startswith(
        "object 'ghost' (read by <SelectSkills name=\"select_skills\"> at line "
    )
    assert problem.message.endswith("expected one of the world's objects (parcel)")
    # {object} at the top level is the task's object, which the world file guarantees.
    assert check_tree_objects(read_tree_document(PICK_AND_PLACE_XML), ["box"]) == []


@pytest.mark.parametrize(
    ("leaf", "ports"),
    [
        (SelectSkills, {"object": "ghost", "plan": "{plan}"}),
        (IsHeld, {"object": "ghost"}),
    ],
)
def test_a_leaf_meeting_an_impossible_value_fails_with_feedback(
    leaf: type[py_trees.behaviour.Behaviour],
    ports: dict[str, object],
    library: SkillLibrary,
) -> None:
    world = FakeWorld()
    node = leaf("probe")
    wire(node, **ports)  # type: ignore[arg-type]
    node.setup(world=world, library=library, control_dt=1.0 / 60.0)
    log = tick_until(node, world, 1.0 / 60.0, max_ticks=5)
    assert log.final == Status.FAILURE
    assert "KeyError: 'ghost'" in str(log.feedback)


_VALUES = st.one_of(
    st.text(max_size=30),
    st.sampled_from(["{", "}", "{}", "{x}", "{{x}}", "nan", "1e400", "-5", "9" * 400, "@x"]),
)


@settings(max_examples=80, deadline=None)
@given(
    attr=st.sampled_from(["force_n", "holding", "timeout_s", "value", "name", "code", "_post"]),
    value=_VALUES,
    tag=st.sampled_from(["StubGrasp", "StubCheck", "Timeout", "Retry", "SubTree", "Sequence"]),
)
def test_fuzzed_tree_attributes_give_problems_never_exceptions(
    attr: str, value: str, tag: str
) -> None:
    """Whatever an attribute holds, validate returns problems (or none) and never raises."""
    node = f'<{tag} name="n" {attr}={quoteattr(value)}>'
    inner = '<StubCheck name="c" value="true"/>' if tag not in ("StubGrasp", "StubCheck") else ""
    if tag == "SubTree":
        node, inner = f'<SubTree ID="Sub" {attr}={quoteattr(value)}>', ""
    text = wrap(
        f'    <Sequence name="s">{node}{inner}</{tag}></Sequence>',
        extra='  <BehaviorTree ID="Sub"><StubCheck name="x" value="{v}"/></BehaviorTree>\n',
    )
    problems = validate_tree_string(text, run_keys=RUN_WRITES)
    assert all(p.message for p in problems)
    if not problems:  # what validates also loads
        load_tree_string(text, run_keys=RUN_WRITES)


def test_validate_tree_on_the_shipped_trees_is_clean() -> None:
    assert validate_tree(PICK_AND_PLACE_XML) == []
