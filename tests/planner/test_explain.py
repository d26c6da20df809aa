"""A failed run always says where and why: the node that started the failure, named."""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from planner.loader import load_tree_string
from planner.runner import explain, readable, run_tree, status_chain
from planner.testing import FakeWorld
from skills.library import SkillLibrary
from tests.planner.stub_leaves import FakeClock, StubCheck, StubCounter  # noqa: F401 (registers)


def run(body: str, dt: float = 0.1, ticks: int = 100) -> py_trees.behaviour.Behaviour:
    """Tick the tree ``body`` (a main tree's content) on a simulated clock until it ends."""
    root = load_tree_string(
        f'<root BTCPP_format="4" main_tree_to_execute="T"><BehaviorTree ID="T">{body}'
        "</BehaviorTree></root>"
    )
    clock = FakeClock(dt=dt)
    tree = py_trees.trees.BehaviourTree(root)
    tree.setup(clock=clock)
    for _ in range(ticks):
        tree.tick()
        if root.status in (Status.SUCCESS, Status.FAILURE):
            break
        clock.advance()
    return root


def test_a_timeout_that_halts_its_child_is_the_reason_with_what_the_child_said() -> None:
    root = run(
        '<Sequence name="s"><Timeout name="guard" msec="500">'
        '<StubCounter name="count" ticks="1000"/></Timeout></Sequence>'
    )
    assert root.status == Status.FAILURE
    assert [n.name for n in status_chain(root)] == ["s", "s.guard"]
    assert explain(root) == (
        "s.guard: timed out after 0.500 s (allowed 0.500 s); halted 's.guard.count' "
        "while count said: tick 6"  # ticks at t = 0, 0.1 ... 0.5
    )


def test_a_leaf_that_fails_silently_is_still_named() -> None:
    root = run(
        '<Sequence name="s"><StubCounter name="first" ticks="1"/>'
        '<StubCheck name="check" value="false"/></Sequence>'
    )
    assert root.status == Status.FAILURE
    assert explain(root) == "s.check: failure without a feedback message"


def test_a_silent_leaf_under_a_retry_gives_the_retrys_count() -> None:
    root = run(
        '<RetryUntilSuccessful name="again" num_attempts="2">'
        '<StubCheck name="check" value="false"/></RetryUntilSuccessful>'
    )
    assert root.status == Status.FAILURE
    assert explain(root) == (
        "again.check: failure without a feedback message "
        "(under again: final failure [status: 2 failure from 2])"
    )


def test_an_earlier_failure_that_was_recovered_is_not_blamed() -> None:
    # The fallback's first branch fails with a message and its second succeeds; the sequence
    # then fails later, at the timeout: that is the reason, not the recovered branch.
    root = run(
        '<Sequence name="s"><Fallback name="choose">'
        '<Timeout name="quick" msec="200"><StubCounter name="slow" ticks="50"/></Timeout>'
        '<StubCounter name="fine" ticks="1"/></Fallback>'
        '<Timeout name="late" msec="300"><StubCounter name="stuck" ticks="50"/></Timeout>'
        "</Sequence>"
    )
    assert root.status == Status.FAILURE
    assert explain(root).startswith("s.late: timed out after 0.300 s")


def test_a_running_tree_is_explained_by_its_tip() -> None:
    root = run('<Sequence name="s"><StubCounter name="count" ticks="1000"/></Sequence>', ticks=3)
    assert root.status == Status.RUNNING
    assert explain(root) == "s.count: tick 3"


def test_a_skipped_branch_is_not_the_reason_the_branch_that_ran_is() -> None:
    # BT.CPP's SKIPPED reads as FAILURE to a Fallback: the skipped last branch decided nothing.
    root = run(
        '<Fallback name="choose"><StubCheck name="check" value="false"/>'
        '<Sequence name="second" _skipIf="true"><StubCounter name="c" ticks="1"/></Sequence>'
        "</Fallback>"
    )
    assert root.status == Status.FAILURE
    assert [n.name for n in status_chain(root)] == ["choose", "choose.check"]


def test_a_branch_skipped_once_and_run_later_is_a_reason_again() -> None:
    root = run(
        '<Sequence name="s"><Fallback name="first">'
        '<Sequence name="a" _skipIf="true"><StubCheck name="c1" value="false"/></Sequence>'
        '<StubCounter name="ok" ticks="1"/></Fallback>'
        '<Script name="w" code="go := true"/>'
        '<Fallback name="second"><Sequence name="b" _skipIf="go != true">'
        '<StubCheck name="c2" value="false"/></Sequence></Fallback></Sequence>'
    )
    assert root.status == Status.FAILURE
    assert [n.name for n in status_chain(root)][-1] == "s.second.b.c2"


