"""The runner ends a tree that cannot finish: on simulated time, and on wall-clock time."""

from __future__ import annotations

import py_trees
from py_trees.common import Status

from planner.runner import run_tree
from planner.testing import FakeWorld


class Forever(py_trees.behaviour.Behaviour):
    """A leaf that never finishes."""

    def update(self) -> Status:
        self.feedback_message = "still going"
        return Status.RUNNING


def test_a_tree_that_never_ends_is_stopped_by_the_wall_clock_guard(
    fake_world: FakeWorld,
) -> None:
    result = run_tree(Forever("forever"), fake_world, None, 1 / 60, 1e9, max_wall_time=0.05)  # type: ignore[arg-type]
    assert result.status == Status.INVALID
    assert result.reason.startswith("wall-clock limit 0.05 s reached; forever: still going")


def test_the_simulated_time_limit_names_what_was_running(fake_world: FakeWorld) -> None:
    result = run_tree(Forever("forever"), fake_world, None, 1 / 60, 0.5)  # type: ignore[arg-type]
    assert result.status == Status.INVALID
    assert result.reason == "time limit 0.5 s reached; forever: still going"
