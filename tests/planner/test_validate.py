"""validate_tree: every problem with file, line and node, without building the tree."""

from __future__ import annotations

from pathlib import Path

import pytest

import tests.planner.stub_leaves  # noqa: F401  (registers the stub leaves)
from planner.tree_dataflow import RUN_WRITES
from planner.validate import TreeProblem, tree_cli_validate, validate_tree, validate_tree_string

TREES = Path(__file__).resolve().parents[1] / "data" / "trees"


def problems_of(text: str) -> list[tuple[int | None, str]]:
    problems = validate_tree_string(text, source="t.xml", run_keys=RUN_WRITES)
    return [(p.line, p.message) for p in problems]


def wrap(body: str, extra: str = "") -> str:
    return (
        '<root BTCPP_format="4" main_tree_to_execute="Main">\n'
        f'  <BehaviorTree ID="Main">\n{body}\n  </BehaviorTree>\n{extra}</root>\n'
    )


@pytest.mark.parametrize(
    "name", ["good_btcpp.xml", "good_pytrees.xml", "retry_timeout.xml", "include_main.xml"]
)
def test_good_trees_have_no_problems(name: str) -> None:
    assert validate_tree(TREES / name) == []


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("bad_unknown_tag.xml", [(5, '<StubGrsp name="typo">', "did you mean 'StubGrasp'")]),
        ("bad_missing_port.xml", [(4, '<StubCounter name="count">', "missing required input")]),
        ("bad_unknown_port.xml", [(4, '<StubGrasp name="grip">', "unknown port 'forse'")]),
        (
            "bad_port_type.xml",
            [
                (4, '<StubGrasp name="grip">', "cannot convert 'strong' to float"),
                (5, '<StubCheck name="check">', "cannot convert 'maybe' to bool"),
                (6, '<StubCounter name="count">', "cannot convert '2.5' to int"),
            ],
        ),
        (
            "bad_unknown_subtree.xml",
            [
                (7, '<SubTree ID="Grap" name="g1">', "unknown subtree 'Grap'"),
                (8, '<SubTree ID="Grip" name="g2">', "unknown port 'forse' of subtree 'Grip'"),
                (
                    3,
                    '<StubGrasp name="grip">',
                    "reads {force} (blackboard key /g2/force), which nothing writes",
                ),
            ],
        ),
        ("bad_syntax.xml", [(5, "", "XML syntax error: mismatched tag")]),
        (
            "bad_decorator.xml",
            [
                (8, '<Timeout name="none">', "missing required attribute 'msec'"),
                (4, '<Inverter name="two">', "exactly 1 child, found 2"),
                (8, '<Timeout name="none">', "exactly 1 child, found 0"),
            ],
        ),
        ("bad_main.xml", [(1, "<root>", "main tree 'Mian' not found")]),
    ],
)
def test_bad_trees(name: str, expected: list[tuple[int, str, str]]) -> None:
    problems = validate_tree(TREES / name, run_keys=RUN_WRITES)
    assert [(p.line, p.node) for p in problems] == [(line, node) for line, node, _ in expected]
    for problem, (_, _, text) in zip(problems, expected, strict=True):
        assert text in problem.message
        assert problem.file == str(TREES / name)


def test_syntax_error_has_a_column_and_formats_file_line_col() -> None:
    (problem,) = validate_tree(TREES / "bad_syntax.xml")
    assert problem.column == 7
    assert str(problem) == f"{TREES / 'bad_syntax.xml'}:5:7: XML syntax error: mismatched tag"


def test_problem_format() -> None:
    problem = TreeProblem("trees/x.xml", 12, '<Grasp name="grip">', "unknown port 'forse'")
    assert str(problem) == "trees/x.xml:12: <Grasp name=\"grip\">: unknown port 'forse'"
    assert str(TreeProblem("x.xml", None, "", "cannot read")) == "x.xml: cannot read"


def test_line_is_the_start_tag_even_when_attributes_span_lines() -> None:
    problems = validate_tree(TREES / "include_bad.xml")
    assert [(Path(p.file).name, p.line) for p in problems] == [("include_bad_grip.xml", 4)]