def test_nodes_the_file_leaves_unnamed_read_as_their_type() -> None:
    # py_trees names an unnamed node <Type>_<uuid4> and an unnamed composite by a bare uuid4;
    # the reason reads as BehaviorTree.CPP names them: by type, with no uuid in it.
    root = run(
        '<Sequence><StubCounter ticks="1"/><Timeout msec="300">'
        '<StubCounter ticks="50"/></Timeout></Sequence>'
    )
    assert root.status == Status.FAILURE
    # The names themselves keep their uuids (they must be unique); what is shown does not.
    assert root.name != "Sequence" and readable(root.name) == "Sequence"
    reason = explain(root)
    assert reason.startswith("Timeout: timed out after 0.300 s"), reason
    assert "halted 'StubCounter' while StubCounter said" in reason, reason


def test_readable_takes_out_only_py_trees_uuids() -> None:
    uid = "c61cbfdd-e6e3-459e-8d3f-6d43d02bb0fd"
    assert readable(f"{uid}.Transport_{uid}: no data") == "Transport: no data"
    assert readable("task.move_6.transport: ok") == "task.move_6.transport: ok"
    assert readable(f"named {uid} in the text") == f"named {uid} in the text"


def test_a_port_with_nothing_on_it_names_the_nodes_that_write_its_key(
    fake_world: FakeWorld, library: SkillLibrary
) -> None:
    # A carry before the grasp that writes its state: the reason says who writes {state}.
    body = (
        '<Sequence name="s"><SelectSkills object="{object}" plan="{plan}"/>'
        '<Transport name="carry" object="{object}" move="0" plan="{plan}" '
        'from_state="{state}" to_state="{state}"/>'
        '<Grasp object="{object}" plan="{plan}" state="{state}"/></Sequence>'
    )
    root = load_tree_string(
        f'<root BTCPP_format="4" main_tree_to_execute="T"><BehaviorTree ID="T">{body}'
        "</BehaviorTree></root>"
    )
    result = run_tree(root, fake_world, library, 1 / 60, 5.0, {"/object": "parcel"})
    assert result.status == Status.FAILURE
    assert result.reason == (
        "s.carry: cannot initialise: NoDataAvailable: s.carry: Input port 'from_state' "
        "(mapped to '/state') has no data available; written by Transport.to_state, "
        "Grasp.state in this tree, none of which has yet"
    )


def test_progress_names_the_running_leaf_that_says_what_it_does_beside_a_watch() -> None:
    # py_trees' tip follows a parallel's last running child: a carry beside a watch had been
    # shown as the watch's KeepRunningUntilFailure, saying nothing.
    from planner.runner import progress_node, working_leaf

    root = load_tree_string(
        '<root BTCPP_format="4" main_tree_to_execute="T"><BehaviorTree ID="T">'
        '<Parallel name="p" success_count="1" failure_count="1">'
        '<StubCounter name="carry" ticks="10"/>'
        '<KeepRunningUntilFailure name="watch"><StubCheck name="held" value="true"/>'
        "</KeepRunningUntilFailure></Parallel></BehaviorTree></root>"
    )
    tree = py_trees.trees.BehaviourTree(root)
    tree.setup(clock=FakeClock())
    tree.tick()
    assert tree.tip() is not None and tree.tip().name.endswith("watch")
    leaf = progress_node(tree)
    assert leaf is not None and leaf.name == "p.carry" and leaf.feedback_message == "tick 1"
    assert working_leaf(root) is leaf
    root.stop(Status.INVALID)
    assert working_leaf(root) is None


def test_progress_names_a_timeout_that_just_failed_with_what_it_said() -> None:
    from planner.runner import progress_node

    root = load_tree_string(
        '<root BTCPP_format="4" main_tree_to_execute="T"><BehaviorTree ID="T">'
        '<Timeout name="guard" msec="150"><StubCounter name="count" ticks="100"/></Timeout>'
        "</BehaviorTree></root>"
    )
    tree = py_trees.trees.BehaviourTree(root)
    clock = FakeClock(dt=0.1)
    tree.setup(clock=clock)
    for _ in range(3):
        tree.tick()
        clock.advance()
    node = progress_node(tree)
    assert node is not None and node.name == "guard" and "timed out" in node.feedback_message