def test_ports_literals_keys_and_children() -> None:
    text = wrap(
        """    <Sequence name="s" memory="sometimes" colour="red">
      <StubGrasp name="a" force_n="{force" holding="true"/>
      <StubAt name="b" position="0.1; 0.2; x"/>
      <StubAt name="c" position="{pos}"><StubCheck name="d" value="1"/></StubAt>
      <StubCheck name="e.f" value="off"/>
    </Sequence>"""
    )
    assert problems_of(text) == [
        (3, "attribute 'memory': expected true or false, got 'sometimes'"),
        (3, "unknown attribute 'colour'; expected one of memory, name"),
        (4, "port 'force_n': malformed blackboard key '{force'; expected {name} or a literal"),
        (4, "output port 'holding': expected a blackboard key such as {holding}, got the "
            "literal 'true'"),
        (5, "port 'position': cannot convert '0.1; 0.2; x' to list[float]"),
        (6, "a leaf takes no children, found 1"),
        (7, "name 'e.f': expected no '.' (py_trees joins parent names with '.')"),
        (6, "port 'position' reads {pos} (blackboard key /pos), which nothing writes: expected "
            "a node's output port, a SetBlackboard or a script to write it, or a key the run "
            "sets before the first tick ({object} at the top level)"),
    ]  # fmt: skip


def test_decorator_and_parallel_attributes() -> None:
    text = wrap(
        """    <Parallel name="p" success_count="2" failure_count="2">
      <RetryUntilSuccessful name="r" num_attempts="many"><StubCheck name="a" value="1"/>
      </RetryUntilSuccessful>
      <Timeout name="t" msec="soon"><StubCheck name="b" value="1"/></Timeout>
      <Retry name="r2"><StubCheck name="c" value="1"/></Retry>
      <Repeat name="rep" num_cycles="2" speed="3"><StubCheck name="d" value="1"/></Repeat>
    </Parallel>"""
    )
    got = problems_of(text)
    assert got == [
        (
            6,
            "attribute 'msec': expected a whole number of milliseconds from 1 to 86400000, "
            "got 'soon'",
        ),
        (4, "attribute 'num_attempts': cannot convert 'many' to int"),
        (7, "missing required attribute 'num_attempts'"),
        (8, "unknown attribute 'speed'; expected one of num_cycles"),
    ]  # fmt: skip


def test_duplicate_names_and_subtree_cycles() -> None:
    text = wrap(
        """    <Sequence name="s">
      <StubCheck name="same" value="1"/>
      <StubCheck name="same" value="0"/>
      <SubTree ID="Loop" name="l1"/>
      <SubTree ID="Leaf" name="twice"/>
      <SubTree ID="Leaf" name="twice"/>
    </Sequence>""",
        extra=(
            '  <BehaviorTree ID="Loop"><SubTree ID="Loop2" name="x"/></BehaviorTree>\n'
            '  <BehaviorTree ID="Loop2"><SubTree ID="Loop" name="y"/></BehaviorTree>\n'
            '  <BehaviorTree ID="Leaf"><StubCheck name="leaf" value="1"/></BehaviorTree>\n'
        ),
    )
    assert problems_of(text) == [
        (5, "duplicate node name 's.same' (also at line 4); py_trees needs unique names: rename "
            "one or name its parent"),
        (8, "duplicate node name 's.twice.leaf' (also at line 13); py_trees needs unique names: "
            "rename one or name its parent"),
        (12, "subtree cycle Loop -> Loop2 -> Loop; a tree cannot contain itself"),
    ]  # fmt: skip


def test_btcpp_condition_and_autoremap_attributes_are_checked() -> None:
    text = wrap(
        """    <Sequence name="s" _skipIf="x == (1">
      <SubTree ID="Sub" name="sub" _autoremap="maybe"/>
    </Sequence>""",
        extra='  <BehaviorTree ID="Sub"><StubCheck name="c" value="{v}"/></BehaviorTree>\n',
    )
    messages = [m for _, m in problems_of(text)]
    assert any(
        m.startswith("attribute '_skipIf': column 8 in the script: expected ')'") for m in messages
    )
    assert "attribute '_autoremap': expected true or false (or 1 or 0)" in messages


def test_structure_problems() -> None:
    text = (
        '<root main_tree_to_execute="Main">\n'
        '  <BehaviorTree ID="Main"/>\n'
        '  <BehaviorTree ID="Main"><StubCheck name="c" value="1"/></BehaviorTree>\n'
        "  <Sequence/>\n"
        "</root>\n"
    )
    assert problems_of(text) == [
        (2, "expected exactly one child (the tree's root node), found 0"),
        (3, "duplicate BehaviorTree ID 'Main' (first at line 2)"),
        (4, "unexpected element under <root>; expected <BehaviorTree ID=...>"),
    ]
    assert problems_of("<tree/>")[0] == (1, "expected <root> as the document element")


def test_cli_prints_problems_to_stderr_and_returns_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert tree_cli_validate(TREES / "bad_port_type.xml") == 2
    out, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert out == ""
    assert len(lines) == 4
    assert lines[0].startswith(f'{TREES / "bad_port_type.xml"}:4: <StubGrasp name="grip">')
    assert lines[-1].endswith("bad_port_type.xml: 3 problems")


def test_cli_ok_summary(capsys: pytest.CaptureFixture[str]) -> None:
    assert tree_cli_validate(TREES / "retry_timeout.xml") == 0
    out, err = capsys.readouterr()
    assert err == ""
    assert out.strip().endswith("ok (main tree 'Main', 2 trees, 12 nodes)")


def test_literals_passed_into_a_subtree_are_checked_against_the_leaf_port() -> None:
    text = wrap(
        """    <SubTree ID="Grip" name="g" force="strong"/>""",
        extra=(
            '  <BehaviorTree ID="Grip">\n'
            '    <StubGrasp name="squeeze" force_n="{force}"/>\n'
            "  </BehaviorTree>\n"
        ),
    )
    assert problems_of(text) == [
        (3, "port 'force' feeds <StubGrasp name=\"squeeze\"> port 'force_n' (line 6): cannot "
            "convert 'strong' to float"),
    ]  # fmt: skip


def test_values_that_would_crash_a_run_are_refused_at_validate(tmp_path: Path) -> None:
    tree = tmp_path / "crashers.xml"
    tree.write_text(
        '<root BTCPP_format="4" main_tree_to_execute="Main"><BehaviorTree ID="Main"><Sequence>'
        '<Approach name="a" object="parcel" standoff_m="nan"/>'
        '<Retreat name="r" segment_s="0"/>'
        '<Timeout msec="-5"><Retreat name="r2"/></Timeout>'
        f'<Timeout msec="{"9" * 400}"><Retreat name="r3"/></Timeout>'
        "</Sequence></BehaviorTree></root>",
        encoding="utf-8",
    )
    import planner.leaves  # noqa: F401  (the shipped leaves this tree uses)

    messages = [p.message for p in validate_tree(tree)]
    assert "port 'standoff_m': expected a finite float within 1e+06, got 'nan'" in messages
    assert "port 'segment_s': expected a duration greater than 0 s, got '0'" in messages
    assert sum("attribute 'msec': expected a whole number" in m for m in messages) == 2


def test_decorator_problems_name_the_attributes_as_bt_cpp_spells_them() -> None:
    # The reader renames them for py_trees (num_attempts -> num_failures, num_cycles ->
    # num_success, msec -> duration); the problems had named py_trees' spellings.
    body = """    <Sequence name="s">
      <RetryUntilSuccessful name="r" num_attemps="3"><AlwaysSuccess/></RetryUntilSuccessful>
      <Repeat name="p" num_cycle="2"><AlwaysSuccess/></Repeat>
      <Timeout name="t" msecs="100"><AlwaysSuccess/></Timeout>
      <RetryUntilSuccessful name="q" num_attempts="abc"><AlwaysSuccess/></RetryUntilSuccessful>
    </Sequence>"""
    messages = [m for _, m in problems_of(wrap(body))]
    assert "missing required attribute 'num_attempts'" in messages
    assert "unknown attribute 'num_attemps'; expected one of num_attempts" in messages
    assert "missing required attribute 'num_cycles'" in messages
    assert "unknown attribute 'num_cycle'; expected one of num_cycles" in messages
    assert "unknown port 'msecs'; expected one of msec" in messages
    assert "attribute 'num_attempts': cannot convert 'abc' to int" in messages
    assert not [m for m in messages if "num_failures" in m or "num_success" in m]
